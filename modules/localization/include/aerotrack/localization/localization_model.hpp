// Localization models: from the person's torso length L_t (neck to mid-hip, pixels) and the
// horizontal image position u_t of the torso centre (pixels) to the person's position p_C in the
// camera frame C (x forward along the optical axis, y left, z up; metres), the paper's Sect. IV-B.
// Two models share one interface:
//  - kPaper, the paper's Eq. (1): x = l1 e^(k1 L) + l2 e^(k2 L), y = (l3 e^(k3 u) + l4 e^(k4 u))(a x + b).
//    The paper's a is redundant with the scale of (l3, l4) (multiply l3, l4 by s and a, b by 1/s:
//    the same y), so we fix a = 1 and fit b; the exponentials are ordered k1 <= k2, k3 <= k4.
//  - kPinhole, physically grounded: a vertical torso of length H at depth x projects to
//    L = fy H / x, so x = fy H / L + x_offset + x_inv_sq / L^2 (H, the offset and the 1/L^2 term
//    are fitted: they absorb the person's real torso, lean and keypoint bias); y follows the ray
//    through u, y = -x (u - cx) / fx (1 + y_scale_correction) + y_offset (y is left, u grows right).
// In both, z is a constant (the paper's assumption 1: the person walks on a plane): the mean of
// the samples' z_m where the data has it, else 0.
// Fitting is robust non-linear least squares (Ceres, Cauchy loss, autodiff Jacobians) started from
// a closed-form initialisation: for fixed exponents the paper's model is linear in its
// coefficients, so a grid of exponent pairs is solved by linear least squares and the best few
// are refined (multi-start); the pinhole model is linear in its parameters and starts from the
// linear least-squares solution.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"

