// Bystanders: parsing, appearance signatures and per-seed generation. See bystanders.hpp.
#include "aerotrack/hal/sim/bystanders.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/rt/config_node.hpp"

namespace aerotrack::hal::sim {
namespace {

using rt::ConfigNode;

constexpr double kMinSpeedMps = 0.1;  ///< Bystander speeds are in [kMinSpeedMps, kMaxSpeedMps].
constexpr double kMaxSpeedMps = 3.0;  ///< Brisk walking to a jog.
constexpr double kBystanderCoordMaxM = 1e5;
/// The bystander-generation stream, apart from instantiate()'s streams (1..6) and any added later.
constexpr std::uint64_t kBystanderStream = 0xB75;
/// Listed and generated paths must keep the legs (this high above the ground) out of obstacles.
constexpr double kPathCheckHeightM = 0.3;

std::mt19937_64 bystanderRng(std::uint64_t seed) {
  // SplitMix64 of (seed, stream), like instantiate()'s makeRng.
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ULL + kBystanderStream * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return std::mt19937_64(z ^ (z >> 31));
}

double uniformIn(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

Eigen::Vector2d vec2Of(const ConfigNode& n, const std::string& key, double lo = -kBystanderCoordMaxM,
                       double hi = kBystanderCoordMaxM) {
  const auto v = n.getDoubleList(key, 2, lo, hi);
  return {v[0], v[1]};
}

Eigen::Vector2d rangeOf(const ConfigNode& n, const std::string& key, double lo, double hi) {
  Eigen::Vector2d r = vec2Of(n, key, lo, hi);
  if (r.y() < r.x()) n.fail(key, "expected [min, max] with min <= max");
  return r;
}

Clothing parseClothing(const ConfigNode& n) {
  Clothing c;
  c.hue_deg = n.getDouble("hue_deg", 0.0, 360.0);
  c.saturation = n.getDouble("saturation", 0.0, 1.0);
  c.second_hue_deg = n.getDoubleOr("second_hue_deg", c.hue_deg, 0.0, 360.0);
  c.second_saturation = n.getDoubleOr("second_saturation", c.saturation, 0.0, 1.0);
  c.second_share = n.getDoubleOr("second_share", 0.3, 0.0, 1.0);
  c.grey_share = n.getDoubleOr("grey_share", 0.2, 0.0, 0.95);
  c.grey_value = n.getDoubleOr("grey_value", c.grey_value, 0.0, 1.0);
  c.legs_hue_deg = n.getDoubleOr("legs_hue_deg", c.legs_hue_deg, 0.0, 360.0);
  c.legs_saturation = n.getDoubleOr("legs_saturation", c.legs_saturation, 0.0, 1.0);
  c.legs_grey_share = n.getDoubleOr("legs_grey_share", c.legs_grey_share, 0.0, 1.0);
  c.legs_grey_value = n.getDoubleOr("legs_grey_value", c.legs_grey_value, 0.0, 1.0);
  n.finish();
  return c;
}

BystanderWalk parseWalk(const ConfigNode& n) {
  BystanderWalk w;
  w.region_min_m = vec2Of(n, "region_min_m");
  w.region_max_m = vec2Of(n, "region_max_m");
  if ((w.region_max_m.array() <= w.region_min_m.array() + 2.0).any())
    n.fail("region_max_m", "must exceed region_min_m by more than 2 m (a 1 m margin inside each side)");
  w.legs = n.getIntOr("legs", w.legs, 1, 1000);
  const Eigen::Vector2d leg = n.has("leg_m") ? rangeOf(n, "leg_m", 0.5, 1000.0) : Eigen::Vector2d(3.0, 8.0);
  w.leg_min_m = leg.x();
  w.leg_max_m = leg.y();
  const Eigen::Vector2d speed =
      n.has("speed_mps") ? rangeOf(n, "speed_mps", kMinSpeedMps, kMaxSpeedMps) : Eigen::Vector2d(0.8, 1.5);
  w.speed_min_mps = speed.x();
  w.speed_max_mps = speed.y();
  w.pause_max_s = n.getDoubleOr("pause_max_s", 0.0, 0.0, 600.0);
  return w;
}

/// A path given point by point ({p_m, speed_mps, pause_s}), checked against the listed obstacles.
std::vector<PathPoint> parseBystanderPath(const ConfigNode& n, const ObstacleWorld& world) {
  std::vector<PathPoint> path;
  for (const ConfigNode& p : n.childList("path")) {
    PathPoint point;
    point.p_W_m = vec2Of(p, "p_m");
    point.speed_mps = p.getDoubleOr("speed_mps", 1.3, kMinSpeedMps, kMaxSpeedMps);
    point.pause_s = p.getDoubleOr("pause_s", 0.0, 0.0, 600.0);
    p.finish();
    const Eigen::Vector3d here(point.p_W_m.x(), point.p_W_m.y(), kPathCheckHeightM);
    if (world.distance(here) <= 0.0) p.fail("p_m", "lies inside an obstacle");
    if (!path.empty()) {
      const Eigen::Vector3d prev(path.back().p_W_m.x(), path.back().p_W_m.y(), kPathCheckHeightM);
      if (!world.segmentClear(prev, here)) p.fail("p_m", "the leg to this point passes through an obstacle");
    }
    path.push_back(point);
  }
  if (path.empty()) n.fail("path", "needs at least one point");
  return path;
}

void parseHeight(const ConfigNode& n, double& height_m, double& torso_m) {
  height_m = n.getDoubleOr("height_m", height_m, 1.0, 2.5);
  torso_m = n.getDoubleOr("torso_m", 0.2857 * height_m, 0.2, 1.0);  // Drillis & Contini: 0.504 / 1.75
  if (torso_m < 0.2 * height_m || torso_m > 0.4 * height_m) n.fail("torso_m", "must be in [0.2, 0.4] x height_m");
}

BystanderSpec parseBystander(const ConfigNode& n, const ObstacleWorld& world) {
  BystanderSpec b;
  if (n.has("path")) b.path = parseBystanderPath(n, world);
  if (n.has("random_walk")) {
    const ConfigNode w = n.child("random_walk");
    b.walk = parseWalk(w);
    w.finish();
  }
  if (b.path.empty() == !b.walk.has_value()) n.fail("path", "give exactly one of path or random_walk");
  b.start_delay_s = n.getDoubleOr("start_delay_s", 0.0, 0.0, 3600.0);
  parseHeight(n, b.height_m, b.torso_m);
  if (n.has("clothing")) b.clothing = parseClothing(n.child("clothing"));
  b.look_alike = n.getBoolOr("look_alike", false);
  n.finish();
  return b;
}

CrossingGenerator parseCrossing(const ConfigNode& n) {
  CrossingGenerator c;
  if (n.has("at_s")) c.at_s = n.getDoubleList("at_s", 0, 0.0, 3600.0);
  c.count = n.getIntOr("count", 0, 0, 1000);
  if (n.has("window_s")) c.window_s = rangeOf(n, "window_s", 0.0, 3600.0);
  if (c.count > 0 && !n.has("window_s")) n.fail("window_s", "count needs window_s: [from, to] seconds");
  if (c.at_s.empty() && c.count == 0) n.fail("at_s", "give at_s (times) or count and window_s");
  c.behind_m = n.getDoubleOr("behind_m", c.behind_m, 0.0, 20.0);
  c.half_width_m = n.getDoubleOr("half_width_m", c.half_width_m, 1.0, 50.0);
  c.speed_mps = n.getDoubleOr("speed_mps", c.speed_mps, kMinSpeedMps, kMaxSpeedMps);
  c.look_alike = n.getBoolOr("look_alike", false);
  n.finish();
  return c;
}

AlongsideGenerator parseAlongside(const ConfigNode& n) {
  AlongsideGenerator a;
  a.from_s = n.getDouble("from_s", 0.0, 3600.0);
  a.to_s = n.getDouble("to_s", 0.0, 3600.0);
  if (a.to_s <= a.from_s + 1.0) n.fail("to_s", "must exceed from_s by more than 1 s");
  a.offset_m = n.getDoubleOr("offset_m", a.offset_m, 0.6, 10.0);
  const std::string side = n.has("side") ? n.getEnum("side", {"left", "right", "random"}) : "random";
  a.side = side == "left" ? 1 : side == "right" ? -1 : 0;
  a.look_alike = n.getBoolOr("look_alike", false);
  n.finish();
  return a;
}

GroupGenerator parseGroup(const ConfigNode& n) {
  GroupGenerator g;
  g.at_s = n.getDouble("at_s", 0.0, 3600.0);
  g.count = n.getInt("count", 0, 100);
  g.radius_m = n.getDoubleOr("radius_m", g.radius_m, 0.5, 50.0);
  g.path_clearance_m = n.getDoubleOr("path_clearance_m", g.path_clearance_m, 0.5, 10.0);
  if (g.path_clearance_m + 0.3 > g.radius_m) n.fail("radius_m", "must exceed path_clearance_m by 0.3 m");
  g.milling = n.getBoolOr("milling", false);
  g.look_alikes = n.getIntOr("look_alikes", 0, 0, 100);
  if (g.look_alikes > g.count) n.fail("look_alikes", "cannot exceed count");
  n.finish();
  return g;
}

RandomWalkersGenerator parseRandomWalkers(const ConfigNode& n) {
  RandomWalkersGenerator r;
  r.count = n.getInt("count", 0, 1000);
  r.walk = parseWalk(n);
  if (n.has("start_delay_s")) r.start_delay_s = rangeOf(n, "start_delay_s", 0.0, 3600.0);
  n.finish();
  return r;
}

// ---- Generation ----

double distanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double distanceToPath(const Eigen::Vector2d& p, const std::vector<PathPoint>& path) {
  if (path.size() == 1) return (p - path[0].p_W_m).norm();
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < path.size(); ++i)
    best = std::min(best, distanceToSegment(p, path[i].p_W_m, path[i + 1].p_W_m));
  return best;
}

Eigen::Vector3d atLegs(const Eigen::Vector2d& p) {
  return {p.x(), p.y(), kPathCheckHeightM};
}

/// The path stays out of the obstacles, its body (kPersonBodyRadiusM) included at the points.
bool pathClear(const std::vector<PathPoint>& path, const ObstacleWorld& world) {
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (world.distance(atLegs(path[i].p_W_m)) <= kPersonBodyRadiusM) return false;
    if (i > 0 && !world.segmentClear(atLegs(path[i - 1].p_W_m), atLegs(path[i].p_W_m))) return false;
  }
  return true;
}

rt::Expected<std::vector<PathPoint>> randomWalk(const BystanderWalk& w, const ObstacleWorld& world,
                                                std::mt19937_64& rng) {
  const Eigen::Vector2d lo = w.region_min_m + Eigen::Vector2d(1.0, 1.0);
  const Eigen::Vector2d hi = w.region_max_m - Eigen::Vector2d(1.0, 1.0);
  const auto inside = [&](const Eigen::Vector2d& p) {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  };
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  bool started = false;
  for (int attempt = 0; attempt < 200 && !started; ++attempt) {
    p = Eigen::Vector2d(uniformIn(rng, lo.x(), hi.x()), uniformIn(rng, lo.y(), hi.y()));
    started = world.distance(atLegs(p)) > kPersonBodyRadiusM + 0.2;
  }
  if (!started) return rt::Error{"random walk: no free start point in the region"};
  std::vector<PathPoint> path;
  double heading = uniformIn(rng, -std::numbers::pi, std::numbers::pi);
  for (int leg = 0; leg < w.legs; ++leg) {
    bool placed = false;
    for (int attempt = 0; attempt < 100 && !placed; ++attempt) {
      // The first leg any way; later ones turn by up to 100 deg, and any way once cornered.
      const double spread = attempt < 50 ? (leg == 0 ? std::numbers::pi : 1.75) : std::numbers::pi;
      const double h = heading + uniformIn(rng, -spread, spread);
      const Eigen::Vector2d next =
          p + uniformIn(rng, w.leg_min_m, w.leg_max_m) * Eigen::Vector2d(std::cos(h), std::sin(h));
      if (!inside(next) || world.distance(atLegs(next)) <= kPersonBodyRadiusM + 0.2 ||
          !world.segmentClear(atLegs(p), atLegs(next)))
        continue;
      path.push_back({p, uniformIn(rng, w.speed_min_mps, w.speed_max_mps),
                      path.empty() ? 0.0 : uniformIn(rng, 0.0, w.pause_max_s)});
      p = next;
      heading = h;
      placed = true;
    }
    if (!placed) break;  // Hemmed in: a shorter walk.
  }
  path.push_back({p, 1.0, 0.0});
  return path;
}

/// Time (s, from its start) at which a person starting from rest, accelerating at a up to speed v,
/// has covered d: what to subtract from a meeting time to start them in time.
double timeToCover(double d_m, double v_mps, double a_mps2) {
  const double ramp_m = 0.5 * v_mps * v_mps / a_mps2;
  if (d_m <= ramp_m) return std::sqrt(2.0 * d_m / a_mps2);
  return v_mps / a_mps2 + (d_m - ramp_m) / v_mps;
}

struct Context {
  const WalkingPerson& target;
  double target_delay_s;
  const std::vector<PathPoint>& target_path;
  const ObstacleWorld& world;
  const ObstacleWorld& walk_world;  ///< world and keep-out discs around the drone's and the target's start.
  std::mt19937_64& rng;
  const Clothing& target_clothing;
  /// The target at sim time t_s (seconds since the start).
  PersonState targetAt(double t_s) const { return target.state(t_s - target_delay_s); }
};

Eigen::Vector2d headingDir(const PersonState& s) {
  return {std::cos(s.heading_rad), std::sin(s.heading_rad)};
}

Bystander makeBystander(const Context& ctx, std::vector<PathPoint> path, double start_delay_s, bool look_alike,
                        const std::optional<Clothing>& clothing, std::string origin) {
  Bystander b;
  b.params = ctx.target.params();
  b.params.height_m = 1.75;
  b.params.torso_m = 0.50;
  b.path = std::move(path);
  b.start_delay_s = start_delay_s;
  b.look_alike = look_alike;
  // Always draw the random clothing, so that setting one person's clothing leaves the others' alone.
  const Clothing random = randomClothing(ctx.rng);
  const Clothing alike = lookAlikeClothing(ctx.target_clothing, ctx.rng);
  b.clothing = look_alike ? alike : clothing ? *clothing : random;
  b.appearance = signatureOf(b.clothing);
  b.origin = std::move(origin);
  return b;
}

rt::Expected<Bystander> crossingAt(const Context& ctx, const CrossingGenerator& c, double at_s, std::string origin) {
  const PersonState t = ctx.targetAt(at_s);
  const Eigen::Vector2d dir = headingDir(t);
  const Eigen::Vector2d left(-dir.y(), dir.x());
  const Eigen::Vector2d cross = t.p_W_m.head<2>() - c.behind_m * dir;
  const double side = std::bernoulli_distribution(0.5)(ctx.rng) ? 1.0 : -1.0;
  std::vector<PathPoint> path = {{cross + side * c.half_width_m * left, c.speed_mps, 0.0},
                                 {cross - side * c.half_width_m * left, c.speed_mps, 0.0}};
  if (!pathClear(path, ctx.world))
    return rt::Error{origin + ": the crossing at " + std::to_string(at_s) + " s passes through an obstacle"};
  const double delay_s = at_s - timeToCover(c.half_width_m, c.speed_mps, ctx.target.params().max_accel_mps2);
  if (delay_s < 0.0)
    return rt::Error{origin + ": the crossing at " + std::to_string(at_s) +
                     " s would have to start before the simulation (use a later time or a smaller half_width_m)"};
  return makeBystander(ctx, std::move(path), delay_s, c.look_alike, std::nullopt, std::move(origin));
}

rt::Expected<Bystander> alongside(const Context& ctx, const AlongsideGenerator& a, std::string origin) {
  const double side = a.side != 0 ? a.side : (std::bernoulli_distribution(0.5)(ctx.rng) ? 1.0 : -1.0);
  const double accel = ctx.target.params().max_accel_mps2;
  std::vector<PathPoint> path;
  // The target's track sampled every 0.5 s, shifted sideways; each leg at the target's speed there.
  const PersonState first = ctx.targetAt(a.from_s);
  const double v0 = std::max(first.speed_mps, 0.5);
  const double ramp_m = 0.5 * v0 * v0 / accel;
  // Start behind the beside-point by the ramp, so they reach it at speed when the target does.
  const Eigen::Vector2d dir0 = headingDir(first);
  const Eigen::Vector2d left0(-dir0.y(), dir0.x());
  path.push_back({first.p_W_m.head<2>() + side * a.offset_m * left0 - ramp_m * dir0, v0, 0.0});
  for (double t_s = a.from_s; t_s <= a.to_s + 1e-9; t_s += 0.5) {
    const PersonState s = ctx.targetAt(t_s);
    const Eigen::Vector2d dir = headingDir(s);
    const Eigen::Vector2d p = s.p_W_m.head<2>() + side * a.offset_m * Eigen::Vector2d(-dir.y(), dir.x());
    const PersonState next = ctx.targetAt(t_s + 0.5);
    const double v = std::clamp((next.p_W_m - s.p_W_m).norm() / 0.5, kMinSpeedMps, kMaxSpeedMps);
    if ((p - path.back().p_W_m).norm() < 0.05) continue;  // The target stands: so do they.
    path.back().speed_mps = std::clamp(v, kMinSpeedMps, kMaxSpeedMps);
    path.push_back({p, v, 0.0});
  }
  if (path.size() < 2) return rt::Error{origin + ": the target does not move between from_s and to_s"};
  if (!pathClear(path, ctx.world)) return rt::Error{origin + ": the side-by-side path passes through an obstacle"};
  const double delay_s = a.from_s - v0 / accel;
  if (delay_s < 0.0) return rt::Error{origin + ": from_s is too early to be walking already (start later)"};
  return makeBystander(ctx, std::move(path), delay_s, a.look_alike, std::nullopt, std::move(origin));
}

rt::Expected<std::vector<Bystander>> group(const Context& ctx, const GroupGenerator& g, const std::string& origin) {
  const Eigen::Vector2d centre = ctx.targetAt(g.at_s).p_W_m.head<2>();
  std::vector<Bystander> out;
  std::vector<Eigen::Vector2d> spots;
  for (int i = 0; i < g.count; ++i) {
    bool placed = false;
    Eigen::Vector2d spot = centre;
    for (int attempt = 0; attempt < 500 && !placed; ++attempt) {
      const double r = g.radius_m * std::sqrt(uniformIn(ctx.rng, 0.0, 1.0));
      const double phi = uniformIn(ctx.rng, -std::numbers::pi, std::numbers::pi);
      spot = centre + r * Eigen::Vector2d(std::cos(phi), std::sin(phi));
      if (distanceToPath(spot, ctx.target_path) < g.path_clearance_m) continue;
      if (ctx.walk_world.distance(atLegs(spot)) <= kPersonBodyRadiusM + 0.1) continue;
      const auto crowded = [&](const Eigen::Vector2d& o) {
        return (o - spot).norm() < 2.0 * kPersonBodyRadiusM + 0.15;
      };
      if (std::any_of(spots.begin(), spots.end(), crowded)) continue;
      placed = true;
    }
    if (!placed)
      return rt::Error{origin + ": cannot place member " + std::to_string(i) + " off the path (radius_m too small?)"};
    spots.push_back(spot);
    std::vector<PathPoint> path = {{spot, 0.5, 0.0}};
    if (g.milling) {
      // Short slow legs around the spot, never nearer the path than path_clearance_m.
      Eigen::Vector2d p = spot;
      for (int leg = 0; leg < 6; ++leg) {
        for (int attempt = 0; attempt < 30; ++attempt) {
          const double phi = uniformIn(ctx.rng, -std::numbers::pi, std::numbers::pi);
          const Eigen::Vector2d next =
              spot + uniformIn(ctx.rng, 0.3, 0.8) * Eigen::Vector2d(std::cos(phi), std::sin(phi));
          if (distanceToPath(next, ctx.target_path) < g.path_clearance_m || (next - p).norm() < 0.2 ||
              ctx.walk_world.distance(atLegs(next)) <= kPersonBodyRadiusM + 0.1)
            continue;
          path.back().speed_mps = uniformIn(ctx.rng, 0.3, 0.6);
          path.push_back({next, 0.5, uniformIn(ctx.rng, 1.0, 4.0)});
          p = next;
          break;
        }
      }
      path.front().pause_s = uniformIn(ctx.rng, 0.0, 3.0);
    }
    out.push_back(makeBystander(ctx, std::move(path), 0.0, i < g.look_alikes, std::nullopt,
                                origin + ".member[" + std::to_string(i) + "]"));
  }
  return out;
}

void mirrorPath(std::vector<PathPoint>& path) {
  for (PathPoint& p : path) p.p_W_m.y() = -p.p_W_m.y();
}

void mirrorWalk(BystanderWalk& w) {
  const double y0 = w.region_min_m.y();
  w.region_min_m.y() = -w.region_max_m.y();
  w.region_max_m.y() = -y0;
}

}  // namespace

