// Fitting and evaluating the localization models of the paper's Sect. IV-B, Eq. (1), and the
// pinhole model (see localization_model.hpp). Ceres stays in this file.
//
// Conditioning: the optimiser works on normalised variables, L_n = L / L_ref (L_ref the median
// torso) and u_n = (u - cx) / fx, so that exponents and coefficients are O(1); the paper's
// parameters are recovered exactly: k = k_n / L_ref, and for y, l e^(k u) = l_n e^(k_n u_n) with
// k = k_n / fx and l = l_n e^(-k_n cx / fx).
#include "aerotrack/localization/localization_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Dense>

namespace aerotrack::localization {
namespace {

constexpr std::size_t kMinPaperSamples = 12;
constexpr std::size_t kMinPinholeSamples = 6;

/// Exponent grids (normalised) for the multi-start of the paper model.
constexpr std::array<double, 14> kXExponentGrid = {-8.0, -6.0, -4.0, -3.0, -2.0, -1.5, -1.0,
                                                   -0.7, -0.4, -0.2, 0.0,  0.2,  0.5,  1.0};
constexpr std::array<double, 10> kYExponentGrid = {-6.0, -4.0, -2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 4.0};

// ---- residuals (autodiff) ----

/// Smallest gap between the two normalised exponents of a pair. When the data is explained by
/// (c0 + c1 s) e^(k s) -- e.g. y linear in u, as pinhole geometry gives -- the least-squares
/// optimum of a sum of two exponentials lies at infinity (k2 -> k1, l1 = -l2 -> inf) and the
/// solver would creep along a flat valley without converging. Fitting the gap d = k2n - k1n >= this
/// bound keeps the problem well posed; an active bound changes the predictions negligibly (the
/// two exponentials differ by e^(0.2 s), |s| < 1: the curvature left is under 0.1%).
constexpr double kMinExponentGap = 0.2;

/// x_n model: l1 e^(k1n Ln) + l2 e^((k1n + d) Ln) - x. p = {l1, k1n, l2, d}.
struct PaperXResidual {
  double torso_n, x_m;
  template <class T>
  bool operator()(const T* p, T* r) const {
    r[0] = p[0] * ceres::exp(p[1] * torso_n) + p[2] * ceres::exp((p[1] + p[3]) * torso_n) - x_m;
    return true;
  }
};

/// y model: (l3n e^(k3n un) + l4n e^((k3n + d) un)) (xhat + b) - y. p = {l3n, k3n, l4n, d, b}.
struct PaperYResidual {
  double u_n, x_hat_m, y_m;
  template <class T>
  bool operator()(const T* p, T* r) const {
    r[0] = (p[0] * ceres::exp(p[1] * u_n) + p[2] * ceres::exp((p[1] + p[3]) * u_n)) * (x_hat_m + p[4]) - y_m;
    return true;
  }
};

/// Pinhole x: torso_m (fy / L) + offset + c_n (L_ref / L)^2 - x. p = {torso_m, offset, c_n}.
struct PinholeXResidual {
  double fy_over_torso, ref_over_torso_sq, x_m;
  template <class T>
  bool operator()(const T* p, T* r) const {
    r[0] = p[0] * fy_over_torso + p[1] + p[2] * ref_over_torso_sq - x_m;
    return true;
  }
};

/// Pinhole y: -xhat tan (1 + d) + e - y, tan = (u - cx) / fx. p = {d, e}.
struct PinholeYResidual {
  double tan_u, x_hat_m, y_m;
  template <class T>
  bool operator()(const T* p, T* r) const {
    r[0] = -x_hat_m * tan_u * (1.0 + p[0]) + p[1] - y_m;
    return true;
  }
};

/// Solves a residual block problem over `params` (size N) with the Cauchy loss; params[gap_index]
/// (if >= 0) is bounded below by kMinExponentGap. Returns the final cost, or an error saying why
/// Ceres stopped.
template <int N, class Residual>
rt::Expected<double> solveRobust(const std::vector<Residual>& residuals, std::array<double, N>& params,
                                 const FitOptions& options, int gap_index = -1) {
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::CauchyLoss loss(options.robust_loss_scale_m);
  for (const Residual& residual : residuals) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Residual, 1, N>(new Residual(residual)), &loss,
                             params.data());
  }
  if (gap_index >= 0) problem.SetParameterLowerBound(params.data(), gap_index, kMinExponentGap);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-10;
  solver_options.gradient_tolerance = 1e-16;
  solver_options.parameter_tolerance = 1e-14;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  if (summary.termination_type != ceres::CONVERGENCE) {
    return rt::Error{"Ceres: " + summary.message};
  }
  for (const double p : params) {
    if (!std::isfinite(p)) return rt::Error{"Ceres converged to a non-finite parameter"};
  }
  return summary.final_cost;
}

