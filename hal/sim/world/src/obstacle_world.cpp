// ObstacleWorld: validation, the 2D grid index, and the grid queries (see obstacle_world.hpp):
// the Amanatides & Woo (1987) grid walk for rays and segments, a ring search for distances.
// The per-obstacle tests are those of geometry.hpp.
#include "aerotrack/hal/sim/obstacle_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

namespace aerotrack::hal::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Footprints are registered in the cells they overlap after padding by this much, so that
/// rounding in the grid walk never skips a cell that touches an obstacle.
constexpr double kPadM = 1e-6;

std::string describe(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << '(' << v.x() << ", " << v.y() << ", " << v.z() << ')';
  return out.str();
}

rt::Status validateBox(const Box& b, std::size_t i) {
  if (!b.min_W_m.allFinite() || !b.max_W_m.allFinite()) {
    return rt::Error{"box " + std::to_string(i) + ": corners must be finite, got min " + describe(b.min_W_m) + " max " +
                     describe(b.max_W_m)};
  }
  if ((b.min_W_m.array() > b.max_W_m.array()).any()) {
    return rt::Error{"box " + std::to_string(i) + ": min_W_m " + describe(b.min_W_m) + " exceeds max_W_m " +
                     describe(b.max_W_m)};
  }
  return rt::ok();
}

rt::Status validateCylinder(const Cylinder& c, std::size_t i) {
  const std::string name = "cylinder " + std::to_string(i) + ": ";
  if (!c.center_W_m.allFinite() || !std::isfinite(c.z_min_m) || !std::isfinite(c.z_max_m)) {
    return rt::Error{name + "center_W_m, z_min_m and z_max_m must be finite"};
  }
  if (!(c.radius_m > 0.0) || !std::isfinite(c.radius_m)) {
    return rt::Error{name + "radius_m must be finite and > 0, got " + std::to_string(c.radius_m)};
  }
  if (c.z_min_m > c.z_max_m) {
    return rt::Error{name + "z_min_m " + std::to_string(c.z_min_m) + " exceeds z_max_m " + std::to_string(c.z_max_m)};
  }
  return rt::ok();
}

}  // namespace