AppearanceSignature signatureOf(const Clothing& clothing) {
  AppearanceSignature sig{};
  const double coloured = 1.0 - clothing.grey_share;
  addColour(sig, SignatureRegion::kTorso, clothing.hue_deg, clothing.saturation, 1.0,
            coloured * (1.0 - clothing.second_share));
  addColour(sig, SignatureRegion::kTorso, clothing.second_hue_deg, clothing.second_saturation, 1.0,
            coloured * clothing.second_share);
  addColour(sig, SignatureRegion::kTorso, 0.0, 0.0, clothing.grey_value, clothing.grey_share);
  addColour(sig, SignatureRegion::kLegs, clothing.legs_hue_deg, clothing.legs_saturation, 1.0,
            1.0 - clothing.legs_grey_share);
  addColour(sig, SignatureRegion::kLegs, 0.0, 0.0, clothing.legs_grey_value, clothing.legs_grey_share);
  return sig;
}

Eigen::Vector3f clothingBgr(const Clothing& clothing) {
  // HSV -> RGB with V = 1 (the standard hexcone conversion).
  const double h = std::fmod(clothing.hue_deg, 360.0) / 60.0;
  const double s = clothing.saturation;
  const double x = (1.0 - s) + s * (1.0 - std::abs(std::fmod(h, 2.0) - 1.0));
  const double lo = 1.0 - s;
  const int sector = static_cast<int>(h) % 6;
  const std::array<std::array<double, 3>, 6> rgb = {
      {{1.0, x, lo}, {x, 1.0, lo}, {lo, 1.0, x}, {lo, x, 1.0}, {x, lo, 1.0}, {1.0, lo, x}}};
  const auto& c = rgb[static_cast<std::size_t>(sector)];
  return {static_cast<float>(c[2]), static_cast<float>(c[1]), static_cast<float>(c[0])};
}

