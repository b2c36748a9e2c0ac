// One concrete trial of a scenario from its spec and a seed: random paths, forests, corridor
// walls and clutter, obstacle jitter, the turn side, the person's speed. Each random stream has
// its own generator seeded from (seed, stream), so changing one generator's use of random numbers
// leaves the others' results unchanged.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <unordered_map>
#include <vector>

#include "aerotrack/hal/sim/scenario.hpp"

namespace aerotrack::hal::sim {
namespace {

enum class Stream : std::uint64_t { kPath = 1, kSpeed, kMirror, kJitter, kForest, kClutter, kBehaviour };

/// SplitMix64 of (seed, stream): well-mixed, independent seeds for each stream.
std::mt19937_64 makeRng(std::uint64_t seed, Stream stream) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(stream) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return std::mt19937_64(z ^ (z >> 31));
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

/// Distance from p to the polyline (segments between consecutive points).
double distanceToPolyline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& line) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector2d& a = line[i];
    const Eigen::Vector2d ab = line[i + 1] - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - p).norm());
  }
  if (line.size() == 1) best = (p - line[0]).norm();
  return best;
}

std::vector<Eigen::Vector2d> pathPoints(const std::vector<PathPoint>& path) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(path.size());
  for (const PathPoint& p : path) out.push_back(p.p_W_m);
  return out;
}