rt::Expected<ObstacleWorld> ObstacleWorld::create(std::vector<Box> boxes, std::vector<Cylinder> cylinders,
                                                  double cell_size_m) {
  if (!(cell_size_m > 0.0) || !std::isfinite(cell_size_m)) {
    return rt::Error{"cell_size_m must be finite and > 0, got " + std::to_string(cell_size_m)};
  }
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (auto status = validateBox(boxes[i], i); !status) return status.error();
  }
  for (std::size_t i = 0; i < cylinders.size(); ++i) {
    if (auto status = validateCylinder(cylinders[i], i); !status) return status.error();
  }
  const std::size_t count = boxes.size() + cylinders.size();
  if (count >= std::numeric_limits<std::uint32_t>::max()) return rt::Error{"too many obstacles"};

  ObstacleWorld world;
  world.cell_size_m_ = cell_size_m;
  world.bounds_.min_W_m = Eigen::Vector3d::Constant(kInf);
  world.bounds_.max_W_m = Eigen::Vector3d::Constant(-kInf);
  for (const Box& b : boxes) {
    world.bounds_.min_W_m = world.bounds_.min_W_m.cwiseMin(b.min_W_m);
    world.bounds_.max_W_m = world.bounds_.max_W_m.cwiseMax(b.max_W_m);
  }
  for (const Cylinder& c : cylinders) {
    const Box b = boundingBox(c);
    world.bounds_.min_W_m = world.bounds_.min_W_m.cwiseMin(b.min_W_m);
    world.bounds_.max_W_m = world.bounds_.max_W_m.cwiseMax(b.max_W_m);
  }
  world.boxes_ = std::move(boxes);
  world.cylinders_ = std::move(cylinders);
  if (count == 0) return world;

  world.grid_min_W_m_ = world.bounds_.min_W_m.head<2>().array() - 2.0 * kPadM;
  const Eigen::Vector2d extent_m = world.bounds_.max_W_m.head<2>().array() + 2.0 * kPadM - world.grid_min_W_m_.array();
  const double nx = std::max(1.0, std::ceil(extent_m.x() / cell_size_m));
  const double ny = std::max(1.0, std::ceil(extent_m.y() / cell_size_m));
  if (nx * ny > static_cast<double>(kMaxCells)) {
    std::ostringstream out;
    out << "grid of " << nx << " x " << ny << " cells of " << cell_size_m << " m exceeds " << kMaxCells
        << " cells; use a larger cell_size_m";
    return rt::Error{out.str()};
  }
  world.nx_ = static_cast<int>(nx);
  world.ny_ = static_cast<int>(ny);

  // Cells overlapped by each obstacle's padded footprint; fn(cell) for each. Cylinders test the
  // disc against the cell rectangle, not just its bounding square.
  const auto forEachCell = [&world](std::uint32_t id, auto&& fn) {
    Eigen::Vector2d lo;
    Eigen::Vector2d hi;
    const Cylinder* cyl = nullptr;
    if (id < world.boxes_.size()) {
      lo = world.boxes_[id].min_W_m.head<2>();
      hi = world.boxes_[id].max_W_m.head<2>();
    } else {
      cyl = &world.cylinders_[id - world.boxes_.size()];
      lo = cyl->center_W_m.array() - cyl->radius_m;
      hi = cyl->center_W_m.array() + cyl->radius_m;
    }
    const double cs = world.cell_size_m_;
    const auto cellOf = [&](double x, double x0, int n) {
      return std::clamp(static_cast<int>(std::floor((x - x0) / cs)), 0, n - 1);
    };
    const int i0 = cellOf(lo.x() - kPadM, world.grid_min_W_m_.x(), world.nx_);
    const int i1 = cellOf(hi.x() + kPadM, world.grid_min_W_m_.x(), world.nx_);
    const int j0 = cellOf(lo.y() - kPadM, world.grid_min_W_m_.y(), world.ny_);
    const int j1 = cellOf(hi.y() + kPadM, world.grid_min_W_m_.y(), world.ny_);
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        if (cyl != nullptr) {
          const Eigen::Vector2d cell_lo = world.grid_min_W_m_ + cs * Eigen::Vector2d(i, j);
          const Eigen::Vector2d nearest =
              cyl->center_W_m.cwiseMax(cell_lo).cwiseMin(cell_lo + Eigen::Vector2d::Constant(cs));
          if ((nearest - cyl->center_W_m).norm() > cyl->radius_m + kPadM) continue;
        }
        fn(static_cast<std::size_t>(j) * static_cast<std::size_t>(world.nx_) + static_cast<std::size_t>(i));
      }
    }
  };

  const std::size_t cells = static_cast<std::size_t>(world.nx_) * static_cast<std::size_t>(world.ny_);
  std::vector<std::uint64_t> fill(cells + 1, 0);
  for (std::uint32_t id = 0; id < count; ++id) forEachCell(id, [&](std::size_t c) { ++fill[c + 1]; });
  for (std::size_t c = 0; c < cells; ++c) fill[c + 1] += fill[c];
  if (fill[cells] >= std::numeric_limits<std::uint32_t>::max()) {
    return rt::Error{"grid lists too many obstacle entries; use a larger cell_size_m"};
  }
  world.cell_begin_.assign(fill.begin(), fill.end());
  world.cell_items_.resize(fill[cells]);
  for (std::uint32_t id = 0; id < count; ++id) {
    forEachCell(id, [&](std::size_t c) { world.cell_items_[fill[c]++] = id; });
  }
  return world;
}