namespace {

/// A stream for the clothing fields added after the first six (issue 22 item 2), seeded by those six:
/// the scenario's bystander stream draws exactly as before, so its people walk where they did.
std::mt19937_64 extraClothingRng(const Clothing& c) {
  std::uint64_t z = 0x9E3779B97F4A7C15ULL;
  for (const double x :
       {c.hue_deg, c.saturation, c.second_hue_deg, c.second_saturation, c.second_share, c.grey_share}) {
    z ^= std::bit_cast<std::uint64_t>(x) + 0x9E3779B97F4A7C15ULL + (z << 6) + (z >> 2);
  }
  return std::mt19937_64(z);
}

}  // namespace

Clothing randomClothing(std::mt19937_64& rng) {
  Clothing c;
  c.hue_deg = uniformIn(rng, 0.0, 360.0);
  c.saturation = uniformIn(rng, 0.4, 1.0);
  c.second_hue_deg = uniformIn(rng, 0.0, 360.0);
  c.second_saturation = uniformIn(rng, 0.4, 1.0);
  c.second_share = uniformIn(rng, 0.1, 0.45);
  c.grey_share = uniformIn(rng, 0.1, 0.35);
  std::mt19937_64 extra = extraClothingRng(c);
  c.grey_value = uniformIn(extra, 0.05, 0.95);
  c.legs_hue_deg = uniformIn(extra, 0.0, 360.0);
  c.legs_saturation = uniformIn(extra, 0.3, 0.9);
  c.legs_grey_share = uniformIn(extra, 0.2, 1.0);
  c.legs_grey_value = uniformIn(extra, 0.05, 0.8);
  return c;
}