bool insideRegion(const Eigen::Vector2d& p, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

rt::Expected<std::vector<PathPoint>> generatePath(const RandomPathGenerator& g, std::mt19937_64& rng) {
  const Eigen::Vector2d margin(1.0, 1.0);
  const Eigen::Vector2d lo = g.region_min_m + margin, hi = g.region_max_m - margin;
  if ((hi.array() <= lo.array()).any()) return rt::Error{"random_path: region is too small"};
  std::vector<PathPoint> path;
  Eigen::Vector2d p(uniform(rng, lo.x(), hi.x()), uniform(rng, lo.y(), hi.y()));
  // Start heading towards the region's centre so the first leg fits.
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  double heading = std::atan2(centre.y() - p.y(), centre.x() - p.x()) + uniform(rng, -0.5, 0.5);
  for (int leg = 0; leg < g.legs; ++leg) {
    bool placed = false;
    for (int attempt = 0; attempt < 100 && !placed; ++attempt) {
      const double turn = leg == 0 ? 0.0 : uniform(rng, -g.max_turn_rad, g.max_turn_rad);
      const double length = uniform(rng, g.leg_min_m, g.leg_max_m);
      const double h = heading + turn;
      const Eigen::Vector2d next = p + length * Eigen::Vector2d(std::cos(h), std::sin(h));
      if (!insideRegion(next, lo, hi)) continue;
      path.push_back({p, uniform(rng, g.speed_min_mps, g.speed_max_mps)});
      p = next;
      heading = h;
      placed = true;
    }
    if (!placed) {
      // Cornered: turn towards the centre, as a person at a fence would.
      heading = std::atan2(centre.y() - p.y(), centre.x() - p.x());
      --leg;
      if (path.size() > 10 * static_cast<std::size_t>(g.legs)) return rt::Error{"random_path: cannot place the legs"};
    }
  }
  path.push_back({p, 0.0});
  return path;
}

/// The random walk's behaviours (PathBehaviours): sprints, speed changes, pauses, reversals and
/// backward walks added to the legs of `in`. Every new point lies on the walk's polyline, so what
/// was cleared along the walk (trees) stays clear. Each leg draws the same eleven numbers whatever is
/// decided, so one probability's value does not shift the others' draws.
std::vector<PathPoint> applyBehaviours(const std::vector<PathPoint>& in, const PathBehaviours& b,
                                       std::mt19937_64& rng) {
  std::vector<PathPoint> out;
  double pause_at_start_s = in.front().pause_s;
  for (std::size_t i = 0; i + 1 < in.size(); ++i) {
    const bool sprint = uniform(rng, 0.0, 1.0) < b.sprint_probability;
    const double sprint_mps = uniform(rng, b.sprint_speed_min_mps, b.sprint_speed_max_mps);
    const bool change = uniform(rng, 0.0, 1.0) < b.speed_change_probability;
    const double change_at = uniform(rng, 0.3, 0.7);
    const double change_mps = uniform(rng, b.speed_change_min_mps, b.speed_change_max_mps);
    const bool pause = uniform(rng, 0.0, 1.0) < b.pause_probability;
    const double pause_s = uniform(rng, b.pause_min_s, b.pause_max_s);
    const bool reversal = uniform(rng, 0.0, 1.0) < b.reversal_probability;
    const double reversal_m = uniform(rng, b.reversal_min_m, b.reversal_max_m);
    const bool backwards = uniform(rng, 0.0, 1.0) < b.backwards_probability;
    const double backwards_mps = uniform(rng, b.backwards_speed_min_mps, b.backwards_speed_max_mps);

    PathPoint start = in[i];
    start.pause_s = pause_at_start_s;
    if (sprint) {
      start.speed_mps = sprint_mps;
      start.accel_mps2 = b.sprint_accel_mps2;
    }
    out.push_back(start);
    const Eigen::Vector2d leg = in[i + 1].p_W_m - start.p_W_m;
    if (change) {
      PathPoint mid = start;
      mid.p_W_m = start.p_W_m + change_at * leg;
      mid.pause_s = 0.0;
      mid.speed_mps = change_mps;
      out.push_back(mid);
    }
    pause_at_start_s = 0.0;
    if (i + 2 == in.size()) break;  // the last point is added below
    const double end_pause_s = pause ? pause_s : 0.0;
    if (!reversal) {
      pause_at_start_s = end_pause_s;
      continue;
    }
    // Pause (if drawn), walk back along the leg (turned round, or backwards facing on), then return.
    const double back_m = std::min(reversal_m, 0.8 * leg.norm());
    PathPoint end = out.back();
    end.p_W_m = in[i + 1].p_W_m;
    end.pause_s = end_pause_s;
    end.backwards = backwards;
    if (backwards) end.speed_mps = backwards_mps;
    out.push_back(end);
    PathPoint turn = out[out.size() - 2];
    turn.p_W_m = in[i + 1].p_W_m - back_m * leg.normalized();
    turn.pause_s = 0.0;
    turn.backwards = false;
    out.push_back(turn);
  }
  out.push_back(in.back());
  return out;
}

/// Trees by rejection sampling, kept clear of the person's path and the drone's start.
std::vector<Cylinder> generateForest(const ForestGenerator& f, const std::vector<Eigen::Vector2d>& path,
                                     const Eigen::Vector2d& drone_start_m, const std::vector<Cylinder>& existing,
                                     std::mt19937_64& rng) {
  const Eigen::Vector2d size = f.region_max_m - f.region_min_m;
  const auto target = static_cast<std::size_t>(std::llround(f.density_per_m2 * size.x() * size.y()));
  std::vector<Cylinder> trees;
  trees.reserve(target);
  // The trees placed so far in a grid of cells as wide as the farthest two trees can overlap from,
  // so a candidate is checked against its 3 x 3 cells, not every tree: linear in the trees, where
  // checking all of them was quadratic (a +-5000 m forest never finished). Same decisions, so the
  // same forest for a seed.
  const double cell_m = 2.0 * f.radius_max_m + f.min_gap_m;
  const auto cellOf = [&](const Eigen::Vector2d& c) {
    return Eigen::Vector2i(static_cast<int>(std::floor((c.x() - f.region_min_m.x()) / cell_m)),
                           static_cast<int>(std::floor((c.y() - f.region_min_m.y()) / cell_m)));
  };
  const auto key = [](int ix, int iy) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32U) | static_cast<std::uint32_t>(iy);
  };
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> grid;
  for (std::size_t attempt = 0; attempt < 50 * target && trees.size() < target; ++attempt) {
    const Eigen::Vector2d c(uniform(rng, f.region_min_m.x(), f.region_max_m.x()),
                            uniform(rng, f.region_min_m.y(), f.region_max_m.y()));
    const double r = uniform(rng, f.radius_min_m, f.radius_max_m);
    if (distanceToPolyline(c, path) < r + f.path_clearance_m) continue;
    if ((c - drone_start_m).norm() < r + f.path_clearance_m + 1.0) continue;
    const auto overlaps = [&](const Cylinder& t) { return (t.center_W_m - c).norm() < t.radius_m + r + f.min_gap_m; };
    const Eigen::Vector2i home = cellOf(c);
    bool blocked = std::any_of(existing.begin(), existing.end(), overlaps);
    for (int dx = -1; dx <= 1 && !blocked; ++dx) {
      for (int dy = -1; dy <= 1 && !blocked; ++dy) {
        const auto it = grid.find(key(home.x() + dx, home.y() + dy));
        if (it == grid.end()) continue;
        blocked = std::any_of(it->second.begin(), it->second.end(), [&](std::size_t i) { return overlaps(trees[i]); });
      }
    }
    if (blocked) continue;
    grid[key(home.x(), home.y())].push_back(trees.size());
    trees.push_back({c, r, 0.0, f.height_m});
  }
  return trees;
}

