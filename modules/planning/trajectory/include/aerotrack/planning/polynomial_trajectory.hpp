// The optimiser's output as the trajectory server sees it: M quintic pieces in W, evaluated by time
// since the start. Immutable once published (shared by handle between the planning and trajectory-
// server threads); before that, assign() refills it reusing its storage, so a pool of these lets the
// planner publish without allocating (see planning_task.hpp).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "aerotrack/planning/min_jerk_spline.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::planning {

class PolynomialTrajectory final : public trajectory_server::Trajectory {
 public:
  /// Reserves storage for up to max_pieces pieces (more later allocates).
  explicit PolynomialTrajectory(int max_pieces = 0);

  /// Copies the spline's coefficients and durations.
  void assign(const MinJerkSpline& spline);
  /// Copies from coefficients (6M x 3, rows 6i..6i+5 = piece i) and durations (M).
  void assign(const RowMatrixX3d& coefficients, const Eigen::VectorXd& durations_s);
  /// Appends one piece after the last (coefficients in its own time, 0 .. duration_s). The caller keeps
  /// the junction continuous (e.g. a brake that starts from the end state).
  void append(const Eigen::Matrix<double, 6, 3>& coefficients, double duration_s);

  int pieces() const { return static_cast<int>(durations_s_.size()); }
  double pieceDurationS(int i) const { return durations_s_[static_cast<std::size_t>(i)]; }
  double durationS() const override { return total_s_; }
  trajectory_server::TrajectorySample sample(double t_s) const override;
  /// Derivative `order` (0 position .. 3 jerk) at t_s (clamped to [0, durationS()]).
  Eigen::Vector3d derivative(int order, double t_s) const;
  /// Pure time rescaling t -> factor * t (factor > 0): the same path in space, every duration times
  /// factor, so velocity scales with 1 / factor, acceleration 1 / factor^2, jerk 1 / factor^3 (c_k becomes
  /// c_k / factor^k). The start's velocity and acceleration scale too: see retimeKeepingStart for a
  /// hand-over that must stay smooth.
  void stretchTime(double factor);

 private:
  int locate(double& t_s) const;  // piece index of t_s; t_s becomes time within the piece

  std::vector<Eigen::Matrix<double, 6, 3>> coeffs_;
  std::vector<double> durations_s_;
  double total_s_ = 0.0;
};

/// Re-allocation of time (issue 21): the minimum-jerk spline through `in`'s junction positions with every
/// duration times `factor` (> 0), from `start` (kept exactly, so the hand-over from the trajectory being
/// flown stays continuous in p, v, a) to `in`'s end position with its end velocity / factor and
/// acceleration / factor^2. Away from the start the dynamics shrink about as a pure stretch's do; the path
/// between junctions may move slightly, so the result must be checked again (collision included).
/// `spline` is scratch. `out` may be `in`. False (out untouched) if the solve failed.
bool retimeKeepingStart(const PolynomialTrajectory& in, const StatePva& start, double factor, MinJerkSpline& spline,
                        PolynomialTrajectory& out);

}  // namespace aerotrack::planning