double median(std::vector<double> values) {
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  return values[mid];
}

rt::Status checkSamples(std::span<const LocalizationSample> samples, std::size_t min_samples) {
  if (samples.size() < min_samples) {
    return rt::Error{"need at least " + std::to_string(min_samples) + " samples, got " +
                     std::to_string(samples.size())};
  }
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const LocalizationSample& s = samples[i];
    if (!std::isfinite(s.torso_px) || !std::isfinite(s.u_px) || !std::isfinite(s.x_m) || !std::isfinite(s.y_m)) {
      return rt::Error{"sample " + std::to_string(i) + " has a non-finite value"};
    }
    if (!(s.torso_px > 0.0)) return rt::Error{"sample " + std::to_string(i) + " has torso_px <= 0"};
    if (const std::string why = implausibleSample(s); !why.empty())
      return rt::Error{"sample " + std::to_string(i) + ": " + why};
  }
  // Rows that do not vary fit any curve through one point with no error (500 identical rows fitted
  // to 0.000 m): the regression needs views at several distances.
  std::vector<double> torsos;
  torsos.reserve(samples.size());
  for (const LocalizationSample& s : samples) torsos.push_back(s.torso_px);
  std::sort(torsos.begin(), torsos.end());
  const auto distinct = static_cast<std::size_t>(std::unique(torsos.begin(), torsos.end()) - torsos.begin());
  constexpr std::size_t kMinDistinctTorsos = 5;
  if (distinct < kMinDistinctTorsos)
    return rt::Error{"the samples do not vary: " + std::to_string(distinct) +
                     " distinct torso length(s), need at least " + std::to_string(kMinDistinctTorsos) +
                     " (views at several distances)"};
  return rt::ok();
}

/// Least-squares solution of A c = b and its sum of squared residuals; nothing if rank-deficient.
std::pair<Eigen::VectorXd, double> linearLeastSquares(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < A.cols()) return {Eigen::VectorXd(), std::numeric_limits<double>::infinity()};
  Eigen::VectorXd c = qr.solve(b);
  const double sse = (A * c - b).squaredNorm();
  if (!c.allFinite() || !std::isfinite(sse)) return {Eigen::VectorXd(), std::numeric_limits<double>::infinity()};
  return {std::move(c), sse};
}

struct Start {
  double sse;
  std::vector<double> params;
};

/// The best `count` starts by plain sum of squares, best first.
std::vector<Start> bestStarts(std::vector<Start> starts, int count) {
  std::sort(starts.begin(), starts.end(), [](const Start& a, const Start& b) { return a.sse < b.sse; });
  if (starts.size() > static_cast<std::size_t>(count)) starts.resize(static_cast<std::size_t>(count));
  return starts;
}

double paperX(const PaperModelParams& p, double torso_px) {
  return p.l1_m * std::exp(p.k1_per_px * torso_px) + p.l2_m * std::exp(p.k2_per_px * torso_px);
}

double pinholeX(const PinholeModelParams& p, double torso_px) {
  return p.fy_px * p.torso_m / torso_px + p.x_offset_m + p.x_inv_sq_m_px2 / (torso_px * torso_px);
}

