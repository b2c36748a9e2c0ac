// Bystanders (issue 20, item 2): the other people of a simulated world. A scenario's optional
// `bystanders:` section (config/scenarios/README.md) lists people with their own path or seeded
// random walk, and generators for the cases that defeat a person follower, placed relative to the
// target's instantiated path and timing:
//   - crossings: a person crossing the target's path a little behind the target, i.e. between the
//     following drone and the target, where the drone's line of sight passes (an occlusion by a
//     person, then two persons side by side in the image);
//   - alongside: a person walking beside the target, same direction and speed, ~1 m to one side
//     (two persons close in the image for a long time: identity swaps);
//   - groups: people standing or milling near a point the target walks through (clutter of
//     similar detections around the target);
//   - random_walkers: people walking seeded random paths in a region (background traffic);
//   - look_alike: any bystander may wear the target's clothes (a small perturbation of its
//     appearance), which defeats an appearance cue.
// Every person carries a true appearance signature in hal's layout (appearance_signature.hpp): the
// torso's histogram made of two clothing colours and a grey of some brightness, the legs' of a
// trousers colour and a grey.
// Everything random comes from one stream of the scenario seed (bystander generation), so a
// scenario without the section instantiates exactly as before.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "aerotrack/hal/sim/geometry.hpp"
#include "aerotrack/hal/sim/give_way.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::rt {
class ConfigNode;
}

