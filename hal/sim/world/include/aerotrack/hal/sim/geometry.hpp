// The simulator's obstacle primitives and their exact single-object queries, shared by the
// ObstacleWorld's grid queries and the depth camera's renderer: axis-aligned boxes (walls,
// buildings) and vertical cylinders (trees, poles), both closed solids.
// Ray/box: the slab test (Kay & Kajiya, SIGGRAPH 1986). Ray/cylinder: the numerically stable
// quadratic (roots q/a and c/q) for the infinite vertical cylinder, intersected with the z slab
// of its caps. Point distance: a box's nearest point is the clamped point; a solid cylinder is a
// disc times an interval, so its distance combines the radial and the axial excess.
// All functions are pure, inline, allocation-free and thread-safe.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include <Eigen/Core>

namespace aerotrack::hal::sim {

/// Solid axis-aligned box in the world frame W (ENU, z up); a wall is a thin box.
struct Box {
  Eigen::Vector3d min_W_m = Eigen::Vector3d::Zero();  ///< Lower corner.
  Eigen::Vector3d max_W_m = Eigen::Vector3d::Zero();  ///< Upper corner, >= min_W_m per axis.
};

/// Solid vertical cylinder (tree trunk, pole) in W: the disc |xy - center| <= radius swept from
/// z_min to z_max, caps included.
struct Cylinder {
  Eigen::Vector2d center_W_m = Eigen::Vector2d::Zero();  ///< Axis position (x, y).
  double radius_m = 0.0;                                 ///< > 0.
  double z_min_m = 0.0;                                  ///< Bottom cap height.
  double z_max_m = 0.0;                                  ///< Top cap height, >= z_min_m.
};

/// The ray origin_W_m + t * dir_W, t >= 0 (t in metres when dir_W is unit length), with what
/// every primitive test needs precomputed once.
struct Ray {
  Ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir)
      : origin_W_m(origin),
        dir_W(dir),
        inv_dir_W(dir.cwiseInverse()),
        dir_xy_sq(dir.x() * dir.x() + dir.y() * dir.y()) {}
  Eigen::Vector3d origin_W_m;
  Eigen::Vector3d dir_W;
  Eigen::Vector3d inv_dir_W;  ///< 1 / dir_W per axis (unused where dir_W is 0).
  double dir_xy_sq;           ///< |dir_W.xy|^2.
};

/// Narrows [t0, t1] to the ts where the ray lies within [lo, hi] along axis k (0, 1, 2); false
/// if that leaves nothing. A ray parallel to the slab keeps [t0, t1] when it starts inside.
inline bool clipSlab(const Ray& ray, int k, double lo, double hi, double& t0, double& t1) {
  if (ray.dir_W[k] == 0.0) return ray.origin_W_m[k] >= lo && ray.origin_W_m[k] <= hi;
  double ta = (lo - ray.origin_W_m[k]) * ray.inv_dir_W[k];
  double tb = (hi - ray.origin_W_m[k]) * ray.inv_dir_W[k];
  if (ta > tb) std::swap(ta, tb);
  t0 = std::max(t0, ta);
  t1 = std::min(t1, tb);
  return t0 <= t1;
}

/// Smallest t in [0, t_max] where the ray meets the closed box (0 if it starts inside or on it).
inline std::optional<double> firstHit(const Box& box, const Ray& ray, double t_max) {
  double t0 = 0.0;
  double t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    if (!clipSlab(ray, k, box.min_W_m[k], box.max_W_m[k], t0, t1)) return std::nullopt;
  }
  return t0;
}

/// Smallest t in [0, t_max] where the ray meets the closed cylinder (0 if it starts inside or
/// on it). The side is tested first: it rejects most candidates cheaply.
inline std::optional<double> firstHit(const Cylinder& cyl, const Ray& ray, double t_max) {
  const double ox = ray.origin_W_m.x() - cyl.center_W_m.x();
  const double oy = ray.origin_W_m.y() - cyl.center_W_m.y();
  const double c = ox * ox + oy * oy - cyl.radius_m * cyl.radius_m;  // > 0: origin outside the side
  double t0 = 0.0;
  double t1 = t_max;
  if (ray.dir_xy_sq == 0.0) {  // Vertical ray: within the disc for all t, or never.
    if (c > 0.0) return std::nullopt;
  } else {
    const double b = ox * ray.dir_W.x() + oy * ray.dir_W.y();  // Half the linear coefficient.
    if (c > 0.0 && b >= 0.0) return std::nullopt;              // Outside and not approaching.
    const double disc = b * b - ray.dir_xy_sq * c;
    if (disc < 0.0) return std::nullopt;
    // Roots of a t^2 + 2 b t + c = 0 without cancellation: q / a and c / q.
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    double ta = 0.0;
    double tb = 0.0;
    if (q != 0.0) {  // q == 0 only when b == 0 and c == 0: touching at t = 0.
      ta = q / ray.dir_xy_sq;
      tb = c / q;
      if (ta > tb) std::swap(ta, tb);
    }
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return std::nullopt;
  }
  if (!clipSlab(ray, 2, cyl.z_min_m, cyl.z_max_m, t0, t1)) return std::nullopt;
  return t0;
}

/// Euclidean distance in metres from p_W_m to the closed box (0 inside or on it).
inline double distanceTo(const Box& box, const Eigen::Vector3d& p_W_m) {
  return (box.min_W_m - p_W_m).cwiseMax(p_W_m - box.max_W_m).cwiseMax(0.0).norm();
}

/// Euclidean distance in metres from p_W_m to the closed cylinder (0 inside or on it), exact at
/// the side, the caps and the rims.
inline double distanceTo(const Cylinder& cyl, const Eigen::Vector3d& p_W_m) {
  const double radial = std::max((p_W_m.head<2>() - cyl.center_W_m).norm() - cyl.radius_m, 0.0);
  const double axial = std::max({cyl.z_min_m - p_W_m.z(), p_W_m.z() - cyl.z_max_m, 0.0});
  return std::hypot(radial, axial);
}

/// Axis-aligned bounding box of a cylinder.
inline Box boundingBox(const Cylinder& cyl) {
  return Box{Eigen::Vector3d(cyl.center_W_m.x() - cyl.radius_m, cyl.center_W_m.y() - cyl.radius_m, cyl.z_min_m),
             Eigen::Vector3d(cyl.center_W_m.x() + cyl.radius_m, cyl.center_W_m.y() + cyl.radius_m, cyl.z_max_m)};
}

}  // namespace aerotrack::hal::sim