double ObstacleWorld::obstacleDistance(std::uint32_t id, const Eigen::Vector3d& p) const {
  if (id < boxes_.size()) return distanceTo(boxes_[id], p);
  return distanceTo(cylinders_[id - boxes_.size()], p);
}

std::optional<double> ObstacleWorld::castObstacles(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                                   double t_end) const {
  if (cell_items_.empty()) return std::nullopt;
  const double cs = cell_size_m_;
  const double gx0 = grid_min_W_m_.x();
  const double gy0 = grid_min_W_m_.y();
  const Ray ray(o, d);
  // Clip the ray to the grid's rectangle and the obstacles' height range.
  double t0 = 0.0;
  double t1 = t_end;
  if (!clipSlab(ray, 0, gx0, gx0 + nx_ * cs, t0, t1) || !clipSlab(ray, 1, gy0, gy0 + ny_ * cs, t0, t1) ||
      !clipSlab(ray, 2, bounds_.min_W_m.z(), bounds_.max_W_m.z(), t0, t1)) {
    return std::nullopt;
  }
  const auto n_boxes = static_cast<std::uint32_t>(boxes_.size());
  // Entry cell (clamped: rounding may put the entry point a hair outside the grid).
  int ix = std::clamp(static_cast<int>(std::floor((o.x() + t0 * d.x() - gx0) / cs)), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(std::floor((o.y() + t0 * d.y() - gy0) / cs)), 0, ny_ - 1);
  // Amanatides & Woo: t of the next x (y) cell boundary, and t between boundaries.
  int step_x = 0;
  int step_y = 0;
  double t_next_x = kInf;
  double t_next_y = kInf;
  double t_delta_x = kInf;
  double t_delta_y = kInf;
  if (d.x() > 0.0) {
    step_x = 1;
    t_next_x = (gx0 + (ix + 1) * cs - o.x()) / d.x();
    t_delta_x = cs / d.x();
  } else if (d.x() < 0.0) {
    step_x = -1;
    t_next_x = (gx0 + ix * cs - o.x()) / d.x();
    t_delta_x = -cs / d.x();
  }
  if (d.y() > 0.0) {
    step_y = 1;
    t_next_y = (gy0 + (iy + 1) * cs - o.y()) / d.y();
    t_delta_y = cs / d.y();
  } else if (d.y() < 0.0) {
    step_y = -1;
    t_next_y = (gy0 + iy * cs - o.y()) / d.y();
    t_delta_y = -cs / d.y();
  }

  double best = kInf;
  for (;;) {
    const std::size_t c = static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(ix);
    const double t_limit = std::min(best, t1);
    for (std::uint32_t k = cell_begin_[c]; k < cell_begin_[c + 1]; ++k) {
      const std::uint32_t id = cell_items_[k];
      const auto hit =
          id < n_boxes ? firstHit(boxes_[id], ray, t_limit) : firstHit(cylinders_[id - n_boxes], ray, t_limit);
      if (hit && *hit < best) best = *hit;
    }
    const double t_exit = std::min(t_next_x, t_next_y);
    if (best <= t_exit || t_exit >= t1) break;
    // Step along x or y; written without a branch on the (unpredictable) choice.
    const bool along_x = t_next_x < t_next_y;
    ix += along_x ? step_x : 0;
    iy += along_x ? 0 : step_y;
    t_next_x += along_x ? t_delta_x : 0.0;
    t_next_y += along_x ? 0.0 : t_delta_y;
    if (static_cast<unsigned>(ix) >= static_cast<unsigned>(nx_) ||
        static_cast<unsigned>(iy) >= static_cast<unsigned>(ny_)) {
      break;
    }
  }
  if (best == kInf) return std::nullopt;
  return best;
}