namespace aerotrack::localization {

/// One calibration sample: image features and the ground-truth position in the camera frame C.
struct LocalizationSample {
  double torso_px = 0.0;  ///< Neck to mid-hip length in the image, pixels; > 0.
  double u_px = 0.0;      ///< Horizontal image coordinate of the torso centre, pixels (right positive).
  double x_m = 0.0;       ///< Forward distance in C, metres.
  double y_m = 0.0;       ///< Left offset in C, metres (a person right of the image centre: y < 0).
  double z_m = std::numeric_limits<double>::quiet_NaN();  ///< Up in C, metres; NaN: not in the data.
};

enum class LocalizationModel : std::uint8_t { kPaper, kPinhole };

/// "paper" or "pinhole".
std::string_view toString(LocalizationModel model);
/// "paper" / "pinhole" to the model; anything else is an error naming the text.
rt::Expected<LocalizationModel> parseLocalizationModel(std::string_view text);

/// The paper's Eq. (1) with a = 1:
///   x_m = l1_m e^(k1_per_px L) + l2_m e^(k2_per_px L)
///   y_m = (l3 e^(k3_per_px u) + l4 e^(k4_per_px u)) (x_m + b_m)
struct PaperModelParams {
  double l1_m = 0.0, k1_per_px = 0.0;
  double l2_m = 0.0, k2_per_px = 0.0;
  double l3 = 0.0, k3_per_px = 0.0;  ///< l3, l4 dimensionless (y / (x + b)).
  double l4 = 0.0, k4_per_px = 0.0;
  double b_m = 0.0;
};

/// The pinhole model:
///   x_m = fy_px torso_m / L + x_offset_m + x_inv_sq_m_px2 / L^2
///   y_m = -x_m (u - cx_px) / fx_px (1 + y_scale_correction) + y_offset_m
struct PinholeModelParams {
  double fx_px = 0.0, fy_px = 0.0, cx_px = 0.0;  ///< Intrinsics of the camera the data came from.
  double torso_m = 0.0;                          ///< Effective torso length (neck to mid-hip).
  double x_offset_m = 0.0;
  double x_inv_sq_m_px2 = 0.0;
  double y_scale_correction = 0.0;
  double y_offset_m = 0.0;
};

/// A fitted model. Only the member of `model` is meaningful.
struct LocalizationParams {
  LocalizationModel model = LocalizationModel::kPaper;
  PaperModelParams paper;
  PinholeModelParams pinhole;
  double z_m = 0.0;               ///< Constant height of the person's reference point in C, metres.
  std::size_t fit_samples = 0;    ///< Samples the fit used (informative).
  double fit_mean_error_m = 0.0;  ///< Mean horizontal error on those samples (informative).
  /// A single frame's noise, measured on the fit's residuals (issue 22 item 3): the standard deviation of one
  /// horizontal axis at forward distance x is noise_std_m + noise_std_per_m x. The estimator weighs each
  /// measurement with it. Both 0: not measured (a file written before the keys existed; optional keys), and the
  /// estimation section's measurement_std_per_m applies.
  double noise_std_m = 0.0;
  double noise_std_per_m = 0.0;
};

/// The noise model of fit(): the residuals sorted by distance into up to eight bins of equal count (at
/// least 50 samples each; one bin for fewer than 100), each bin's standard deviation taken robustly as
/// median(|r|) / 1.1774 (the median of the length of a 2-D isotropic Gaussian error, per axis), and a
/// least-squares line a + b x through the bins, with a, b >= 0. Writes noise_std_m and noise_std_per_m of
/// params (whose model predicts). Pure; allocates O(samples).
void fitNoise(LocalizationParams& params, std::span<const LocalizationSample> samples);

struct FitOptions {
  /// Scale of the Cauchy loss on each residual (metres): residuals well beyond it (gross
  /// outliers, e.g. a mismatched detection) lose their pull; > 0. Default 0.3 m, about twice
  /// the localization noise at 8 m.
  double robust_loss_scale_m = 0.3;
  int max_iterations = 200;  ///< Per Ceres solve; >= 1.
  /// Paper model: the best this-many grid starts are refined with Ceres; >= 1.
  int paper_starts = 4;
};

/// Fits `model` to the samples. intrinsics supplies fx, fy, cx (the pinhole model stores them;
/// the paper model uses them only to scale its internal variables). Errors: too few samples
/// (paper 12, pinhole 6), a non-finite or non-positive torso, non-finite values, non-positive
/// focal lengths, or no start converging (the message says why Ceres stopped).
/// Thread safety: reentrant. Allocates (Ceres problems, O(samples)).
rt::Expected<LocalizationParams> fit(LocalizationModel model, std::span<const LocalizationSample> samples,
                                     const hal::CameraIntrinsics& intrinsics, const FitOptions& options = {});

/// p_C (x forward, y left, z up; metres) of a person with torso length torso_px (> 0) whose torso
/// centre is at u_px. Pure, allocation-free, reentrant. A non-positive torso gives NaN.
Eigen::Vector3d predict(const LocalizationParams& params, double torso_px, double u_px);

/// The same model's p_C for a person at forward distance x_m (known from elsewhere) seen at u_px: the
/// bearing half of the regression, for a torso too cut off for a distance (issue 22). predict(L, u)
/// equals predictAtDistance(predict(L, u).x(), u).
Eigen::Vector3d predictAtDistance(const LocalizationParams& params, double x_m, double u_px);

/// The parameter file's keys (localization_io.hpp): model, z_m, fit_samples, fit_mean_error_m and the
/// model's section (`paper:` or `pinhole:`, the other one is an unknown key), all required. The one list
/// of keys and ranges that reading, validate() and writing share (rt/field_table.hpp): every value
/// finite, the pinhole focal lengths > 0, fit_mean_error_m >= 0.
const rt::FieldTable<LocalizationParams>& localizationFields();
const rt::FieldTable<PaperModelParams>& paperModelFields();
const rt::FieldTable<PinholeModelParams>& pinholeModelFields();

/// Checks the values against localizationFields() (the active model's section only). Error names the key
/// path ("pinhole.fx_px must be in (0, inf), got 0").
rt::Status validate(const LocalizationParams& params);

/// validate(), then what the parameters predict: finite and within 10 km for every torso of 10-1000
/// px at u of 0-1280 px. An exponent of 1000 per pixel is a finite number that evaluates to
/// infinity: without this a person would silently never be estimated. Reading, writing and fitting
/// a parameter file check it.
rt::Status validatePredictions(const LocalizationParams& params);

/// The range of a plausible calibration sample (the input policy): torso_px in (0, 10000], u_px in
/// [-10000, 10000], x_m in (0, 1000], y_m and z_m (when given) in [-1000, 1000]. "" or the reason,
/// naming the column ("x_m: must be in (0, 1000], got 1e+308").
std::string implausibleSample(const LocalizationSample& sample);

}  // namespace aerotrack::localization