rt::Status fitPaper(std::span<const LocalizationSample> samples, const hal::CameraIntrinsics& intrinsics,
                    const FitOptions& options, PaperModelParams& out) {
  const std::size_t n = samples.size();
  std::vector<double> torsos(n);
  for (std::size_t i = 0; i < n; ++i) torsos[i] = samples[i].torso_px;
  const double torso_ref_px = median(torsos);

  // ---- x: grid of exponent pairs, each solved for (l1, l2) by linear least squares ----
  Eigen::VectorXd x(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) x[static_cast<Eigen::Index>(i)] = samples[i].x_m;
  std::vector<Start> starts;
  Eigen::MatrixXd A(static_cast<Eigen::Index>(n), 2);
  for (std::size_t a = 0; a < kXExponentGrid.size(); ++a) {
    for (std::size_t b = a + 1; b < kXExponentGrid.size(); ++b) {
      for (std::size_t i = 0; i < n; ++i) {
        const double torso_n = samples[i].torso_px / torso_ref_px;
        A(static_cast<Eigen::Index>(i), 0) = std::exp(kXExponentGrid[a] * torso_n);
        A(static_cast<Eigen::Index>(i), 1) = std::exp(kXExponentGrid[b] * torso_n);
      }
      auto [c, sse] = linearLeastSquares(A, x);
      if (std::isfinite(sse))
        starts.push_back({sse, {c[0], kXExponentGrid[a], c[1], kXExponentGrid[b] - kXExponentGrid[a]}});
    }
  }
  std::vector<PaperXResidual> x_residuals;
  x_residuals.reserve(n);
  for (const LocalizationSample& s : samples) x_residuals.push_back({s.torso_px / torso_ref_px, s.x_m});
  double best_cost = std::numeric_limits<double>::infinity();
  std::array<double, 4> best_x{};
  std::string last_error = "no usable start";
  for (const Start& start : bestStarts(std::move(starts), options.paper_starts)) {
    std::array<double, 4> p = {start.params[0], start.params[1], start.params[2], start.params[3]};
    const rt::Expected<double> cost = solveRobust<4>(x_residuals, p, options, 3);
    if (!cost) {
      last_error = cost.error().message;
      continue;
    }
    if (*cost < best_cost) {
      best_cost = *cost;
      best_x = p;
    }
  }
  if (!std::isfinite(best_cost)) return rt::Error{"paper model: the x fit did not converge (" + last_error + ")"};
  out.l1_m = best_x[0];
  out.k1_per_px = best_x[1] / torso_ref_px;
  out.l2_m = best_x[2];
  out.k2_per_px = (best_x[1] + best_x[3]) / torso_ref_px;

  // ---- y, on the fitted x: for fixed exponents, y = l3 xhat e3 + l4 xhat e4 + m3 e3 + m4 e4 is
  // linear in (l3, l4, m3, m4), with m = l b; b is then the least-squares ratio ----
  std::vector<double> x_hat(n), u_n(n);
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    x_hat[i] = paperX(out, samples[i].torso_px);
    u_n[i] = (samples[i].u_px - intrinsics.cx_px) / intrinsics.fx_px;
    y[static_cast<Eigen::Index>(i)] = samples[i].y_m;
  }
  starts.clear();
  Eigen::MatrixXd B(static_cast<Eigen::Index>(n), 4);
  for (std::size_t a = 0; a < kYExponentGrid.size(); ++a) {
    for (std::size_t b = a + 1; b < kYExponentGrid.size(); ++b) {
      for (std::size_t i = 0; i < n; ++i) {
        const auto row = static_cast<Eigen::Index>(i);
        const double e3 = std::exp(kYExponentGrid[a] * u_n[i]);
        const double e4 = std::exp(kYExponentGrid[b] * u_n[i]);
        B(row, 0) = x_hat[i] * e3;
        B(row, 1) = x_hat[i] * e4;
        B(row, 2) = e3;
        B(row, 3) = e4;
      }
      auto [c, sse] = linearLeastSquares(B, y);
      if (!std::isfinite(sse)) continue;
      const double norm_sq = c[0] * c[0] + c[1] * c[1];
      const double offset_m = norm_sq > 1e-12 ? (c[0] * c[2] + c[1] * c[3]) / norm_sq : 0.0;
      starts.push_back({sse, {c[0], kYExponentGrid[a], c[1], kYExponentGrid[b] - kYExponentGrid[a], offset_m}});
    }
  }
  std::vector<PaperYResidual> y_residuals;
  y_residuals.reserve(n);
  for (std::size_t i = 0; i < n; ++i) y_residuals.push_back({u_n[i], x_hat[i], samples[i].y_m});
  best_cost = std::numeric_limits<double>::infinity();
  std::array<double, 5> best_y{};
  last_error = "no usable start";
  for (const Start& start : bestStarts(std::move(starts), options.paper_starts)) {
    std::array<double, 5> p = {start.params[0], start.params[1], start.params[2], start.params[3], start.params[4]};
    const rt::Expected<double> cost = solveRobust<5>(y_residuals, p, options, 3);
    if (!cost) {
      last_error = cost.error().message;
      continue;
    }
    if (*cost < best_cost) {
      best_cost = *cost;
      best_y = p;
    }
  }
  if (!std::isfinite(best_cost)) return rt::Error{"paper model: the y fit did not converge (" + last_error + ")"};
  const double k4_n = best_y[1] + best_y[3];
  out.k3_per_px = best_y[1] / intrinsics.fx_px;
  out.l3 = best_y[0] * std::exp(-best_y[1] * intrinsics.cx_px / intrinsics.fx_px);
  out.k4_per_px = k4_n / intrinsics.fx_px;
  out.l4 = best_y[2] * std::exp(-k4_n * intrinsics.cx_px / intrinsics.fx_px);
  out.b_m = best_y[4];
  return rt::ok();
}