namespace aerotrack::hal::sim {

/// A person's appearance signature (hal::PersonDetection::appearance's layout; each region sums to 1).
using AppearanceSignature = AppearanceHistogram;

/// Random walkers and group members keep this far from the drone's start point.
inline constexpr double kDroneStartKeepOutM = 2.0;
/// ... and random walks this far from where the target stands before they set off: two bodies' radii and half a
/// metre between them (crowd seed 16 started a walker 0.26 m from the target, inside their body, and the
/// association could not tell the two apart from the first frame).
inline constexpr double kTargetStartKeepOutM = 1.0;

/// A person's body as an obstacle and occluder: a vertical cylinder of their height. 0.25 m covers
/// the shoulders (0.259 H = 0.45 m wide at H = 1.75 m, Drillis & Contini) and the swinging arms.
inline constexpr double kPersonBodyRadiusM = 0.25;

/// Clothing: the torso's two colours (hue in degrees, saturation in [0, 1]) and a grey share (hair, skin
/// in shadow, a dark pattern) of some brightness; the legs' one colour and grey share.
struct Clothing {
  double hue_deg = 0.0;
  double saturation = 0.7;
  double second_hue_deg = 0.0;
  double second_saturation = 0.5;
  double second_share = 0.3;  ///< Of the coloured part, [0, 1].
  double grey_share = 0.2;    ///< Of the whole, [0, 1).
  double grey_value = 0.3;    ///< Brightness of the grey, [0, 1]: black 0, white 1.
  double legs_hue_deg = 220.0;
  double legs_saturation = 0.5;
  double legs_grey_share = 0.8;  ///< Of the legs, [0, 1]: dark trousers are mostly grey.
  double legs_grey_value = 0.2;
};

/// The signature of clothing, both regions measured: each colour votes as a pixel of that colour does
/// (hal::addColour; coloured cloth at brightness 1, the greys at their brightness). Pure.
AppearanceSignature signatureOf(const Clothing& clothing);

/// The main clothing colour as BGR in [0, 1] (HSV with value 1), for the image renderer's recolouring.
Eigen::Vector3f clothingBgr(const Clothing& clothing);

/// Random clothing: hues uniform, saturations in [0.4, 1], grey share in [0.1, 0.35]; grey brightness in
/// [0.05, 0.95]; legs' saturation in [0.3, 0.9], grey share in [0.2, 1], grey brightness in [0.05, 0.8].
/// Draws six numbers from rng, as before the legs and brightness existed (so that every scenario's
/// bystanders walk where they did); the rest comes from a stream seeded by those six.
Clothing randomClothing(std::mt19937_64& rng);

/// Clothing like `target`'s: hues within +-8 deg, saturations, shares and brightnesses within +-0.05.
/// Draws six numbers from rng (as randomClothing).
Clothing lookAlikeClothing(const Clothing& target, std::mt19937_64& rng);

/// One frame's measurement of a signature: each bin of a measured region times (1 + 0.15 N(0, 1)) plus
/// U(0, 0.0005), clamped at 0, the region renormalised (a real histogram changes with light, pose and
/// crop); a region not measured stays zeros. Draws 2 x kAppearanceSignatureBins numbers.
AppearanceSignature noisySignature(const AppearanceSignature& truth, std::mt19937_64& rng);

using hal::signatureDistance;

/// A bystander's random walk: legs of random length and turn inside a region.
struct BystanderWalk {
  Eigen::Vector2d region_min_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d region_max_m = Eigen::Vector2d::Zero();
  int legs = 4;
  double leg_min_m = 3.0;
  double leg_max_m = 8.0;
  double speed_min_mps = 0.8;
  double speed_max_mps = 1.5;
  double pause_max_s = 0.0;  ///< Each corner: a pause uniform in [0, pause_max_s].
};

/// A listed bystander.
struct BystanderSpec {
  std::vector<PathPoint> path;        ///< Or empty, with walk set.
  std::optional<BystanderWalk> walk;  ///< Seeded random walk.
  double start_delay_s = 0.0;         ///< Seconds from the simulation's start until they walk.
  double height_m = 1.75;
  double torso_m = 0.50;
  std::optional<Clothing> clothing;  ///< Absent: random (seeded).
  bool look_alike = false;           ///< Dressed like the target (overrides clothing).
};

/// People crossing the target's path behind it, perpendicular to it.
struct CrossingGenerator {
  std::vector<double> at_s;  ///< When they cross (seconds since the start); or count + window:
  int count = 0;             ///< seeded times uniform in [window_s[0], window_s[1]].
  Eigen::Vector2d window_s = Eigen::Vector2d::Zero();
  double behind_m = 1.2;      ///< The crossing point trails the target by this, along its heading.
  double half_width_m = 5.0;  ///< They walk from this far on one side of the path to as far on the other.
  double speed_mps = 1.4;
  bool look_alike = false;
};

/// A person walking beside the target from from_s to to_s (seconds since the start).
struct AlongsideGenerator {
  double from_s = 0.0;
  double to_s = 0.0;
  double offset_m = 1.0;  ///< Lateral distance from the target, > 0.
  int side = 0;           ///< +1 left of the target, -1 right, 0 seeded.
  bool look_alike = false;
};

/// People standing (or milling) around the point the target passes at at_s.
struct GroupGenerator {
  double at_s = 0.0;
  int count = 4;
  double radius_m = 2.5;          ///< Members stand within this of the point...
  double path_clearance_m = 0.8;  ///< ...but at least this far from the target's path.
  bool milling = false;           ///< Walk short slow legs around their spot instead of standing.
  int look_alikes = 0;            ///< The first this many members are look-alikes.
};

/// Background walkers on seeded random walks.
struct RandomWalkersGenerator {
  int count = 0;
  BystanderWalk walk;
  Eigen::Vector2d start_delay_s = Eigen::Vector2d::Zero();  ///< Uniform in [lo, hi].
};

/// The `bystanders:` section (empty: no bystanders).
struct BystandersSpec {
  std::optional<Clothing> target_clothing;  ///< Absent: random (seeded).
  std::vector<BystanderSpec> people;
  std::vector<CrossingGenerator> crossings;
  std::vector<AlongsideGenerator> alongside;
  std::vector<GroupGenerator> groups;
  std::optional<RandomWalkersGenerator> random_walkers;
  bool empty() const {
    return people.empty() && crossings.empty() && alongside.empty() && groups.empty() && !random_walkers;
  }
};

/// One concrete bystander of an instance.
struct Bystander {
  PersonParams params;
  std::vector<PathPoint> path;
  double start_delay_s = 0.0;  ///< From the simulation's start.
  Clothing clothing;
  AppearanceSignature appearance{};
  bool look_alike = false;
  std::string origin;  ///< Which entry made them ("people[2]", "crossings[0]", ...), for errors and reports.
  /// Their side-steps around the followed person (give_way.hpp): add to the walk of `path` (withOffset).
  GiveWay give_way;
};

/// The concrete people of one instance besides the target.
struct BystandersInstance {
  Clothing target_clothing;
  AppearanceSignature target_appearance{};
  std::vector<Bystander> people;
};

/// Parses the `bystanders:` node. Listed paths are checked against the listed obstacles (a path
/// through one fails naming its key). Throws rt::ConfigNode's error on a bad key or value.
BystandersSpec parseBystanders(const rt::ConfigNode& node, const std::vector<Box>& boxes,
                               const std::vector<Cylinder>& cylinders);

/// Generates the bystanders for one seed around the target (its params, instantiated path and start
/// delay), keeping generated paths out of the obstacles, and random walks and groups also
/// kDroneStartKeepOutM away from the drone's start (so nobody walks into the drone before it takes
/// off). mirrored: the instance was mirrored about y = 0 (listed paths and regions follow). Each one's
/// side-steps around the target (Bystander::give_way) are sampled over the trial's first duration_s. Error if
/// a generator cannot place what it was asked to.
rt::Expected<BystandersInstance> instantiateBystanders(
    const BystandersSpec& spec, const PersonParams& target_params, const std::vector<PathPoint>& target_path,
    double target_start_delay_s, const Eigen::Vector2d& drone_start_m, bool mirrored, const std::vector<Box>& boxes,
    const std::vector<Cylinder>& cylinders, std::uint64_t seed, double duration_s);

}  // namespace aerotrack::hal::sim