/// Walls around the centreline: cells of 0.1 m that are outside the corridor but within the wall
/// thickness of it, merged into boxes row by row (identical spans of consecutive rows merge).
std::vector<Box> generateCorridorWalls(const CorridorGenerator& c) {
  constexpr double kCell = 0.1;
  const double half = 0.5 * c.width_m;
  Eigen::Vector2d lo = c.centreline_m[0], hi = c.centreline_m[0];
  for (const auto& p : c.centreline_m) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double pad = half + c.wall_thickness_m + kCell;
  lo.array() -= pad;
  hi.array() += pad;
  const int nx = static_cast<int>(std::ceil((hi.x() - lo.x()) / kCell));
  const int ny = static_cast<int>(std::ceil((hi.y() - lo.y()) / kCell));
  // The centreline's two ends stay open: cells beyond an end (projection outside the segment)
  // are not walls, so the person can walk in and out.
  const auto isWall = [&](int ix, int iy) {
    const Eigen::Vector2d p = lo + kCell * Eigen::Vector2d(ix + 0.5, iy + 0.5);
    const double d = distanceToPolyline(p, c.centreline_m);
    if (d <= half || d > half + c.wall_thickness_m) return false;
    for (const std::size_t end : {std::size_t{0}, c.centreline_m.size() - 1}) {
      const std::size_t other = end == 0 ? 1 : end - 1;
      const Eigen::Vector2d dir = (c.centreline_m[end] - c.centreline_m[other]).normalized();
      if ((p - c.centreline_m[end]).dot(dir) > 0.0) return false;
    }
    return true;
  };
  struct Span {
    int x0, x1, y0, y1;
  };
  std::vector<Span> open, done;
  for (int iy = 0; iy < ny; ++iy) {
    std::vector<Span> row;
    for (int ix = 0; ix < nx; ++ix) {
      if (!isWall(ix, iy)) continue;
      if (!row.empty() && row.back().x1 == ix)
        row.back().x1 = ix + 1;
      else
        row.push_back({ix, ix + 1, iy, iy + 1});
    }
    std::vector<Span> next_open;
    for (Span s : row) {
      const auto match =
          std::find_if(open.begin(), open.end(), [&](const Span& o) { return o.x0 == s.x0 && o.x1 == s.x1; });
      if (match != open.end()) {
        s.y0 = match->y0;
        open.erase(match);
      }
      next_open.push_back(s);
    }
    done.insert(done.end(), open.begin(), open.end());
    open = std::move(next_open);
  }
  done.insert(done.end(), open.begin(), open.end());
  std::vector<Box> boxes;
  boxes.reserve(done.size());
  for (const Span& s : done)
    boxes.push_back({Eigen::Vector3d(lo.x() + s.x0 * kCell, lo.y() + s.y0 * kCell, 0.0),
                     Eigen::Vector3d(lo.x() + s.x1 * kCell, lo.y() + s.y1 * kCell, c.height_m)});
  return boxes;
}