std::optional<double> ObstacleWorld::raycast(const Eigen::Vector3d& origin_W_m, const Eigen::Vector3d& dir_W,
                                             double max_range_m, bool hit_ground) const {
  if (!(max_range_m >= 0.0) || !origin_W_m.allFinite() || !dir_W.allFinite()) return std::nullopt;
  double t_end = max_range_m;
  std::optional<double> ground;
  if (hit_ground) {
    if (origin_W_m.z() <= 0.0) return 0.0;
    if (dir_W.z() < 0.0) {
      const double t_ground = origin_W_m.z() / -dir_W.z();
      if (t_ground <= t_end) {
        t_end = t_ground;
        ground = t_ground;
      }
    }
  }
  if (const auto hit = castObstacles(origin_W_m, dir_W, t_end)) return hit;
  return ground;
}

bool ObstacleWorld::segmentClear(const Eigen::Vector3d& a_W_m, const Eigen::Vector3d& b_W_m) const {
  if (!a_W_m.allFinite() || !b_W_m.allFinite()) return false;
  const Eigen::Vector3d ab = b_W_m - a_W_m;
  const double length_m = ab.norm();
  if (length_m == 0.0) return distance(a_W_m) > 0.0;
  return !castObstacles(a_W_m, ab / length_m, length_m).has_value();
}

double ObstacleWorld::distance(const Eigen::Vector3d& p_W_m) const {
  if (!p_W_m.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  if (cell_items_.empty()) return kInf;
  const double cs = cell_size_m_;
  // The grid cell nearest to p (p's own cell when p is over the grid); rings are centred on it.
  const auto nearestCell = [cs](double x, double x0, int n) {
    const double f = std::clamp(std::floor((x - x0) / cs), 0.0, static_cast<double>(n - 1));
    return static_cast<int>(f);
  };
  const int qi = nearestCell(p_W_m.x(), grid_min_W_m_.x(), nx_);
  const int qj = nearestCell(p_W_m.y(), grid_min_W_m_.y(), ny_);
  const double qx0 = grid_min_W_m_.x() + qi * cs;
  const double qy0 = grid_min_W_m_.y() + qj * cs;

  double best = kInf;
  const auto visit = [&](int i, int j) {
    const std::size_t c = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i);
    for (std::uint32_t k = cell_begin_[c]; k < cell_begin_[c + 1]; ++k) {
      best = std::min(best, obstacleDistance(cell_items_[k], p_W_m));
    }
  };
  for (int k = 0;; ++k) {
    if (k > 0) {
      // Every cell of ring k is at least k cells from q along x or y; its nearest point to p is
      // at least this far (sides of the ring outside the grid hold nothing and do not count).
      double bound = kInf;
      bool any = false;
      const double inner = (k - 1) * cs;
      const auto side = [&](bool exists, double gap_m) {
        if (!exists) return;
        bound = std::min(bound, std::max(0.0, gap_m));
        any = true;
      };
      side(qi + k < nx_, qx0 + cs + inner - p_W_m.x());
      side(qi - k >= 0, p_W_m.x() - (qx0 - inner));
      side(qj + k < ny_, qy0 + cs + inner - p_W_m.y());
      side(qj - k >= 0, p_W_m.y() - (qy0 - inner));
      if (!any || bound >= best) break;
    }
    const int i_lo = std::max(0, qi - k);
    const int i_hi = std::min(nx_ - 1, qi + k);
    for (const int j : {qj - k, qj + k}) {  // Bottom and top rows of the ring.
      if (j >= 0 && j < ny_) {
        for (int i = i_lo; i <= i_hi; ++i) visit(i, j);
      }
      if (k == 0) break;
    }
    if (k > 0) {
      const int j_lo = std::max(0, qj - k + 1);
      const int j_hi = std::min(ny_ - 1, qj + k - 1);
      for (const int i : {qi - k, qi + k}) {  // Left and right columns, corners excluded.
        if (i < 0 || i >= nx_) continue;
        for (int j = j_lo; j <= j_hi; ++j) visit(i, j);
      }
    }
    if (best == 0.0) break;
  }
  return best;
}

}  // namespace aerotrack::hal::sim
