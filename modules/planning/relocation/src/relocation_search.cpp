// The search pattern of a relocation: see relocation_search.hpp.
#include "aerotrack/planning/relocation_search.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

namespace aerotrack::planning {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Less unseen mass than this in sight is nothing to fly for.
constexpr double kMinMass = 1e-3;
// A new best viewpoint replaces the current one only if it scores this much better (no dithering).
constexpr double kSwitchGain = 1.2;
// The person's own speed may exceed the plausible maximum: the reach grows at least this much faster.
constexpr double kLastSpeedMargin = 1.2;
// Samples per belief cell (centre and four quarter points, at two heights) of the grid's raw occupancy.
constexpr double kBlockSampleHeightsM[] = {0.5, 1.1};

}  // namespace

const rt::FieldTable<RelocationSearchParams>& relocationSearchFields() {
  using P = RelocationSearchParams;
  using rt::Range;
  static const rt::FieldTable<P> kTable(
      {
          rt::number("cell_m", &P::cell_m, Range::closed(0.1, 5.0)),
          rt::number("max_radius_m", &P::max_radius_m, Range::closed(1.0, 50.0)),
          rt::number("max_person_speed_mps", &P::max_person_speed_mps, Range::closed(0.1, 15.0)),
          rt::number("heading_concentration", &P::heading_concentration, Range::closed(0.0, 20.0)),
          rt::number("camera_range_m", &P::camera_range_m, Range::closed(0.5, 100.0)),
          rt::number("full_look_s", &P::full_look_s, Range::closed(0.01, 60.0)),
          rt::number("clearance_m", &P::clearance_m, Range::closed(0.0, 5.0)),
          rt::number("travel_speed_mps", &P::travel_speed_mps, Range::closed(0.1, 20.0)),
          rt::number("reselect_s", &P::reselect_s, Range::closed(0.05, 60.0)),
          rt::number("reached_m", &P::reached_m, Range::closed(0.05, 10.0)),
          rt::integer("viewpoint_bearings", &P::viewpoint_bearings, 1, 72),
          rt::numberList("viewpoint_radii_m", &P::viewpoint_radii_m, 3, Range::closed(0.1, 50.0)),
      },
      {{"max_radius_m", "must be > cell_m", [](const P& p) { return p.max_radius_m > p.cell_m; }}});
  return kTable;
}

rt::Status validate(const RelocationSearchParams& params) {
  return relocationSearchFields().validate(params);
}

rt::Expected<RelocationSearch> RelocationSearch::create(const RelocationSearchParams& params, double sight_height_m,
                                                        double flight_altitude_m) {
  if (rt::Status s = validate(params); !s) return rt::Error{"relocation: " + s.error().message};
  if (!(sight_height_m > 0.0) || !(flight_altitude_m > 0.0))
    return rt::Error{"relocation: sight height and flight altitude must be > 0"};
  return RelocationSearch(params, sight_height_m, flight_altitude_m);
}

