// The people image mode can draw: the target and the bystanders each wear one of them (scenario key
// sensors.gimbal_camera.people names a cast file; without it, defaultCast()). Every person is a real
// person in a photo or video frame that a Debian package ships, cut out and cut into parts
// (person_sprite.hpp).
//
// defaultCast(): six people, all from Debian's opencv-doc package (OpenCV's sample data, distributed
// under OpenCV's licence, Apache 2.0 / 3-clause BSD; docs/modules/simulation.md lists them):
//   basketball1_standing  basketball1.png, the standing man on the left (front)
//   vtest_glasses         vtest.avi frame 200, man with glasses, dark jacket, jeans (front)
//   vtest_black           vtest.avi frame 200, man in black (front)
//   vtest_blonde          vtest.avi frame 650, woman with blonde hair, black coat (back)
//   vtest_red_jacket      vtest.avi frame 550, man in a red and navy jacket (back)
//   vtest_grey_jacket     vtest.avi frame 50, bald man, dark jacket, jeans, walking away (back)
// vtest.avi's people are 100-125 px tall in its 768 x 576 frames, seen from a first floor: the
// renderer's part warps stretch their foreshortened legs to the simulated ones.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "aerotrack/hal/sim/person_sprite.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// At most this many people in a cast (each costs a GrabCut at load).
inline constexpr std::size_t kMaxCastPeople = 32;

struct PersonCastSpec {
  std::vector<PersonSpriteSpec> people;
};

/// The six people above.
PersonCastSpec defaultCast();

/// Ok if the cast has 1..kMaxCastPeople people, each valid, with distinct names.
rt::Status validate(const PersonCastSpec& cast);

/// Index of the person named `name` in the cast; an empty name is the first person.
rt::Expected<std::size_t> findPerson(const PersonCastSpec& cast, const std::string& name);

/// Whom person `id` of a scene (0 the target, 1.. the bystanders) wears: the target and look-alikes
/// the target's person, every other bystander another person of the cast by their id (with a cast of
/// one, the target's: the renderer then recolours their clothes).
std::size_t castPersonFor(std::size_t id, bool look_alike, std::size_t target, std::size_t cast_size);

using PersonSprites = std::vector<std::shared_ptr<const PersonSprite>>;

/// Loads every person (each video read once, in one pass). Errors name the person, file and key.
rt::Expected<PersonSprites> loadCast(const PersonCastSpec& cast);

}  // namespace aerotrack::hal::sim
