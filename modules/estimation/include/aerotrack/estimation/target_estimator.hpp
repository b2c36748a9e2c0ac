// TargetEstimator: the followed person's position and velocity in the world, p_WT and v_WT, with
// covariance, from the localization's single-frame positions (issue 6, item 5; the paper's
// Sect. IV-B output p_t^w feeds its prediction, Sect. V). A Kalman filter with a constant-velocity
// model: state [p_WT; v_WT] (metres, m/s; W world ENU), continuous white-noise acceleration with
// separate horizontal and vertical spectral densities, so that over dt the process noise per axis
// is q [dt^3/3, dt^2/2; dt^2/2, dt]. Measurements are 3D positions with their own or a default
// noise; the update uses the Joseph form.
//  - Gating: a measurement whose squared Mahalanobis distance to the prediction exceeds
//    gate_chi2 is rejected (a jump the person cannot make: a wrong detection, a bystander). After
//    reinit_after_rejections rejections in a row that agree with one another the filter restarts at
//    the newest measurement (it had lost the person, not the detector). Agreement is a tentative track
//    (M-of-N confirmation, Bar-Shalom et al. Sect. 3.6 on track initiation): each rejected position
//    that the tentative track's gate admits extends it, one it refuses starts it anew. A detector
//    returning garbage (issue 23's fault matrix: positions scattered over metres) restarted the
//    filter at its eighth rejection in a row, 1.8 m off; scattered positions never agree.
//  - Latency: each measurement is applied at its capture time. The estimator keeps the last
//    replay_window_s of measurements with the filter state after each; a late (out-of-sequence)
//    measurement is inserted in time order and the filter is re-run from the state before it, so
//    the estimate is exactly the one it would be had the measurement arrived on time.
//  - Manoeuvres (issue 21): with manoeuvre_accel_psd_xy_m2ps3 > 0 the filter is an interacting
//    multiple model (IMM; Blom and Bar-Shalom 1988; Bar-Shalom, Li and Kirubarajan, "Estimation with
//    Applications to Tracking and Navigation", Sect. 11.6): two constant-velocity models, a steady one
//    (accel_psd) and a manoeuvring one (manoeuvre_accel_psd), switching as a two-state Markov chain with
//    mean sojourn times steady_mean_s and manoeuvre_mean_s (transition probabilities over any dt from the
//    chain's exact solution). Why: one noise level either lags a runner who brakes (0.8 m/s behind at
//    3 m/s^2, and the drone overran them) or passes a walker's measurement noise to the drone. The
//    estimate, its covariance and the gate are the models' mixture.
//  - Dropouts: estimate(now) predicts from the newest state to now (covariance grows);
//    `lost` once no measurement was accepted for lost_after_s; the next measurement restarts it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/rt/bitwise_copyable.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::estimation {

struct TargetEstimatorParams {
  /// Spectral density of the white acceleration noise, horizontal (x, y) and vertical (z), in
  /// m^2/s^3: about (typical acceleration)^2 x (its duration). > 0.
  double accel_psd_xy_m2ps3 = 0.4;
  double accel_psd_z_m2ps3 = 0.05;
  /// Default measurement noise (standard deviation per axis), metres, used when a measurement
  /// carries none; > 0.
  double measurement_std_xy_m = 0.15;
  double measurement_std_z_m = 0.3;
  double initial_speed_std_mps = 1.5;  ///< Velocity uncertainty at (re)start, per axis; > 0.
  /// Rejection threshold on the squared Mahalanobis distance (3 degrees of freedom): 16.27 is the
  /// chi-square 99.9% quantile. > 0.
  double gate_chi2 = 16.27;
  int reinit_after_rejections = 8;  ///< Consecutive rejections, agreeing with one another, that restart it; >= 1.
  double lost_after_s = 1.0;        ///< No accepted measurement for this long: lost; > 0.
  /// Out-of-sequence window: measurements older than the newest minus this are refused; > 0.
  double replay_window_s = 0.5;
  std::size_t max_buffered_measurements = 64;  ///< Buffer size (allocated once); >= 2.
  /// The manoeuvring model's horizontal spectral density (m^2/s^3); 0: off (one constant-velocity
  /// model); else > accel_psd_xy_m2ps3.
  double manoeuvre_accel_psd_xy_m2ps3 = 0.0;
  double steady_mean_s = 5.0;     ///< Mean time between manoeuvres (the chain's sojourn in steady); > 0.
  double manoeuvre_mean_s = 1.5;  ///< Mean length of a manoeuvre; > 0.
  /// estimate() past the newest measurement (coasting) holds the models' probabilities at the newest
  /// measurement's instead of letting the chain relax them (each model still predicted on its own). The
  /// filter's own steps and the gate (mahalanobisSq) always use the chain.
  bool hold_probabilities_coasting = true;
};