RelocationSearch::RelocationSearch(const RelocationSearchParams& params, double sight_height_m,
                                   double flight_altitude_m)
    : params_(params), sight_height_m_(sight_height_m), flight_altitude_m_(flight_altitude_m) {
  side_ = 2 * static_cast<int>(std::ceil(params.max_radius_m / params.cell_m)) + 1;
  const auto cells = static_cast<std::size_t>(side_) * static_cast<std::size_t>(side_);
  weight_.assign(cells, 0.0);
  seen_s_.assign(cells, 0.0);
  distance_m_.assign(cells, kInfinity);
  blocked_.assign(cells, 0);
  heap_.reserve(8 * cells + 1);
  abandoned_W_m_.fill(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  candidates_.reserve(2 * params.viewpoint_radii_m.size() * static_cast<std::size_t>(params.viewpoint_bearings));
}

void RelocationSearch::start(const Eigen::Vector3d& p_WT_m, const Eigen::Vector3d& v_WT_mps, rt::TimeNs lost_ns) {
  active_ = true;
  p_last_W_m_ = Eigen::Vector3d(p_WT_m.x(), p_WT_m.y(), sight_height_m_);
  v_last_W_mps_ = Eigen::Vector3d(v_WT_mps.x(), v_WT_mps.y(), 0.0);
  lost_ns_ = lost_ns;
  last_update_ns_ = -1;
  reach_m_ = 0.0;
  std::fill(weight_.begin(), weight_.end(), 0.0);
  std::fill(seen_s_.begin(), seen_s_.end(), 0.0);
  std::fill(distance_m_.begin(), distance_m_.end(), kInfinity);
  current_.reset();
  chosen_ns_ = 0;
  abandoned_W_m_.fill(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  abandoned_next_ = 0;
}

Eigen::Vector3d RelocationSearch::cellCenterM(std::size_t cell) const {
  const int half = side_ / 2;
  const int ix = static_cast<int>(cell % static_cast<std::size_t>(side_)) - half;
  const int iy = static_cast<int>(cell / static_cast<std::size_t>(side_)) - half;
  return {p_last_W_m_.x() + ix * params_.cell_m, p_last_W_m_.y() + iy * params_.cell_m, sight_height_m_};
}

double RelocationSearch::seenFraction(std::size_t cell) const {
  return std::min(1.0, seen_s_[cell] / params_.full_look_s);
}

double RelocationSearch::totalUnseenMass() const {
  double total = 0.0;
  for (std::size_t c = 0; c < weight_.size(); ++c) total += unseenMass(c);
  return total;
}

bool RelocationSearch::cellBlocked(const mapping::LocalGrid& grid, const Eigen::Vector3d& centre_W_m) const {
  // Every map cell under the belief cell, at each height: a wall's mapped surface is one map cell thick.
  const double step_m = grid.params().resolution_m;
  const int per_side = std::max(1, static_cast<int>(std::ceil(params_.cell_m / step_m)));
  const double first_m = -0.5 * params_.cell_m + 0.5 * step_m;
  for (const double z : kBlockSampleHeightsM) {
    for (int j = 0; j < per_side; ++j) {
      for (int i = 0; i < per_side; ++i) {
        const Eigen::Vector3d p(centre_W_m.x() + first_m + i * step_m, centre_W_m.y() + first_m + j * step_m, z);
        if (grid.state(p) == mapping::CellState::kOccupied) return true;
      }
    }
  }
  return false;
}

void RelocationSearch::updateBelief(const mapping::LocalGrid& grid, rt::TimeNs now_ns) {
  const double t_s = std::max(0.0, rt::nsToSeconds(now_ns - lost_ns_));
  const double speed_mps = v_last_W_mps_.norm();
  reach_m_ = std::max(params_.cell_m, std::max(params_.max_person_speed_mps, kLastSpeedMargin * speed_mps) * t_s);
  const std::size_t cells = weight_.size();
  for (std::size_t c = 0; c < cells; ++c) {
    blocked_[c] = cellBlocked(grid, cellCenterM(c)) ? 1 : 0;
    distance_m_[c] = kInfinity;
  }
  // Walking distance from the last position: 8-connected Dijkstra, no corner cutting, up to the reach.
  const int half = side_ / 2;
  const auto source = static_cast<std::size_t>(half) * static_cast<std::size_t>(side_) + static_cast<std::size_t>(half);
  blocked_[source] = 0;  // the person stood there
  distance_m_[source] = 0.0;
  heap_.clear();
  heap_.emplace_back(0.0, static_cast<int>(source));
  const auto greater = std::greater<std::pair<double, int>>();
  const double diagonal_m = params_.cell_m * std::sqrt(2.0);
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), greater);
    const auto [d, cell] = heap_.back();
    heap_.pop_back();
    if (d > distance_m_[static_cast<std::size_t>(cell)]) continue;
    const int x = cell % side_;
    const int y = cell / side_;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const int nx = x + dx;
        const int ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= side_ || ny >= side_) continue;
        const std::size_t next = cellAt(nx, ny);
        if (blocked_[next] != 0) continue;
        if (dx != 0 && dy != 0 && (blocked_[cellAt(nx, y)] != 0 || blocked_[cellAt(x, ny)] != 0)) continue;
        const double nd = d + (dx != 0 && dy != 0 ? diagonal_m : params_.cell_m);
        if (nd > reach_m_ || nd >= distance_m_[next]) continue;
        distance_m_[next] = nd;
        heap_.emplace_back(nd, static_cast<int>(next));
        std::push_heap(heap_.begin(), heap_.end(), greater);
      }
    }
  }
  // The prior: along the last velocity, at the distance it would have carried the person.
  const double kappa = speed_mps > 1e-3 ? params_.heading_concentration * std::min(speed_mps, 1.0) : 0.0;
  const double expected_m = speed_mps * t_s;
  const double sigma_m = std::max(1.0, expected_m / 2.0);
  double total = 0.0;
  for (std::size_t c = 0; c < cells; ++c) {
    if (!std::isfinite(distance_m_[c])) {
      weight_[c] = 0.0;
      continue;
    }
    const Eigen::Vector3d offset = cellCenterM(c) - p_last_W_m_;
    const double r_m = offset.head<2>().norm();
    const double cos_bearing =
        r_m > 1e-9 && kappa > 0.0 ? offset.head<2>().dot(v_last_W_mps_.head<2>()) / (r_m * speed_mps) : 1.0;
    const double radial = (distance_m_[c] - expected_m) / sigma_m;
    weight_[c] = std::exp(kappa * (cos_bearing - 1.0) - 0.5 * radial * radial);
    total += weight_[c];
  }
  if (total > 0.0) {
    for (double& w : weight_) w /= total;
  }
}