rt::Status fitPinhole(std::span<const LocalizationSample> samples, const hal::CameraIntrinsics& intrinsics,
                      const FitOptions& options, PinholeModelParams& out) {
  const std::size_t n = samples.size();
  std::vector<double> torsos(n);
  for (std::size_t i = 0; i < n; ++i) torsos[i] = samples[i].torso_px;
  const double torso_ref_px = median(torsos);
  out.fx_px = intrinsics.fx_px;
  out.fy_px = intrinsics.fy_px;
  out.cx_px = intrinsics.cx_px;

  // x: linear least squares for the start, then the robust fit.
  std::vector<PinholeXResidual> x_residuals;
  x_residuals.reserve(n);
  Eigen::MatrixXd A(static_cast<Eigen::Index>(n), 3);
  Eigen::VectorXd x(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const LocalizationSample& s = samples[i];
    const double ratio = torso_ref_px / s.torso_px;
    x_residuals.push_back({intrinsics.fy_px / s.torso_px, ratio * ratio, s.x_m});
    const auto row = static_cast<Eigen::Index>(i);
    A(row, 0) = x_residuals.back().fy_over_torso;
    A(row, 1) = 1.0;
    A(row, 2) = x_residuals.back().ref_over_torso_sq;
    x[row] = s.x_m;
  }
  auto [cx, sse_x] = linearLeastSquares(A, x);
  std::array<double, 3> px = {0.5, 0.0, 0.0};  // a 0.5 m torso, if the data is degenerate
  if (std::isfinite(sse_x)) px = {cx[0], cx[1], cx[2]};
  if (rt::Expected<double> cost = solveRobust<3>(x_residuals, px, options); !cost) {
    return rt::Error{"pinhole model: the x fit did not converge (" + cost.error().message + ")"};
  }
  out.torso_m = px[0];
  out.x_offset_m = px[1];
  out.x_inv_sq_m_px2 = px[2] * torso_ref_px * torso_ref_px;

  // y on the fitted x: linear in (d, e) too.
  std::vector<PinholeYResidual> y_residuals;
  y_residuals.reserve(n);
  Eigen::MatrixXd B(static_cast<Eigen::Index>(n), 2);
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const LocalizationSample& s = samples[i];
    const double tan_u = (s.u_px - intrinsics.cx_px) / intrinsics.fx_px;
    const double x_hat_m = pinholeX(out, s.torso_px);
    y_residuals.push_back({tan_u, x_hat_m, s.y_m});
    const auto row = static_cast<Eigen::Index>(i);
    B(row, 0) = -x_hat_m * tan_u;
    B(row, 1) = 1.0;
    y[row] = s.y_m + x_hat_m * tan_u;  // y + xhat tan = -xhat tan d + e
  }
  auto [cy, sse_y] = linearLeastSquares(B, y);
  std::array<double, 2> py = {0.0, 0.0};
  if (std::isfinite(sse_y)) py = {cy[0], cy[1]};
  if (rt::Expected<double> cost = solveRobust<2>(y_residuals, py, options); !cost) {
    return rt::Error{"pinhole model: the y fit did not converge (" + cost.error().message + ")"};
  }
  out.y_scale_correction = py[0];
  out.y_offset_m = py[1];
  return rt::ok();
}

}  // namespace