Clothing lookAlikeClothing(const Clothing& target, std::mt19937_64& rng) {
  Clothing c = target;
  c.hue_deg = std::fmod(target.hue_deg + uniformIn(rng, -8.0, 8.0) + 360.0, 360.0);
  c.second_hue_deg = std::fmod(target.second_hue_deg + uniformIn(rng, -8.0, 8.0) + 360.0, 360.0);
  c.saturation = std::clamp(target.saturation + uniformIn(rng, -0.05, 0.05), 0.0, 1.0);
  c.second_saturation = std::clamp(target.second_saturation + uniformIn(rng, -0.05, 0.05), 0.0, 1.0);
  c.second_share = std::clamp(target.second_share + uniformIn(rng, -0.05, 0.05), 0.0, 1.0);
  c.grey_share = std::clamp(target.grey_share + uniformIn(rng, -0.05, 0.05), 0.0, 0.95);
  std::mt19937_64 extra = extraClothingRng(c);
  c.grey_value = std::clamp(target.grey_value + uniformIn(extra, -0.05, 0.05), 0.0, 1.0);
  c.legs_hue_deg = std::fmod(target.legs_hue_deg + uniformIn(extra, -8.0, 8.0) + 360.0, 360.0);
  c.legs_saturation = std::clamp(target.legs_saturation + uniformIn(extra, -0.05, 0.05), 0.0, 1.0);
  c.legs_grey_share = std::clamp(target.legs_grey_share + uniformIn(extra, -0.05, 0.05), 0.0, 1.0);
  c.legs_grey_value = std::clamp(target.legs_grey_value + uniformIn(extra, -0.05, 0.05), 0.0, 1.0);
  return c;
}

