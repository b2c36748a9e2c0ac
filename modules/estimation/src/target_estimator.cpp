// The target estimator: constant-velocity Kalman filter with gating and out-of-sequence replay
// (see target_estimator.hpp).
#include "aerotrack/estimation/target_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include <Eigen/Cholesky>

namespace aerotrack::estimation {
namespace {

using Matrix3d = Eigen::Matrix3d;

bool valid(const TargetMeasurement& m) {
  const bool bad_bearing =
      m.hasLineOfSight() && (!m.bearing_W.allFinite() || std::abs(m.bearing_W.norm() - 1.0) > 1e-6 ||
                             !std::isfinite(m.range_std_m) || !(m.range_std_m > 0.0));
  return m.p_WT_m.allFinite() && std::isfinite(m.std_xy_m) && std::isfinite(m.std_z_m) && m.std_xy_m >= 0.0 &&
         m.std_z_m >= 0.0 && !bad_bearing;
}

/// R: std_xy across the line of sight and, for a bearing or a ranged measurement, range_std_m along it
/// (R = s^2 I + (r^2 - s^2) b b^T).
Matrix3d measurementNoise(const TargetEstimatorParams& params, const TargetMeasurement& m) {
  const double std_xy = m.std_xy_m > 0.0 ? m.std_xy_m : params.measurement_std_xy_m;
  const double std_z = m.std_z_m > 0.0 ? m.std_z_m : params.measurement_std_z_m;
  Matrix3d R = Eigen::Vector3d(std_xy * std_xy, std_xy * std_xy, std_z * std_z).asDiagonal();
  if (m.hasLineOfSight()) {
    const Eigen::Vector2d& b = m.bearing_W;
    R.topLeftCorner<2, 2>() += (m.range_std_m * m.range_std_m - std_xy * std_xy) * b * b.transpose();
  }
  return R;
}

using Matrix36d = Eigen::Matrix<double, 3, 6>;

/// The Kalman update with H = [I 0]: K = P H^T S^-1 (S factored in llt); Joseph form (I - K H) P (I - K H)^T + K R K^T.
void kalmanUpdate(Vector6d& x, Matrix6d& P, const Eigen::Vector3d& innovation, const Eigen::LLT<Matrix3d>& llt,
                  const Matrix3d& R) {
  const Eigen::Matrix<double, 6, 3> PHt = P.leftCols<3>();
  const Eigen::Matrix<double, 6, 3> K = llt.solve(PHt.transpose()).transpose();
  x += K * innovation;
  Matrix6d I_KH = Matrix6d::Identity();
  I_KH.leftCols<3>() -= K;
  P = I_KH * P * I_KH.transpose() + K * R * K.transpose();
}

bool positiveFinite(double v) {
  return std::isfinite(v) && v > 0.0;
}

}  // namespace

rt::Status validate(const TargetEstimatorParams& p) {
  const auto positive = [](const char* name, double v) -> rt::Status {
    if (!positiveFinite(v)) return rt::Error{std::string("target estimator: ") + name + " must be finite and > 0"};
    return rt::ok();
  };
  for (const auto& [name, value] : {std::pair<const char*, double>{"accel_psd_xy_m2ps3", p.accel_psd_xy_m2ps3},
                                    {"accel_psd_z_m2ps3", p.accel_psd_z_m2ps3},
                                    {"measurement_std_xy_m", p.measurement_std_xy_m},
                                    {"measurement_std_z_m", p.measurement_std_z_m},
                                    {"initial_speed_std_mps", p.initial_speed_std_mps},
                                    {"gate_chi2", p.gate_chi2},
                                    {"lost_after_s", p.lost_after_s},
                                    {"replay_window_s", p.replay_window_s}}) {
    if (rt::Status s = positive(name, value); !s) return s;
  }
  if (p.reinit_after_rejections < 1) return rt::Error{"target estimator: reinit_after_rejections must be >= 1"};
  if (p.max_buffered_measurements < 2) return rt::Error{"target estimator: max_buffered_measurements must be >= 2"};
  if (!std::isfinite(p.manoeuvre_accel_psd_xy_m2ps3) || p.manoeuvre_accel_psd_xy_m2ps3 < 0.0 ||
      (p.manoeuvre_accel_psd_xy_m2ps3 > 0.0 && !(p.manoeuvre_accel_psd_xy_m2ps3 > p.accel_psd_xy_m2ps3)))
    return rt::Error{"target estimator: manoeuvre_accel_psd_xy_m2ps3 must be 0 (off) or > accel_psd_xy_m2ps3"};
  if (rt::Status s = positive("steady_mean_s", p.steady_mean_s); !s) return s;
  if (rt::Status s = positive("manoeuvre_mean_s", p.manoeuvre_mean_s); !s) return s;
  return rt::ok();
}

TargetEstimatorParams parseTargetEstimatorParams(const rt::ConfigNode& node) {
  TargetEstimatorParams p;
  p.accel_psd_xy_m2ps3 = node.getDouble("accel_psd_xy_m2ps3", 1e-6, 1e3);
  p.accel_psd_z_m2ps3 = node.getDouble("accel_psd_z_m2ps3", 1e-6, 1e3);
  p.measurement_std_xy_m = node.getDouble("measurement_std_xy_m", 1e-4, 100.0);
  p.measurement_std_z_m = node.getDouble("measurement_std_z_m", 1e-4, 100.0);
  p.initial_speed_std_mps = node.getDouble("initial_speed_std_mps", 1e-3, 100.0);
  p.gate_chi2 = node.getDouble("gate_chi2", 0.1, 1e6);
  p.reinit_after_rejections = node.getInt("reinit_after_rejections", 1, 10000);
  p.lost_after_s = node.getDouble("lost_after_s", 1e-3, 3600.0);
  p.replay_window_s = node.getDouble("replay_window_s", 1e-3, 60.0);
  p.max_buffered_measurements = static_cast<std::size_t>(node.getInt("max_buffered_measurements", 2, 100000));
  p.manoeuvre_accel_psd_xy_m2ps3 = node.getDouble("manoeuvre_accel_psd_xy_m2ps3", 0.0, 1e3);
  p.steady_mean_s = node.getDouble("steady_mean_s", 1e-3, 3600.0);
  p.manoeuvre_mean_s = node.getDouble("manoeuvre_mean_s", 1e-3, 3600.0);
  p.hold_probabilities_coasting = node.getBool("hold_probabilities_coasting");
  node.finish();
  return p;
}

const char* toString(MeasurementVerdict verdict) {
  switch (verdict) {
    case MeasurementVerdict::kAccepted:
      return "accepted";
    case MeasurementVerdict::kStarted:
      return "started";
    case MeasurementVerdict::kRejectedGate:
      return "rejected_gate";
    case MeasurementVerdict::kRejectedTooOld:
      return "rejected_too_old";
    case MeasurementVerdict::kRejectedInvalid:
      return "rejected_invalid";
    case MeasurementVerdict::kRejectedNoTrack:
      return "rejected_no_track";
  }
  return "unknown";
}

rt::Expected<TargetEstimator> TargetEstimator::create(const TargetEstimatorParams& params) {
  if (rt::Status status = validate(params); !status) return status.error();
  return TargetEstimator(params);
}

TargetEstimator::TargetEstimator(const TargetEstimatorParams& params) : params_(params) {
  buffer_.reserve(params.max_buffered_measurements);
}

void TargetEstimator::reset() {
  anchor_ = State{};
  buffer_.clear();
  folded_any_ = false;
  folded_until_ns_ = 0;
}

void TargetEstimator::startAt(const TargetMeasurement& m, Vector6d& x, Matrix6d& P) const {
  const double std_xy = m.std_xy_m > 0.0 ? m.std_xy_m : params_.measurement_std_xy_m;
  const double std_z = m.std_z_m > 0.0 ? m.std_z_m : params_.measurement_std_z_m;
  x.head<3>() = m.p_WT_m;
  x.tail<3>().setZero();
  P.setZero();
  P.diagonal() << std_xy * std_xy, std_xy * std_xy, std_z * std_z,
      Eigen::Vector3d::Constant(params_.initial_speed_std_mps * params_.initial_speed_std_mps);
}

void TargetEstimator::start(State& state, const TargetMeasurement& m) const {
  state.initialised = true;
  state.stamp_ns = m.stamp_ns;
  startAt(m, state.x, state.P);
  state.last_accepted_ns = m.stamp_ns;
  state.tentative.count = 0;
  // Both models start at the measurement, weighted by the chain's stationary probabilities.
  const double manoeuvring = params_.manoeuvre_mean_s / (params_.steady_mean_s + params_.manoeuvre_mean_s);
  state.models[0] = Model{state.x, state.P, imm() ? 1.0 - manoeuvring : 1.0};
  state.models[1] = Model{state.x, state.P, imm() ? manoeuvring : 0.0};
}

int TargetEstimator::extendTentative(State::Tentative& tentative, const TargetMeasurement& m) const {
  const Matrix3d R = measurementNoise(params_, m);
  if (tentative.count > 0 && m.stamp_ns >= tentative.stamp_ns) {
    Vector6d x = tentative.x;
    Matrix6d P = tentative.P;
    predictModel(x, P, rt::nsToSeconds(m.stamp_ns - tentative.stamp_ns), params_.accel_psd_xy_m2ps3);
    const Eigen::Vector3d innovation = m.p_WT_m - x.head<3>();
    const Eigen::LLT<Matrix3d> llt(P.topLeftCorner<3, 3>() + R);
    if (llt.info() == Eigen::Success && innovation.dot(llt.solve(innovation)) <= params_.gate_chi2) {
      kalmanUpdate(x, P, innovation, llt, R);
      tentative.x = x;
      tentative.P = P;
      tentative.stamp_ns = m.stamp_ns;
      return ++tentative.count;
    }
  }
  startAt(m, tentative.x, tentative.P);  // the first of a new run
  tentative.stamp_ns = m.stamp_ns;
  tentative.count = 1;
  return 1;
}

void TargetEstimator::predictModel(Vector6d& x, Matrix6d& P, double dt, double q_xy) const {
  // x' = F x with F = [I dt I; 0 I]; P' = F P F^T + Q, computed blockwise.
  x.head<3>() += dt * x.tail<3>();
  const Matrix3d Ppp = P.topLeftCorner<3, 3>();
  const Matrix3d Ppv = P.topRightCorner<3, 3>();
  const Matrix3d Pvv = P.bottomRightCorner<3, 3>();
  const Matrix3d new_Ppv = Ppv + dt * Pvv;
  P.topLeftCorner<3, 3>() = Ppp + dt * (Ppv + Ppv.transpose()) + dt * dt * Pvv;
  P.topRightCorner<3, 3>() = new_Ppv;
  P.bottomLeftCorner<3, 3>() = new_Ppv.transpose();
  const Eigen::Vector3d q(q_xy, q_xy, params_.accel_psd_z_m2ps3);
  for (int i = 0; i < 3; ++i) {
    P(i, i) += q[i] * dt * dt * dt / 3.0;
    P(i, i + 3) += q[i] * dt * dt / 2.0;
    P(i + 3, i) += q[i] * dt * dt / 2.0;
    P(i + 3, i + 3) += q[i] * dt;
  }
}

void TargetEstimator::mixture(const std::array<Model, 2>& models, const std::array<double, 2>& weights, Vector6d& x,
                              Matrix6d& P) {
  x = weights[0] * models[0].x + weights[1] * models[1].x;
  P.setZero();
  for (int i = 0; i < 2; ++i) {
    const Vector6d d = models[i].x - x;
    P += weights[i] * (models[i].P + d * d.transpose());
  }
}

void TargetEstimator::combine(State& state) {
  mixture(state.models, {state.models[0].probability, state.models[1].probability}, state.x, state.P);
}

void TargetEstimator::predict(State& state, rt::TimeNs t_ns, bool transitions) const {
  if (t_ns <= state.stamp_ns) return;
  const double dt = rt::nsToSeconds(t_ns - state.stamp_ns);
  state.stamp_ns = t_ns;
  if (!imm()) {
    predictModel(state.x, state.P, dt, params_.accel_psd_xy_m2ps3);
    return;
  }
  if (transitions) {
    // The chain's transition probabilities over dt (exact for a two-state continuous-time Markov chain):
    // pi[i][j] = P(model j at the end | model i at the start).
    const double to_manoeuvre = 1.0 / params_.steady_mean_s;
    const double to_steady = 1.0 / params_.manoeuvre_mean_s;
    const double rate = to_manoeuvre + to_steady;
    const double settled = 1.0 - std::exp(-rate * dt);
    const double stationary_manoeuvre = to_manoeuvre / rate;
    const double pi[2][2] = {{1.0 - stationary_manoeuvre * settled, stationary_manoeuvre * settled},
                             {(1.0 - stationary_manoeuvre) * settled, 1.0 - (1.0 - stationary_manoeuvre) * settled}};
    // Interaction (mixing): each model starts from the mixture of both, weighted by where it came from.
    std::array<Model, 2> mixed;
    for (int j = 0; j < 2; ++j) {
      const double c = pi[0][j] * state.models[0].probability + pi[1][j] * state.models[1].probability;
      const std::array<double, 2> from = c > 0.0 ? std::array<double, 2>{pi[0][j] * state.models[0].probability / c,
                                                                         pi[1][j] * state.models[1].probability / c}
                                                 : std::array<double, 2>{0.5, 0.5};
      mixture(state.models, from, mixed[j].x, mixed[j].P);
      mixed[j].probability = c;
    }
    state.models = mixed;
  }
  predictModel(state.models[0].x, state.models[0].P, dt, params_.accel_psd_xy_m2ps3);
  predictModel(state.models[1].x, state.models[1].P, dt, params_.manoeuvre_accel_psd_xy_m2ps3);
  combine(state);
}

MeasurementVerdict TargetEstimator::step(State& state, const TargetMeasurement& m) const {
  const rt::DurationNs lost_after_ns = rt::secondsToNs(params_.lost_after_s);
  const bool lost = !state.initialised || m.stamp_ns - state.last_accepted_ns > lost_after_ns;
  if (lost && m.bearingOnly()) return MeasurementVerdict::kRejectedNoTrack;
  if (lost) {
    start(state, m);
    return MeasurementVerdict::kStarted;
  }
  State predicted = state;
  predict(predicted, m.stamp_ns);
  const Matrix3d R = measurementNoise(params_, m);
  const Eigen::Vector3d innovation = m.p_WT_m - predicted.x.head<3>();
  const Matrix3d S = predicted.P.topLeftCorner<3, 3>() + R;
  const Eigen::LLT<Matrix3d> llt(S);
  const double mahalanobis_sq = innovation.dot(llt.solve(innovation));
  if (llt.info() != Eigen::Success || !(mahalanobis_sq <= params_.gate_chi2)) {
    // A run of rejected bearings cannot restart the filter: they carry no distance to start from.
    if (!m.bearingOnly() && extendTentative(state.tentative, m) >= params_.reinit_after_rejections) {
      start(state, m);
      return MeasurementVerdict::kStarted;
    }
    return MeasurementVerdict::kRejectedGate;  // state stays at its own time; prediction composes exactly
  }
  if (imm()) {
    // Each model updated on its own; its probability by the likelihood of its own innovation.
    double log_likelihood[2];
    for (int j = 0; j < 2; ++j) {
      Model& model = predicted.models[j];
      const Eigen::Vector3d nu = m.p_WT_m - model.x.head<3>();
      const Eigen::LLT<Matrix3d> llt_j(model.P.topLeftCorner<3, 3>() + R);
      if (llt_j.info() != Eigen::Success) return MeasurementVerdict::kRejectedInvalid;
      const Matrix3d L = llt_j.matrixL();
      log_likelihood[j] = -0.5 * nu.dot(llt_j.solve(nu)) - L.diagonal().array().log().sum();
      kalmanUpdate(model.x, model.P, nu, llt_j, R);
    }
    const double top = std::max(log_likelihood[0], log_likelihood[1]);
    double total = 0.0;
    for (int j = 0; j < 2; ++j) {
      predicted.models[j].probability *= std::exp(log_likelihood[j] - top);
      total += predicted.models[j].probability;
    }
    for (Model& model : predicted.models) model.probability = total > 0.0 ? model.probability / total : 0.5;
    combine(predicted);
  } else {
    kalmanUpdate(predicted.x, predicted.P, innovation, llt, R);
  }
  // A bearing does not keep the track alive: without a distance for lost_after_s the range is a guess.
  if (!m.bearingOnly()) predicted.last_accepted_ns = m.stamp_ns;
  predicted.tentative.count = 0;
  state = predicted;
  return MeasurementVerdict::kAccepted;
}

std::optional<double> TargetEstimator::mahalanobisSq(const TargetMeasurement& m) const {
  const std::optional<Fit> f = fit(m);
  if (!f) return std::nullopt;
  return f->d2;
}

std::optional<TargetEstimator::Fit> TargetEstimator::fit(const TargetMeasurement& m) const {
  const std::optional<Innovation> i = innovation(m);
  if (!i) return std::nullopt;
  const Eigen::LLT<Matrix3d> llt(i->S_m2);
  if (llt.info() != Eigen::Success) return std::nullopt;
  // ln|S| = 2 sum ln L_kk of S = L L^T, from the factor the distance needs anyway.
  const Matrix3d L = llt.matrixL();
  return Fit{i->nu_m.dot(llt.solve(i->nu_m)), 2.0 * L.diagonal().array().log().sum()};
}

std::optional<TargetEstimator::Fit> TargetEstimator::fitAcrossLine(const TargetMeasurement& m) const {
  if (!m.hasLineOfSight() || !(std::abs(m.bearing_W.norm() - 1.0) <= 1e-6)) return std::nullopt;
  const std::optional<Innovation> i = innovation(m);
  if (!i) return std::nullopt;
  const Eigen::Vector2d n(-m.bearing_W.y(), m.bearing_W.x());
  const double across_m = n.dot(i->nu_m.head<2>());
  const double s_m2 = n.dot(i->S_m2.topLeftCorner<2, 2>() * n);
  if (!(s_m2 > 0.0) || !std::isfinite(s_m2)) return std::nullopt;
  return Fit{across_m * across_m / s_m2, std::log(s_m2)};
}

std::optional<TargetEstimator::Innovation> TargetEstimator::innovation(const TargetMeasurement& m) const {
  if (!valid(m) || (folded_any_ && m.stamp_ns < folded_until_ns_)) return std::nullopt;
  // The state add() would update: after the newest buffered measurement at or before m's time.
  const auto after = std::upper_bound(buffer_.begin(), buffer_.end(), m.stamp_ns,
                                      [](rt::TimeNs t, const Entry& e) { return t < e.measurement.stamp_ns; });
  State state = after == buffer_.begin() ? anchor_ : std::prev(after)->after;
  if (!state.initialised) return std::nullopt;
  predict(state, m.stamp_ns);
  return Innovation{m.p_WT_m - state.x.head<3>(), state.P.topLeftCorner<3, 3>() + measurementNoise(params_, m)};
}

MeasurementVerdict TargetEstimator::add(const TargetMeasurement& m) {
  if (!valid(m)) {
    ++rejected_;
    return MeasurementVerdict::kRejectedInvalid;
  }
  const rt::DurationNs window_ns = rt::secondsToNs(params_.replay_window_s);
  if ((folded_any_ && m.stamp_ns < folded_until_ns_) ||
      (!buffer_.empty() && m.stamp_ns < buffer_.back().measurement.stamp_ns - window_ns)) {
    ++rejected_;
    return MeasurementVerdict::kRejectedTooOld;
  }
  // Make room: fold the oldest into the anchor (a measurement older than it is then too old).
  if (buffer_.size() == buffer_.capacity()) {
    anchor_ = buffer_.front().after;
    folded_any_ = true;
    folded_until_ns_ = buffer_.front().measurement.stamp_ns;
    buffer_.erase(buffer_.begin());
    if (m.stamp_ns < folded_until_ns_) {
      ++rejected_;
      return MeasurementVerdict::kRejectedTooOld;
    }
  }
  // Insert after the entries with the same or an earlier capture time, then re-run from there.
  const auto position = std::upper_bound(buffer_.begin(), buffer_.end(), m.stamp_ns,
                                         [](rt::TimeNs t, const Entry& e) { return t < e.measurement.stamp_ns; });
  const auto index = static_cast<std::size_t>(position - buffer_.begin());
  buffer_.insert(position, Entry{m, State{}, MeasurementVerdict::kAccepted});
  for (std::size_t i = index; i < buffer_.size(); ++i) {
    State state = i == 0 ? anchor_ : buffer_[i - 1].after;
    buffer_[i].verdict = step(state, buffer_[i].measurement);
    buffer_[i].after = state;
  }
  const MeasurementVerdict verdict = buffer_[index].verdict;
  if (verdict == MeasurementVerdict::kRejectedGate || verdict == MeasurementVerdict::kRejectedNoTrack) {
    ++rejected_;
  } else {
    ++accepted_;
  }
  // Fold the measurements that left the window into the anchor.
  const rt::TimeNs window_start_ns = buffer_.back().measurement.stamp_ns - window_ns;
  std::size_t fold = 0;
  while (fold + 1 < buffer_.size() && buffer_[fold].measurement.stamp_ns < window_start_ns) ++fold;
  if (fold > 0) {
    anchor_ = buffer_[fold - 1].after;
    folded_any_ = true;
    folded_until_ns_ = buffer_[fold - 1].measurement.stamp_ns;
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(fold));
  }
  return verdict;
}

TargetEstimate TargetEstimator::estimate(rt::TimeNs now_ns) const {
  State state = newest();
  TargetEstimate e;
  e.initialised = state.initialised;
  if (!state.initialised) {
    e.stamp_ns = now_ns;
    return e;
  }
  // Coasting with the probabilities held (hold_probabilities_coasting): without a measurement the chain would only
  // relax them to its stationary ones, and the covariance the planner and the gimbal read would grow as if a
  // manoeuvre were likelier than the measurements said (issue 21: the gimbal stopped looking at the prediction
  // sooner when the person turned a corner out of sight).
  predict(state, now_ns, !params_.hold_probabilities_coasting);
  e.stamp_ns = state.stamp_ns;
  e.p_WT_m = state.x.head<3>();
  e.v_WT_mps = state.x.tail<3>();
  e.covariance = state.P;
  e.manoeuvre_probability = imm() ? state.models[1].probability : 0.0;
  e.last_accepted_ns = state.last_accepted_ns;
  e.lost = now_ns - state.last_accepted_ns > rt::secondsToNs(params_.lost_after_s);
  return e;
}

}  // namespace aerotrack::estimation