std::string_view toString(LocalizationModel model) {
  switch (model) {
    case LocalizationModel::kPaper:
      return "paper";
    case LocalizationModel::kPinhole:
      return "pinhole";
  }
  return "unknown";
}

rt::Expected<LocalizationModel> parseLocalizationModel(std::string_view text) {
  if (text == "paper") return LocalizationModel::kPaper;
  if (text == "pinhole") return LocalizationModel::kPinhole;
  return rt::Error{"expected paper or pinhole, got '" + std::string(text) + "'"};
}

rt::Expected<LocalizationParams> fit(LocalizationModel model, std::span<const LocalizationSample> samples,
                                     const hal::CameraIntrinsics& intrinsics, const FitOptions& options) {
  if (!(options.robust_loss_scale_m > 0.0) || options.max_iterations < 1 || options.paper_starts < 1) {
    return rt::Error{"fit options: robust_loss_scale_m > 0, max_iterations >= 1 and paper_starts >= 1 required"};
  }
  if (!(intrinsics.fx_px > 0.0) || !(intrinsics.fy_px > 0.0) || !std::isfinite(intrinsics.fx_px) ||
      !std::isfinite(intrinsics.fy_px) || !std::isfinite(intrinsics.cx_px)) {
    return rt::Error{"camera intrinsics: fx_px and fy_px must be finite and > 0, cx_px finite"};
  }
  const std::size_t min_samples = model == LocalizationModel::kPaper ? kMinPaperSamples : kMinPinholeSamples;
  if (rt::Status status = checkSamples(samples, min_samples); !status) {
    return rt::Error{std::string(toString(model)) + " model: " + status.error().message};
  }
  LocalizationParams params;
  params.model = model;
  const rt::Status fitted = model == LocalizationModel::kPaper
                                ? fitPaper(samples, intrinsics, options, params.paper)
                                : fitPinhole(samples, intrinsics, options, params.pinhole);
  if (!fitted) return fitted.error();

  double z_sum_m = 0.0;
  std::size_t z_count = 0;
  for (const LocalizationSample& s : samples) {
    if (std::isfinite(s.z_m)) {
      z_sum_m += s.z_m;
      ++z_count;
    }
  }
  params.z_m = z_count > 0 ? z_sum_m / static_cast<double>(z_count) : 0.0;
  params.fit_samples = samples.size();
  double error_sum_m = 0.0;
  for (const LocalizationSample& s : samples) {
    const Eigen::Vector3d p_C = predict(params, s.torso_px, s.u_px);
    error_sum_m += std::hypot(p_C.x() - s.x_m, p_C.y() - s.y_m);
  }
  params.fit_mean_error_m = error_sum_m / static_cast<double>(samples.size());
  fitNoise(params, samples);
  if (rt::Status valid = validatePredictions(params); !valid) {
    return rt::Error{std::string(toString(model)) + " model: the fit gave " + valid.error().message};
  }
  return params;
}