AppearanceSignature noisySignature(const AppearanceSignature& truth, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> small(0.0, 0.0005);
  AppearanceSignature out{};
  for (std::size_t r = 0; r < kSignatureRegions; ++r) {
    const auto region = static_cast<SignatureRegion>(r);
    const bool measured = regionSum(truth, region) > 0.0;
    const std::size_t offset = regionOffset(region);
    double sum = 0.0;
    for (std::size_t i = offset; i < offset + kSignatureRegionBins; ++i) {
      const double n = normal(rng);  // drawn for every bin, so the stream's use does not depend on the truth
      const double u = small(rng);
      const double v = measured ? std::max(0.0, static_cast<double>(truth[i]) * (1.0 + 0.15 * n) + u) : 0.0;
      out[i] = static_cast<float>(v);
      sum += v;
    }
    if (sum > 0.0)
      for (std::size_t i = offset; i < offset + kSignatureRegionBins; ++i)
        out[i] = static_cast<float>(static_cast<double>(out[i]) / sum);
  }
  return out;
}

BystandersSpec parseBystanders(const rt::ConfigNode& n, const std::vector<Box>& boxes,
                               const std::vector<Cylinder>& cylinders) {
  BystandersSpec s;
  auto world = ObstacleWorld::create(boxes, cylinders);
  if (!world) n.fail("people", "the listed obstacles are invalid: " + world.error().message);
  if (n.has("target_clothing")) s.target_clothing = parseClothing(n.child("target_clothing"));
  if (n.has("people"))
    for (const ConfigNode& p : n.childList("people")) s.people.push_back(parseBystander(p, *world));
  if (n.has("crossings"))
    for (const ConfigNode& c : n.childList("crossings")) s.crossings.push_back(parseCrossing(c));
  if (n.has("alongside"))
    for (const ConfigNode& a : n.childList("alongside")) s.alongside.push_back(parseAlongside(a));
  if (n.has("groups"))
    for (const ConfigNode& g : n.childList("groups")) s.groups.push_back(parseGroup(g));
  if (n.has("random_walkers")) s.random_walkers = parseRandomWalkers(n.child("random_walkers"));
  n.finish();
  return s;
}