/// Ok if every field is in its documented range; the error names the field.
rt::Status validate(const TargetEstimatorParams& params);

/// Reads the estimator's config section: every field of TargetEstimatorParams by its name, all
/// required (accel_psd_xy_m2ps3, accel_psd_z_m2ps3, measurement_std_xy_m, measurement_std_z_m,
/// initial_speed_std_mps, gate_chi2, reinit_after_rejections, lost_after_s, replay_window_s,
/// max_buffered_measurements, manoeuvre_accel_psd_xy_m2ps3, steady_mean_s, manoeuvre_mean_s,
/// hold_probabilities_coasting). Throws rt::ConfigError naming the key (use inside rt::parseConfig).
TargetEstimatorParams parseTargetEstimatorParams(const rt::ConfigNode& node);

/// One localized position of the person.
struct TargetMeasurement {
  rt::TimeNs stamp_ns = 0;                           ///< Capture time of the image.
  Eigen::Vector3d p_WT_m = Eigen::Vector3d::Zero();  ///< Position in W, metres.
  double std_xy_m = 0.0;                             ///< Noise per horizontal axis, metres; 0: the params' default.
  double std_z_m = 0.0;                              ///< Noise vertically, metres; 0: the params' default.
  /// A bearing-only measurement (a torso too cut off for a distance, issue 22): p_WT_m lies on the line
  /// of sight at an assumed range, and along this horizontal unit direction (the line of sight) the
  /// noise is range_std_m instead of std_xy_m. Zero: an ordinary measurement. A bearing neither starts
  /// the filter nor keeps it from being lost (it carries no distance).
  Eigen::Vector2d bearing_W = Eigen::Vector2d::Zero();
  double range_std_m = 0.0;
  /// With bearing_W: the distance along the line of sight was measured (the depth camera, depth_range.hpp), to
  /// range_std_m; an ordinary measurement whose noise differs along and across the line of sight.
  bool ranged = false;
  bool hasLineOfSight() const { return !(bearing_W.x() == 0.0 && bearing_W.y() == 0.0); }  // NaN: a (bad) one
  bool bearingOnly() const { return hasLineOfSight() && !ranged; }
};

enum class MeasurementVerdict : std::uint8_t {
  kAccepted,         ///< Used in a Kalman update.
  kStarted,          ///< (Re)started the filter: first measurement, after `lost`, or after repeated rejections.
  kRejectedGate,     ///< Outside the Mahalanobis gate.
  kRejectedTooOld,   ///< Older than the replay window (or than the state folded out of it).
  kRejectedInvalid,  ///< Non-finite position or negative noise, or a bearing that is not a unit vector.
  kRejectedNoTrack,  ///< A bearing-only measurement with no live track to give it a distance.
};
const char* toString(MeasurementVerdict verdict);

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Another person near the followed one, as their own track estimates them (BystanderTracks): an obstacle
/// that moves, which the planner keeps away from along its constant-velocity prediction (issue 21 item 5: the
/// crowd's people walked into the drone's path faster than the map showed them there).
struct OtherPerson {
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();
};

