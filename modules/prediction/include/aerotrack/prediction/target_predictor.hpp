// TargetPredictor: the person's future path p_WT(t) (W world ENU, metres) over the prediction
// horizon, from the target estimator's recent positions -- the paper's Sect. V-A (after
// Fast-Tracker): polynomial regression with a Bezier curve, as a QP.
//  - The curve: one Bezier of degree n (default 5) per axis over [t_first, t_now + horizon], in
//    normalised time. It is fitted to the estimates of the last window_s, so its part beyond the
//    newest datum is the extrapolation (the paper's P_t on (t_c, t_p]).
//  - The cost: the age-weighted mean squared residual, sum_k w_k |p(t_k) - p_k|^2 / sum_k w_k with
//    w_k = 2^(-age_k / weight_half_life_s) (old estimates count less), plus
//    accel_energy_weight_s3 * int |p''(t)|^2 dt over the whole span (closed form, bezier.hpp), which
//    keeps the curve from over-fitting and makes the future part continue smoothly.
//  - The constraints (the paper's assumption 3, bounded velocity and acceleration): every
//    control point of the velocity and acceleration hodographs within +-max_speed_mps and
//    +-max_accel_mps2 per axis, so by the convex hull property the bounds hold on the whole curve
//    (a per-axis box: the horizontal speed is at most sqrt(2) max_speed_mps). Optionally the curve
//    passes through the newest estimate (pin_to_newest).
//  - Dropouts: predict(now) with no new data still fits over [t_first, now + horizon], so the
//    prediction keeps extrapolating, and reports the age of its newest datum; past max_data_age_s
//    it fails instead.
// Each axis is one small QP solved by DenseQpSolver, warm-started with that axis's last active set.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/prediction/bezier.hpp"
#include "aerotrack/prediction/dense_qp.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::prediction {

struct TargetPredictorParams {
  int bezier_degree = 5;                 ///< n, 3..kMaxBezierDegree.
  double window_s = 1.5;                 ///< Estimates older than the newest minus this are dropped; > 0.
  double horizon_s = 1.5;                ///< Prediction horizon after now; > 0.
  double weight_half_life_s = 0.5;       ///< An estimate's weight halves with every this much age; > 0.
  double accel_energy_weight_s3 = 0.01;  ///< lambda on int |p''|^2 dt (cost in m^2); >= 0.
  double max_speed_mps = 3.0;            ///< Bound on each axis of the velocity; > 0.
  double max_accel_mps2 = 3.0;           ///< Bound on each axis of the acceleration; > 0.
  bool fit_z = false;                    ///< False: z is the weighted mean height, constant.
  bool pin_to_newest = false;            ///< The curve passes exactly through the newest estimate.
  /// The curve's velocity at the newest estimate's time is the estimate's (the Kalman filter's), where the
  /// estimate carries one. Why (issue 21): weighted over its window, the fit lags a runner who brakes
  /// (4.09 m/s against the filter's 3.21 m/s on forest 5 m/s seed 1), so the goal stays metres ahead of
  /// a person who stops and the drone overshoots them. (The shipped configs turn it on: docs/benchmarks.md.)
  bool pin_velocity_to_newest = false;
  /// Softer: w x (curve velocity at the newest estimate's time - the estimate's)^2 added to the fit (w in s^2:
  /// 1 m/s off costs w m^2, against position residuals whose weights sum to 1); 0: off. Ignored when
  /// pin_velocity_to_newest; >= 0.
  double newest_velocity_weight = 0.0;
  int min_samples = 5;          ///< Fewer estimates in the window: no prediction; >= 2.
  double max_data_age_s = 3.0;  ///< Newest estimate older than this at now: no prediction; > 0.
  int max_samples = 128;        ///< Buffer size (allocated once); >= min_samples.
  int qp_max_iterations = 100;  ///< Per axis; >= 1.
};

/// The predictor's config section: every field of TargetPredictorParams by its name, all required, with
/// the one range per field (and the rule max_samples >= min_samples) that parsing, validate() and
/// printing share (rt/field_table.hpp; the ranges are in the .cpp).
const rt::FieldTable<TargetPredictorParams>& targetPredictorFields();

/// Ok if every field is in its range and the rule holds; the error names the field.
rt::Status validate(const TargetPredictorParams& params);