void fitNoise(LocalizationParams& params, std::span<const LocalizationSample> samples) {
  params.noise_std_m = params.noise_std_per_m = 0.0;
  struct Residual {
    double x_m, error_m;
  };
  std::vector<Residual> residuals;
  residuals.reserve(samples.size());
  for (const LocalizationSample& s : samples) {
    const Eigen::Vector3d p_C = predict(params, s.torso_px, s.u_px);
    const double error_m = std::hypot(p_C.x() - s.x_m, p_C.y() - s.y_m);
    if (std::isfinite(error_m) && std::isfinite(s.x_m)) residuals.push_back({s.x_m, error_m});
  }
  if (residuals.empty()) return;
  std::sort(residuals.begin(), residuals.end(), [](const Residual& a, const Residual& b) { return a.x_m < b.x_m; });
  constexpr std::size_t kMinPerBin = 50;
  constexpr std::size_t kMaxBins = 8;
  // The median length of a 2-D isotropic Gaussian vector of per-axis sigma: sigma sqrt(2 ln 2).
  const double kRayleighMedian = std::sqrt(2.0 * std::log(2.0));
  const std::size_t bins = std::clamp<std::size_t>(residuals.size() / kMinPerBin, 1, kMaxBins);
  std::vector<double> bin_x, bin_sigma, scratch;
  for (std::size_t b = 0; b < bins; ++b) {
    const std::size_t from = b * residuals.size() / bins;
    const std::size_t to = (b + 1) * residuals.size() / bins;
    const auto median_of = [&](auto value) {
      scratch.clear();
      for (std::size_t i = from; i < to; ++i) scratch.push_back(value(residuals[i]));
      const auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
      std::nth_element(scratch.begin(), mid, scratch.end());
      return *mid;
    };
    bin_x.push_back(median_of([](const Residual& r) { return r.x_m; }));
    bin_sigma.push_back(median_of([](const Residual& r) { return r.error_m; }) / kRayleighMedian);
  }
  const auto n = static_cast<double>(bins);
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  for (std::size_t b = 0; b < bins; ++b) {
    sx += bin_x[b];
    sy += bin_sigma[b];
    sxx += bin_x[b] * bin_x[b];
    sxy += bin_x[b] * bin_sigma[b];
  }
  const double det = n * sxx - sx * sx;
  double slope = det > 1e-12 ? (n * sxy - sx * sy) / det : 0.0;
  double intercept = (sy - slope * sx) / n;
  if (slope < 0.0) {  // noise that falls with distance is not a model to extrapolate: a constant
    slope = 0.0;
    intercept = sy / n;
  } else if (intercept < 0.0) {  // through the origin
    intercept = 0.0;
    slope = sxx > 0.0 ? sxy / sxx : 0.0;
  }
  params.noise_std_m = intercept;
  params.noise_std_per_m = slope;
}

Eigen::Vector3d predict(const LocalizationParams& params, double torso_px, double u_px) {
  if (!(torso_px > 0.0)) return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  const double x_m =
      params.model == LocalizationModel::kPaper ? paperX(params.paper, torso_px) : pinholeX(params.pinhole, torso_px);
  return predictAtDistance(params, x_m, u_px);
}

Eigen::Vector3d predictAtDistance(const LocalizationParams& params, double x_m, double u_px) {
  double y_m = 0.0;
  if (params.model == LocalizationModel::kPaper) {
    const PaperModelParams& p = params.paper;
    y_m = (p.l3 * std::exp(p.k3_per_px * u_px) + p.l4 * std::exp(p.k4_per_px * u_px)) * (x_m + p.b_m);
  } else {
    const PinholeModelParams& p = params.pinhole;
    y_m = -x_m * (u_px - p.cx_px) / p.fx_px * (1.0 + p.y_scale_correction) + p.y_offset_m;
  }
  return {x_m, y_m, params.z_m};
}

const rt::FieldTable<PaperModelParams>& paperModelFields() {
  using P = PaperModelParams;
  const rt::Range any = rt::Range::finite();
  static const rt::FieldTable<P> kTable({
      rt::number("l1_m", &P::l1_m, any),
      rt::number("k1_per_px", &P::k1_per_px, any),
      rt::number("l2_m", &P::l2_m, any),
      rt::number("k2_per_px", &P::k2_per_px, any),
      rt::number("l3", &P::l3, any),
      rt::number("k3_per_px", &P::k3_per_px, any),
      rt::number("l4", &P::l4, any),
      rt::number("k4_per_px", &P::k4_per_px, any),
      rt::number("b_m", &P::b_m, any),
  });
  return kTable;
}