/// The most other people an estimate carries (the target task tracks as many: target_task.hpp).
inline constexpr std::size_t kMaxOtherPeople = 12;

struct TargetEstimate {
  rt::TimeNs stamp_ns = 0;   ///< The time the estimate is for.
  bool initialised = false;  ///< False: no measurement yet; the rest is meaningless.
  bool lost = true;          ///< No accepted measurement for lost_after_s (or never).
  Eigen::Vector3d p_WT_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_WT_mps = Eigen::Vector3d::Zero();
  Matrix6d covariance = Matrix6d::Identity();  ///< Of [p_WT_m; v_WT_mps] (m^2, m^2/s, m^2/s^2).
  double manoeuvre_probability = 0.0;          ///< The IMM's weight on the manoeuvring model (0 when off).
  rt::TimeNs last_accepted_ns = 0;             ///< Capture time of the newest accepted measurement.
  /// The other people tracked and not lost, at stamp_ns (the first other_count; filled by the target task).
  std::array<OtherPerson, kMaxOtherPeople> others{};
  std::size_t other_count = 0;
};

/// Thread safety: none (one owner). Allocation: the buffer, once, in create(); add() and
/// estimate() never allocate.
class TargetEstimator {
 public:
  static rt::Expected<TargetEstimator> create(const TargetEstimatorParams& params);

  /// Applies a measurement at its capture time (re-running the newer ones if it is late). Returns
  /// the verdict at the time of the call (a later out-of-sequence arrival may change the verdicts
  /// of the measurements after it, exactly as if they had arrived in order).
  /// Cost: O(measurements after it in the window).
  MeasurementVerdict add(const TargetMeasurement& measurement);

  /// The state predicted to now_ns from the newest state (now_ns before it: the newest state
  /// itself, stamped with its own time). `lost` is judged at now_ns.
  TargetEstimate estimate(rt::TimeNs now_ns) const;

  /// The squared Mahalanobis distance of the measurement from the state it would update (the state at its
  /// capture time, as add() would compute it), the quantity add() compares with gate_chi2; nothing if the
  /// filter has not started, or the measurement is invalid or older than the window. Whether the track is
  /// lost is the caller's concern (the distance is then measured against the prediction's grown
  /// covariance: where the person can have gone since). Allocation-free.
  std::optional<double> mahalanobisSq(const TargetMeasurement& measurement) const;

  /// The innovation behind mahalanobisSq: the measurement's position minus the prediction, and its covariance (the
  /// prediction's plus the measurement's noise). Nothing where mahalanobisSq gives nothing.
  struct Innovation {
    Eigen::Vector3d nu_m = Eigen::Vector3d::Zero();
    Eigen::Matrix3d S_m2 = Eigen::Matrix3d::Identity();
  };
  std::optional<Innovation> innovation(const TargetMeasurement& measurement) const;

  /// mahalanobisSq with the log-determinant of the innovation's covariance (S in m^2): d2 + ln|S| is twice the
  /// measurement's negative log-likelihood under this track, up to a constant -- the generalised distance of
  /// global-nearest-neighbour assignment (Blackman and Popoli, Sect. 6.4), which compares tracks of unlike
  /// covariance fairly: d2 alone favours the wider one. Nothing where mahalanobisSq gives nothing.
  struct Fit {
    double d2 = 0.0;
    double log_det_S = 0.0;
  };
  std::optional<Fit> fit(const TargetMeasurement& measurement) const;
  /// fit() of a bearing's line of sight across it on the ground plane alone: the innovation's component along the
  /// horizontal normal n of bearing_W, d2 = (n . nu)^2 / (n^T S n) and ln(n^T S n). Along the line a bearing says
  /// nothing (its noise there is range_std_m), and its height is the followed track's prediction, while a track fed
  /// by the depth camera carries no height (a 100 m spread in z): the 3-D ln|S| of such a track says how little is
  /// known of its height, not whether the bearing is theirs. Nothing where fit() gives nothing, or bearing_W is not
  /// a horizontal unit vector.
  std::optional<Fit> fitAcrossLine(const TargetMeasurement& measurement) const;