void RelocationSearch::look(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_WC_m, double dt_s) {
  if (!(dt_s > 0.0)) return;
  const double range2 = params_.camera_range_m * params_.camera_range_m;
  for (std::size_t c = 0; c < weight_.size(); ++c) {
    if (unseenMass(c) < kNegligibleMass) continue;
    const Eigen::Vector3d centre = cellCenterM(c);
    if ((centre - p_WC_m).head<2>().squaredNorm() > range2) continue;
    if (grid.lineOfSight(p_WC_m, centre)) seen_s_[c] += dt_s;
  }
}

double RelocationSearch::visibleMass(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_WC_m,
                                     Eigen::Vector3d& look_W_m) const {
  const double range2 = params_.camera_range_m * params_.camera_range_m;
  double mass = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t c = 0; c < weight_.size(); ++c) {
    const double m = unseenMass(c);
    if (m < kNegligibleMass) continue;
    const Eigen::Vector3d centre = cellCenterM(c);
    if ((centre - p_WC_m).head<2>().squaredNorm() > range2) continue;
    if (!grid.lineOfSight(p_WC_m, centre)) continue;
    mass += m;
    sum += m * centre;
  }
  look_W_m = mass > 0.0 ? Eigen::Vector3d(sum / mass) : p_last_W_m_;
  return mass;
}

Eigen::Vector3d RelocationSearch::unseenCentroid() const {
  double mass = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t c = 0; c < weight_.size(); ++c) {
    const double m = unseenMass(c);
    mass += m;
    sum += m * cellCenterM(c);
  }
  return mass > 0.0 ? Eigen::Vector3d(sum / mass) : p_last_W_m_;
}

bool RelocationSearch::viewpointFree(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_W_m,
                                     const Eigen::Vector3d& p_WB_m) const {
  // Known free (seen by the depth camera), or unknown but in plain sight of the drone: the unknown inside of a
  // building lies behind its mapped walls, while open air at the flight altitude stays unknown where the depth
  // camera's level rays found nothing to hit (no return: no free space is carved; corner_hide, issue 21). The
  // planner checks the way there against the map as it fills, and an unreached viewpoint is abandoned.
  if (!grid.isFree(p_W_m) && (grid.isOccupied(p_W_m) || !grid.inWindow(p_W_m) || !grid.lineOfSight(p_WB_m, p_W_m)))
    return false;
  for (const Eigen::Vector3d& tabu : abandoned_W_m_) {
    if ((tabu - p_W_m).head<2>().norm() < params_.reached_m) return false;
  }
  if (!(params_.clearance_m > 0.0)) return true;
  constexpr int kDirections = 8;
  for (int k = 0; k < kDirections; ++k) {
    const double a = 2.0 * std::numbers::pi * k / kDirections;
    const Eigen::Vector3d p = p_W_m + params_.clearance_m * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
    if (grid.isOccupied(p)) return false;
  }
  return true;
}

