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

 private:
  int locate(double& t_s) const;  // piece index of t_s; t_s becomes time within the piece

  std::vector<Eigen::Matrix<double, 6, 3>> coeffs_;
  std::vector<double> durations_s_;
  double total_s_ = 0.0;
};

}  // namespace aerotrack::planning