  /// Forgets everything (the buffer keeps its memory).
  void reset();

  std::uint64_t acceptedCount() const { return accepted_; }
  std::uint64_t rejectedCount() const { return rejected_; }
  const TargetEstimatorParams& params() const { return params_; }

 private:
  /// One model of the IMM: its state, covariance and probability.
  struct Model {
    Vector6d x = Vector6d::Zero();
    Matrix6d P = Matrix6d::Identity();
    double probability = 0.0;
  };
  struct State {
    bool initialised = false;
    rt::TimeNs stamp_ns = 0;
    Vector6d x = Vector6d::Zero();      ///< The models' mixture (the only model when the IMM is off).
    Matrix6d P = Matrix6d::Identity();  ///< Its covariance, spread of the models included.
    std::array<Model, 2> models;        ///< [0] steady, [1] manoeuvring; unused when the IMM is off.
    rt::TimeNs last_accepted_ns = 0;
    /// The rejected positions' own constant-velocity track (steady model), and how many in a row it holds.
    struct Tentative {
      Vector6d x = Vector6d::Zero();
      Matrix6d P = Matrix6d::Identity();
      rt::TimeNs stamp_ns = 0;
      int count = 0;
    } tentative;
  };
  struct Entry {
    TargetMeasurement measurement;
    State after;
    MeasurementVerdict verdict = MeasurementVerdict::kAccepted;
  };

  explicit TargetEstimator(const TargetEstimatorParams& params);
  /// The filter step: state (at or before m's time) and m -> the state at m's time.
  MeasurementVerdict step(State& state, const TargetMeasurement& m) const;
  void start(State& state, const TargetMeasurement& m) const;
  /// Position and velocity at a (re)start from m: m's position, zero velocity, their covariance.
  void startAt(const TargetMeasurement& m, Vector6d& x, Matrix6d& P) const;
  /// Adds a rejected position to the tentative track (or starts it anew); how many in a row it holds.
  int extendTentative(State::Tentative& tentative, const TargetMeasurement& m) const;
  /// Predicts to t_ns; with the IMM, transitions=false skips the chain's mixing (the probabilities held).
  void predict(State& state, rt::TimeNs t_ns, bool transitions = true) const;
  bool imm() const { return params_.manoeuvre_accel_psd_xy_m2ps3 > 0.0; }
  /// Predicts one constant-velocity state over dt with horizontal spectral density q_xy.
  void predictModel(Vector6d& x, Matrix6d& P, double dt_s, double q_xy) const;
  /// The models' mixture with these weights: mean, and covariance with their spread.
  static void mixture(const std::array<Model, 2>& models, const std::array<double, 2>& weights, Vector6d& x,
                      Matrix6d& P);
  /// The IMM's output: state.x and state.P, the models' mixture by their probabilities.
  static void combine(State& state);
  const State& newest() const { return buffer_.empty() ? anchor_ : buffer_.back().after; }

  TargetEstimatorParams params_;
  State anchor_;                    ///< The state after the measurements folded out of the buffer.
  std::vector<Entry> buffer_;       ///< Measurements in the replay window, in capture-time order.
  bool folded_any_ = false;         ///< Some measurement was folded into anchor_.
  rt::TimeNs folded_until_ns_ = 0;  ///< Capture time of the newest folded measurement: older ones are refused.
  std::uint64_t accepted_ = 0;
  std::uint64_t rejected_ = 0;
};

}  // namespace aerotrack::estimation

// A TargetEstimate travels through rt::LatestSlot: its Eigen members are fixed-size arrays of
// doubles (see rt/bitwise_copyable.hpp).
static_assert(std::is_standard_layout_v<aerotrack::estimation::TargetEstimate>);
template <>
struct aerotrack::rt::IsBitwiseCopyable<aerotrack::estimation::TargetEstimate> : std::true_type {};
