#include "aerotrack/hal/sim/give_way.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "aerotrack/hal/sim/bystanders.hpp"

namespace aerotrack::hal::sim {

namespace {

/// Where a walker's body meets low obstacles (benches): the height bystander paths are checked at.
constexpr double kLegsHeightM = 0.3;
constexpr std::size_t kMaxSamples = 1'000'000;

/// The least a >= 0 with |d + a n| >= D (n a unit vector, |d| < D): the larger root of a^2 + 2 a (d.n) + |d|^2 - D^2.
double stepNeeded(const Eigen::Vector2d& d, const Eigen::Vector2d& n, double min_distance_m) {
  const double along = d.dot(n);
  const double slack = min_distance_m * min_distance_m - d.squaredNorm();
  if (!(slack > 0.0)) return 0.0;
  return -along + std::sqrt(along * along + slack);
}

}  // namespace

rt::Expected<GiveWay> GiveWay::compute(const WalkingPerson& person, double person_delay_s, const WalkingPerson& walker,
                                       double walker_delay_s, const ObstacleWorld& world, const GiveWayParams& params) {
  const auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  if (!positive(params.min_distance_m) || !positive(params.step_speed_mps) || !positive(params.sample_s) ||
      !positive(params.horizon_s) || !std::isfinite(person_delay_s) || !std::isfinite(walker_delay_s))
    return rt::Error{"give way: every parameter must be finite, distances, speed, sample and horizon > 0"};
  if (params.horizon_s / params.sample_s >= static_cast<double>(kMaxSamples))
    return rt::Error{"give way: horizon_s / sample_s must stay below " + std::to_string(kMaxSamples)};
  const auto count = static_cast<std::size_t>(std::floor(params.horizon_s / params.sample_s)) + 1;
  GiveWay g;
  g.sample_s_ = params.sample_s;
  g.offsets_m_.assign(count, Eigen::Vector2d::Zero());
  std::vector<Eigen::Vector2d> walker_m(count), apart_m(count);  // the walker's place, and from the person to them
  for (std::size_t k = 0; k < count; ++k) {
    const double t_s = static_cast<double>(k) * params.sample_s;
    walker_m[k] = walker.state(t_s - walker_delay_s).p_W_m.head<2>();
    apart_m[k] = walker_m[k] - person.state(t_s - person_delay_s).p_W_m.head<2>();
  }
  const double D = params.min_distance_m;
  const double slope_m = params.step_speed_mps * params.sample_s;  // the most the step changes in one sample
  std::vector<double> step_m(count);
  for (std::size_t begin = 0; begin < count;) {
    if (!(apart_m[begin].norm() < D)) {
      ++begin;
      continue;
    }
    std::size_t end = begin;  // one encounter: [begin, end)
    std::size_t closest = begin;
    while (end < count && apart_m[end].norm() < D) {
      if (apart_m[end].norm() < apart_m[closest].norm()) closest = end;
      ++end;
    }
    ++g.encounters_;
    // Sideways to their relative motion, away from the person at the closest approach (the least step that keeps
    // a passing walker out); straight through them, to the left of that motion; walking together (no relative
    // motion), straight away from them.
    const std::size_t before = closest > 0 ? closest - 1 : closest;
    const std::size_t after = closest + 1 < count ? closest + 1 : closest;
    const Eigen::Vector2d relative = apart_m[after] - apart_m[before];
    Eigen::Vector2d away = apart_m[closest];
    if (relative.norm() > 1e-9) {
      const Eigen::Vector2d left = Eigen::Vector2d(-relative.y(), relative.x()).normalized();
      away = left.dot(away) * left;
      if (away.norm() < 1e-6) away = left;
    }
    if (away.norm() > 1e-9) {
      away.normalize();
    } else {
      const double heading = walker.state(static_cast<double>(closest) * params.sample_s - walker_delay_s).heading_rad;
      away = Eigen::Vector2d(-std::sin(heading), std::cos(heading));
    }
    const auto clear = [&](const Eigen::Vector2d& n) {
      const Eigen::Vector2d p = walker_m[closest] + stepNeeded(apart_m[closest], n, D) * n;
      return world.distance(Eigen::Vector3d(p.x(), p.y(), kLegsHeightM)) > kPersonBodyRadiusM;
    };
    const Eigen::Vector2d n = clear(away) || !clear(-away) ? away : Eigen::Vector2d(-away);
    // The required steps, then the least envelope above them whose slope stays within step_speed_mps (a forward
    // and a backward pass): the walker drifts aside ahead of the meeting and back after it.
    std::fill(step_m.begin(), step_m.end(), 0.0);
    for (std::size_t k = begin; k < end; ++k) step_m[k] = stepNeeded(apart_m[k], n, D);
    for (std::size_t k = 1; k < count; ++k) step_m[k] = std::max(step_m[k], step_m[k - 1] - slope_m);
    for (std::size_t k = count - 1; k-- > 0;) step_m[k] = std::max(step_m[k], step_m[k + 1] - slope_m);
    for (std::size_t k = 0; k < count; ++k) g.offsets_m_[k] += step_m[k] * n;
    begin = end;
  }
  return g;
}

Eigen::Vector2d GiveWay::offsetM(double t_s) const {
  if (offsets_m_.empty() || !(t_s > 0.0)) return offsets_m_.empty() ? Eigen::Vector2d::Zero() : offsets_m_.front();
  const double x = t_s / sample_s_;
  const auto k = static_cast<std::size_t>(std::min(std::floor(x), static_cast<double>(offsets_m_.size() - 1)));
  if (k + 1 >= offsets_m_.size()) return offsets_m_.back();
  const double f = x - static_cast<double>(k);
  return (1.0 - f) * offsets_m_[k] + f * offsets_m_[k + 1];
}

Eigen::Vector2d GiveWay::rateMps(double t_s) const {
  if (offsets_m_.size() < 2 || !(t_s >= 0.0)) return Eigen::Vector2d::Zero();
  const double x = t_s / sample_s_;
  if (x >= static_cast<double>(offsets_m_.size() - 1)) return Eigen::Vector2d::Zero();
  const auto k = static_cast<std::size_t>(std::floor(x));
  return (offsets_m_[k + 1] - offsets_m_[k]) / sample_s_;
}

PersonState withOffset(PersonState state, const GiveWay& give_way, double t_s) {
  const Eigen::Vector2d offset_m = give_way.offsetM(t_s);
  if (offset_m.isZero()) return state;
  const Eigen::Vector3d shift_m(offset_m.x(), offset_m.y(), 0.0);
  state.p_W_m += shift_m;
  for (Eigen::Vector3d& k : state.keypoints_W_m) k += shift_m;
  const Eigen::Vector2d rate = give_way.rateMps(t_s);
  state.v_W_mps.head<2>() += rate;
  state.speed_mps = state.v_W_mps.head<2>().norm();
  return state;
}

}  // namespace aerotrack::hal::sim