/// Boxes against the corridor's walls (axis-aligned bounds of the placed rectangle).
std::vector<Box> generateClutter(const CorridorGenerator& c, const Eigen::Vector2d& keep_free_m, std::mt19937_64& rng) {
  std::vector<Box> boxes;
  const double half = 0.5 * c.width_m;
  for (int attempt = 0; attempt < 50 * c.clutter_count && static_cast<int>(boxes.size()) < c.clutter_count; ++attempt) {
    const auto seg = std::uniform_int_distribution<std::size_t>(0, c.centreline_m.size() - 2)(rng);
    const Eigen::Vector2d a = c.centreline_m[seg], b = c.centreline_m[seg + 1];
    const double len = (b - a).norm();
    const double length = uniform(rng, c.clutter_length_min_m, c.clutter_length_max_m);
    if (len < length + 2.0 * c.width_m) continue;  // keep corners free
    const Eigen::Vector2d dir = (b - a) / len, left(-dir.y(), dir.x());
    const double s = uniform(rng, c.width_m + 0.5 * length, len - c.width_m - 0.5 * length);
    const double side = std::bernoulli_distribution(0.5)(rng) ? 1.0 : -1.0;
    const double depth = uniform(rng, 0.2, c.clutter_depth_max_m);
    const Eigen::Vector2d centre = a + s * dir + side * (half - 0.5 * depth) * left;
    if ((centre - keep_free_m).norm() < 2.0) continue;
    const Eigen::Vector2d ext = 0.5 * length * dir.cwiseAbs() + 0.5 * depth * left.cwiseAbs();
    const Box box{Eigen::Vector3d(centre.x() - ext.x(), centre.y() - ext.y(), 0.0),
                  Eigen::Vector3d(centre.x() + ext.x(), centre.y() + ext.y(), c.clutter_height_m)};
    const auto overlaps = [&](const Box& o) {
      return (box.min_W_m.head<2>().array() < o.max_W_m.head<2>().array() + 0.3).all() &&
             (o.min_W_m.head<2>().array() < box.max_W_m.head<2>().array() + 0.3).all();
    };
    if (std::any_of(boxes.begin(), boxes.end(), overlaps)) continue;
    boxes.push_back(box);
  }
  return boxes;
}

void mirrorY(ScenarioSpec& s) {
  for (Box& b : s.boxes) {
    const double y0 = b.min_W_m.y();
    b.min_W_m.y() = -b.max_W_m.y();
    b.max_W_m.y() = -y0;
  }
  for (Cylinder& c : s.cylinders) c.center_W_m.y() = -c.center_W_m.y();
  for (PathPoint& p : s.path) p.p_W_m.y() = -p.p_W_m.y();
  s.drone.start_m.y() = -s.drone.start_m.y();
  s.drone.start_yaw_rad = -s.drone.start_yaw_rad;
  for (OdometryJump& j : s.odometry.drift.jumps) {  // the relocalisation errors mirror with the world
    j.dp_m.y() = -j.dp_m.y();
    j.dyaw_rad = -j.dyaw_rad;
  }
  if (s.wind) s.wind->mean_W_mps.y() = -s.wind->mean_W_mps.y();
  const double y0 = s.bounds_min_m.y();
  s.bounds_min_m.y() = -s.bounds_max_m.y();
  s.bounds_max_m.y() = -y0;
}

}  // namespace