void RelocationSearch::makeCandidates(const mapping::LocalGrid& grid, const Eigen::Vector3d& centre_W_m,
                                      const Eigen::Vector3d& p_WB_m) {
  candidates_.clear();
  for (const Eigen::Vector3d& centre : {centre_W_m, p_last_W_m_}) {
    for (const double r_m : params_.viewpoint_radii_m) {
      for (int k = 0; k < params_.viewpoint_bearings; ++k) {
        const double a = 2.0 * std::numbers::pi * k / params_.viewpoint_bearings;
        const Eigen::Vector3d p(centre.x() + r_m * std::cos(a), centre.y() + r_m * std::sin(a), flight_altitude_m_);
        if (viewpointFree(grid, p, p_WB_m)) candidates_.push_back(p);
      }
    }
  }
}

std::optional<Viewpoint> RelocationSearch::bestViewpoint(const mapping::LocalGrid& grid,
                                                         const Eigen::Vector3d& p_WB_m) const {
  std::optional<Viewpoint> best;
  for (const Eigen::Vector3d& p : candidates_) {
    Viewpoint v;
    v.p_W_m = p;
    v.mass = visibleMass(grid, p, v.look_W_m);
    if (v.mass < kMinMass) continue;
    v.score = v.mass / ((p - p_WB_m).norm() / params_.travel_speed_mps + params_.full_look_s);
    if (!best || v.score > best->score) best = v;
  }
  return best;
}

std::optional<Viewpoint> RelocationSearch::update(const mapping::LocalGrid& grid, const Eigen::Vector3d& p_WC_m,
                                                  rt::TimeNs now_ns) {
  if (!active_) return std::nullopt;
  updateBelief(grid, now_ns);
  const double dt_s = last_update_ns_ < 0 ? 0.0 : std::min(0.5, rt::nsToSeconds(now_ns - last_update_ns_));
  last_update_ns_ = now_ns;
  look(grid, p_WC_m, dt_s);
  const bool reached = current_ && (current_->p_W_m - p_WC_m).head<2>().norm() < params_.reached_m;
  // Not reached in twice the time it should take (the planner cannot get there): never chosen again.
  if (current_ && !reached && rt::nsToSeconds(now_ns - heading_since_ns_) > give_up_s_) {
    abandoned_W_m_[abandoned_next_++ % abandoned_W_m_.size()] = current_->p_W_m;
    current_.reset();
  }
  const bool stale = !current_ || rt::nsToSeconds(now_ns - chosen_ns_) >= params_.reselect_s;
  if (!reached && !stale) return current_;
  chosen_ns_ = now_ns;
  makeCandidates(grid, unseenCentroid(), p_WC_m);
  std::optional<Viewpoint> best = bestViewpoint(grid, p_WC_m);
  if (current_ && !reached) {  // keep the current one unless clearly beaten (or nothing is left to see from it)
    Viewpoint kept = *current_;
    kept.mass = visibleMass(grid, kept.p_W_m, kept.look_W_m);
    kept.score = kept.mass / ((kept.p_W_m - p_WC_m).norm() / params_.travel_speed_mps + params_.full_look_s);
    if (kept.mass >= kMinMass && viewpointFree(grid, kept.p_W_m, p_WC_m) &&
        (!best || kSwitchGain * kept.score >= best->score))
      best = kept;
  }
  if (best && (!current_ || best->p_W_m != current_->p_W_m)) {  // a new goal: its time to get there starts
    heading_since_ns_ = now_ns;
    give_up_s_ = 2.0 * ((best->p_W_m - p_WC_m).norm() / params_.travel_speed_mps) + params_.full_look_s;
  }
  current_ = best;
  return current_;
}

}  // namespace aerotrack::planning