/// targetPredictorFields().parse. Throws rt::ConfigError naming the key (use inside rt::parseConfig).
TargetPredictorParams parseTargetPredictorParams(const rt::ConfigNode& node);

/// The predicted path: a Bezier curve in W from start_ns (the oldest estimate used) to end_ns
/// (now + horizon). Evaluation is thread-safe and allocation-free. Times outside [start_ns, end_ns]
/// evaluate the polynomial, but the bounds are guaranteed only inside.
struct TargetPrediction {
  int degree = 0;
  std::array<Eigen::Vector3d, kMaxBezierDegree + 1> control_points_W_m{};  ///< c_0..c_degree.
  rt::TimeNs start_ns = 0;
  rt::TimeNs end_ns = 0;
  rt::TimeNs now_ns = 0;          ///< The time predict() was called for (>= newest_data_ns).
  rt::TimeNs newest_data_ns = 0;  ///< Capture time of the newest estimate used.
  int samples_used = 0;
  int qp_iterations = 0;  ///< Summed over the axes.

  double durationS() const { return rt::nsToSeconds(end_ns - start_ns); }
  /// How old the newest estimate is at now_ns, seconds (grows during a dropout).
  double dataAgeS() const { return rt::nsToSeconds(now_ns - newest_data_ns); }
  Eigen::Vector3d position(rt::TimeNs t_ns) const;      ///< p_WT, metres.
  Eigen::Vector3d velocity(rt::TimeNs t_ns) const;      ///< v_WT, m/s.
  Eigen::Vector3d acceleration(rt::TimeNs t_ns) const;  ///< a_WT, m/s^2.
  /// Velocity hodograph control point i = 0..degree-1, m/s: n/T (c_{i+1} - c_i).
  Eigen::Vector3d velocityControlPoint(int i) const;
  /// Acceleration hodograph control point i = 0..degree-2, m/s^2: n(n-1)/T^2 (c_{i+2} - 2c_{i+1} + c_i).
  Eigen::Vector3d accelerationControlPoint(int i) const;
};

/// Thread safety: none (one owner). Allocation: create() only; add() and a successful predict()
/// never allocate (a failed predict() allocates its error text).
class TargetPredictor {
 public:
  static rt::Expected<TargetPredictor> create(const TargetPredictorParams& params);

  /// Appends an estimate of p_WT at its time. Returns false (and ignores it) when it is not newer
  /// than the newest or not finite. Drops the estimates that fell out of the window.
  bool add(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WT_m);
  /// ... with the estimate's velocity (used by pin_velocity_to_newest); not finite: ignored, as above.
  bool add(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WT_m, const Eigen::Vector3d& v_WT_mps);

  /// Fits the curve over [oldest estimate, now_ns + horizon_s] (now_ns before the newest estimate
  /// counts as the newest estimate's time). Errors: fewer than min_samples estimates, data older
  /// than max_data_age_s, or a QP failure (named).
  rt::Expected<TargetPrediction> predict(rt::TimeNs now_ns);

  void reset();
  std::size_t sampleCount() const { return samples_.size(); }
  const TargetPredictorParams& params() const { return params_; }

 private:
  struct Sample {
    rt::TimeNs stamp_ns = 0;
    Eigen::Vector3d p_WT_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d v_WT_mps = Eigen::Vector3d::Zero();
    bool has_velocity = false;
  };

  TargetPredictor(const TargetPredictorParams& params, DenseQpSolver solver);

  TargetPredictorParams params_;
  DenseQpSolver solver_;
  std::vector<Sample> samples_;  ///< In time order, capacity max_samples.
  Eigen::MatrixXd energy_unit_;  ///< Acceleration energy matrix for T = 1 s.
  Eigen::MatrixXd basis_;        ///< (n+1) x max_samples: Bernstein basis at each sample.
  Eigen::VectorXd weights_;      ///< Normalised weights, per sample.
  Eigen::MatrixXd hessian_;
  Eigen::VectorXd gradient_;
  Eigen::MatrixXd a_eq_, a_in_;
  Eigen::VectorXd b_eq_, b_in_;
  std::array<std::vector<int>, 3> warm_active_;  ///< Per axis: the last active set.
};

}  // namespace aerotrack::prediction