const rt::FieldTable<PinholeModelParams>& pinholeModelFields() {
  using P = PinholeModelParams;
  const rt::Range any = rt::Range::finite();
  static const rt::FieldTable<P> kTable({
      rt::number("fx_px", &P::fx_px, rt::Range::greaterThan(0.0)),
      rt::number("fy_px", &P::fy_px, rt::Range::greaterThan(0.0)),
      rt::number("cx_px", &P::cx_px, any),
      rt::number("torso_m", &P::torso_m, any),
      rt::number("x_offset_m", &P::x_offset_m, any),
      rt::number("x_inv_sq_m_px2", &P::x_inv_sq_m_px2, any),
      rt::number("y_scale_correction", &P::y_scale_correction, any),
      rt::number("y_offset_m", &P::y_offset_m, any),
  });
  return kTable;
}

const rt::FieldTable<LocalizationParams>& localizationFields() {
  using P = LocalizationParams;
  const auto is = [](LocalizationModel model) { return [model](const P& p) { return p.model == model; }; };
  static const rt::FieldTable<P> kTable({
      rt::choice("model", &P::model,
                 {{std::string(toString(LocalizationModel::kPaper)), LocalizationModel::kPaper},
                  {std::string(toString(LocalizationModel::kPinhole)), LocalizationModel::kPinhole}}),
      rt::number("z_m", &P::z_m, rt::Range::finite()),
      rt::count("fit_samples", &P::fit_samples),
      rt::number("fit_mean_error_m", &P::fit_mean_error_m, rt::Range::atLeast(0.0)),
      rt::optionalNumber("noise_std_m", &P::noise_std_m, rt::Range::closed(0.0, 100.0), 0.0),
      rt::optionalNumber("noise_std_per_m", &P::noise_std_per_m, rt::Range::closed(0.0, 10.0), 0.0),
      rt::section("paper", &P::paper, paperModelFields())
          .when(is(LocalizationModel::kPaper))
          .withComment("x = l1_m e^(k1_per_px L) + l2_m e^(k2_per_px L); y = (l3 e^(k3_per_px u) + l4 e^(k4_per_px u)) "
                       "(x + b_m)"),
      rt::section("pinhole", &P::pinhole, pinholeModelFields())
          .when(is(LocalizationModel::kPinhole))
          .withComment("x = fy_px torso_m / L + x_offset_m + x_inv_sq_m_px2 / L^2;\n"
                       "y = -x (u - cx_px) / fx_px (1 + y_scale_correction) + y_offset_m"),
  });
  return kTable;
}

rt::Status validate(const LocalizationParams& params) {
  return localizationFields().validate(params);
}

rt::Status validatePredictions(const LocalizationParams& params) {
  if (rt::Status fields = validate(params); !fields) return fields;
  constexpr double kMaxPredictionM = 1e4;
  for (const double torso_px : {10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0}) {
    for (const double u_px : {0.0, 320.0, 640.0, 960.0, 1280.0}) {
      const Eigen::Vector3d p_C = predict(params, torso_px, u_px);
      if (!p_C.allFinite() || p_C.cwiseAbs().maxCoeff() > kMaxPredictionM) {
        std::array<char, 160> text{};
        std::snprintf(text.data(), text.size(),
                      "predicts (%.3g, %.3g) m for a torso of %g px at u = %g px: not a position", p_C.x(), p_C.y(),
                      torso_px, u_px);
        return rt::Error{std::string(toString(params.model)) + " model " + text.data()};
      }
    }
  }
  return rt::ok();
}

std::string implausibleSample(const LocalizationSample& s) {
  const auto outside = [](const char* column, double value, const char* range) {
    std::array<char, 96> text{};
    std::snprintf(text.data(), text.size(), "%s: must be in %s, got %.6g", column, range, value);
    return std::string(text.data());
  };
  if (!(s.torso_px > 0.0 && s.torso_px <= 1e4)) return outside("torso_px", s.torso_px, "(0, 10000]");
  if (!(std::abs(s.u_px) <= 1e4)) return outside("u_px", s.u_px, "[-10000, 10000]");
  if (!(s.x_m > 0.0 && s.x_m <= 1e3)) return outside("x_m", s.x_m, "(0, 1000]");
  if (!(std::abs(s.y_m) <= 1e3)) return outside("y_m", s.y_m, "[-1000, 1000]");
  if (std::isfinite(s.z_m) && !(std::abs(s.z_m) <= 1e3)) return outside("z_m", s.z_m, "[-1000, 1000]");
  return "";
}

}  // namespace aerotrack::localization