rt::Expected<ScenarioInstance> instantiate(const ScenarioSpec& spec, std::uint64_t seed,
                                           std::optional<double> speed_override_mps) {
  ScenarioInstance inst;
  inst.seed = seed;
  inst.spec = spec;
  ScenarioSpec& s = inst.spec;

  if (s.random_path) {
    auto rng = makeRng(seed, Stream::kPath);
    auto path = generatePath(*s.random_path, rng);
    if (!path) return rt::Error{spec.source + ": " + path.error().message};
    s.path = std::move(path.value());
    if (s.random_path->behaviours) {
      auto behaviour_rng = makeRng(seed, Stream::kBehaviour);
      s.path = applyBehaviours(s.path, *s.random_path->behaviours, behaviour_rng);
    }
    s.random_path.reset();
  }
  auto speed_rng = makeRng(seed, Stream::kSpeed);
  inst.speed_scale =
      uniform(speed_rng, 1.0 - s.randomize.speed_jitter_fraction, 1.0 + s.randomize.speed_jitter_fraction);
  for (std::size_t i = 0; i + 1 < s.path.size(); ++i) {
    PathPoint& q = s.path[i];
    if (speed_override_mps && !q.backwards) q.speed_mps = *speed_override_mps;
    q.speed_mps *= inst.speed_scale;
    if (q.backwards) q.speed_mps = std::min(q.speed_mps, s.person.max_backward_speed_mps);
    if (!(s.path[i].speed_mps > 0.0)) return rt::Error{spec.source + ": person.path: every leg needs a speed > 0"};
  }

  if (s.randomize.obstacle_jitter_m > 0.0) {
    auto rng = makeRng(seed, Stream::kJitter);
    const double j = s.randomize.obstacle_jitter_m;
    for (Box& b : s.boxes) {
      const Eigen::Vector3d shift(uniform(rng, -j, j), uniform(rng, -j, j), 0.0);
      b.min_W_m += shift;
      b.max_W_m += shift;
    }
    for (Cylinder& c : s.cylinders) c.center_W_m += Eigen::Vector2d(uniform(rng, -j, j), uniform(rng, -j, j));
  }
  if (s.drone.start_behind_person_m) {
    const Eigen::Vector2d dir = (s.path[1].p_W_m - s.path[0].p_W_m).normalized();
    s.drone.start_m.head<2>() = s.path[0].p_W_m - *s.drone.start_behind_person_m * dir;
    s.drone.start_yaw_rad = std::atan2(dir.y(), dir.x());
    s.drone.start_behind_person_m.reset();
  }
  const std::vector<Eigen::Vector2d> path_xy = pathPoints(s.path);
  if (s.corridor) {
    auto rng = makeRng(seed, Stream::kClutter);
    for (const Box& b : generateCorridorWalls(*s.corridor)) s.boxes.push_back(b);
    for (const Box& b : generateClutter(*s.corridor, s.drone.start_m.head<2>(), rng)) s.boxes.push_back(b);
    s.corridor.reset();
  }
  if (s.forest) {
    auto rng = makeRng(seed, Stream::kForest);
    for (const Cylinder& c : generateForest(*s.forest, path_xy, s.drone.start_m.head<2>(), s.cylinders, rng))
      s.cylinders.push_back(c);
    s.forest.reset();
  }
  if (s.randomize.mirror_y) {
    auto rng = makeRng(seed, Stream::kMirror);
    inst.mirrored = std::bernoulli_distribution(0.5)(rng);
    if (inst.mirrored) mirrorY(s);
  }

  auto person = WalkingPerson::create(s.person, s.path);
  if (!person) return rt::Error{spec.source + ": person: " + person.error().message};
  inst.duration_s = std::min(s.max_duration_s, s.person_start_delay_s + person->durationS() + s.end_margin_s);
  auto bystanders =
      instantiateBystanders(s.bystanders, s.person, s.path, s.person_start_delay_s, s.drone.start_m.head<2>(),
                            inst.mirrored, s.boxes, s.cylinders, seed, inst.duration_s);
  if (!bystanders) return rt::Error{spec.source + ": " + bystanders.error().message};
  inst.bystanders = std::move(bystanders.value());
  return inst;
}

}  // namespace aerotrack::hal::sim