rt::Expected<BystandersInstance> instantiateBystanders(
    const BystandersSpec& spec, const PersonParams& target_params, const std::vector<PathPoint>& target_path,
    double target_start_delay_s, const Eigen::Vector2d& drone_start_m, bool mirrored, const std::vector<Box>& boxes,
    const std::vector<Cylinder>& cylinders, std::uint64_t seed, double duration_s) {
  auto rng = bystanderRng(seed);
  BystandersInstance inst;
  const Clothing random_target = randomClothing(rng);
  inst.target_clothing = spec.target_clothing ? *spec.target_clothing : random_target;
  inst.target_appearance = signatureOf(inst.target_clothing);
  if (spec.empty()) return inst;
  auto target = WalkingPerson::create(target_params, target_path);
  if (!target) return rt::Error{"bystanders: target: " + target.error().message};
  auto world = ObstacleWorld::create(boxes, cylinders);
  if (!world) return rt::Error{"bystanders: " + world.error().message};
  std::vector<Cylinder> with_keep_out = cylinders;
  with_keep_out.push_back(Cylinder{drone_start_m, kDroneStartKeepOutM, 0.0, 3.0});
  with_keep_out.push_back(Cylinder{target->state(0.0).p_W_m.head<2>(), kTargetStartKeepOutM, 0.0, 3.0});
  auto walk_world = ObstacleWorld::create(boxes, with_keep_out);
  if (!walk_world) return rt::Error{"bystanders: " + walk_world.error().message};
  const Context ctx{*target, target_start_delay_s, target_path, *world, *walk_world, rng, inst.target_clothing};

  for (std::size_t i = 0; i < spec.people.size(); ++i) {
    const BystanderSpec& p = spec.people[i];
    const std::string origin = "bystanders.people[" + std::to_string(i) + "]";
    std::vector<PathPoint> path = p.path;
    if (p.walk) {
      BystanderWalk walk = *p.walk;
      if (mirrored) mirrorWalk(walk);
      auto generated = randomWalk(walk, *walk_world, rng);
      if (!generated) return rt::Error{origin + ": " + generated.error().message};
      path = std::move(generated.value());
    } else {
      if (mirrored) mirrorPath(path);
      // The file's obstacles were checked when it was read; this seed's world also has jittered
      // and generated ones (trees, clutter), which a listed path must not cross either.
      if (!pathClear(path, *world))
        return rt::Error{origin + ": the listed path passes through an obstacle of seed " + std::to_string(seed) +
                         "'s world (jittered or generated)"};
    }
    Bystander b = makeBystander(ctx, std::move(path), p.start_delay_s, p.look_alike, p.clothing, origin);
    b.params.height_m = p.height_m;
    b.params.torso_m = p.torso_m;
    inst.people.push_back(std::move(b));
  }
  for (std::size_t i = 0; i < spec.crossings.size(); ++i) {
    const CrossingGenerator& c = spec.crossings[i];
    std::vector<double> times = c.at_s;
    for (int k = 0; k < c.count; ++k) times.push_back(uniformIn(rng, c.window_s.x(), c.window_s.y()));
    for (std::size_t k = 0; k < times.size(); ++k) {
      auto b =
          crossingAt(ctx, c, times[k], "bystanders.crossings[" + std::to_string(i) + "][" + std::to_string(k) + "]");
      if (!b) return b.error();
      inst.people.push_back(std::move(b.value()));
    }
  }
  for (std::size_t i = 0; i < spec.alongside.size(); ++i) {
    auto b = alongside(ctx, spec.alongside[i], "bystanders.alongside[" + std::to_string(i) + "]");
    if (!b) return b.error();
    inst.people.push_back(std::move(b.value()));
  }
  for (std::size_t i = 0; i < spec.groups.size(); ++i) {
    auto members = group(ctx, spec.groups[i], "bystanders.groups[" + std::to_string(i) + "]");
    if (!members) return members.error();
    for (Bystander& b : members.value()) inst.people.push_back(std::move(b));
  }
  if (spec.random_walkers) {
    const RandomWalkersGenerator& r = *spec.random_walkers;
    BystanderWalk walk = r.walk;
    if (mirrored) mirrorWalk(walk);
    for (int i = 0; i < r.count; ++i) {
      const std::string origin = "bystanders.random_walkers[" + std::to_string(i) + "]";
      auto path = randomWalk(walk, *walk_world, rng);
      if (!path) return rt::Error{origin + ": " + path.error().message};
      const double delay_s = uniformIn(rng, r.start_delay_s.x(), r.start_delay_s.y());
      inst.people.push_back(makeBystander(ctx, std::move(path.value()), delay_s, false, std::nullopt, origin));
    }
  }
  GiveWayParams give_way;
  give_way.min_distance_m = 2.0 * kPersonBodyRadiusM;
  give_way.horizon_s = std::max(duration_s, give_way.sample_s);
  for (Bystander& b : inst.people) {
    auto walker = WalkingPerson::create(b.params, b.path);
    if (!walker) return rt::Error{b.origin + ": " + walker.error().message};
    auto steps = GiveWay::compute(*target, target_start_delay_s, *walker, b.start_delay_s, *world, give_way);
    if (!steps) return rt::Error{b.origin + ": " + steps.error().message};
    b.give_way = std::move(steps.value());
  }
  return inst;
}

}  // namespace aerotrack::hal::sim
