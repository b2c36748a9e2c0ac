// Reading cast files. See cast_file.hpp.
#include "aerotrack/hal/sim/cast_file.hpp"

#include <cmath>
#include <filesystem>

namespace aerotrack::hal::sim {
namespace {

using rt::ConfigNode;

constexpr double kMaxPx = 1e5;

PersonSpriteSpec parsePerson(const ConfigNode& n, const std::string& base_dir) {
  PersonSpriteSpec p;
  p.name = n.getString("name");
  if (p.name.empty()) n.fail("name", "must not be empty");
  const std::string image = n.getString("image");
  if (image.empty()) n.fail("image", "must not be empty");
  p.image_path = std::filesystem::path(image).is_absolute() || base_dir.empty()
                     ? image
                     : (std::filesystem::path(base_dir) / image).lexically_normal().string();
  p.frame = n.has("frame") ? n.getInt("frame", 0, 20000) : -1;
  p.view = n.getEnum("view", {"front", "back"}) == "front" ? PersonView::kFront : PersonView::kBack;
  const auto crop = n.getDoubleList("crop_px", 4, 0.0, kMaxPx);
  for (std::size_t i = 0; i < 4; ++i) {
    if (crop[i] != std::floor(crop[i])) n.fail("crop_px", "expected whole pixels [x, y, width, height]");
    p.crop_px[i] = static_cast<int>(crop[i]);
  }
  const auto keypoints = n.getDoubleRows("keypoints_px", 2, 0.0, kMaxPx);
  if (keypoints.size() != kNumKeypoints)
    n.fail("keypoints_px", "expected the 17 COCO keypoints, got " + std::to_string(keypoints.size()));
  for (std::size_t i = 0; i < kNumKeypoints; ++i) p.keypoints_px[i] = {keypoints[i][0], keypoints[i][1]};
  const auto strokes = [&](const std::string& key) {
    std::vector<std::array<double, 4>> out;
    if (!n.has(key)) return out;
    for (const auto& row : n.getDoubleRows(key, 4, 0.0, kMaxPx)) out.push_back({row[0], row[1], row[2], row[3]});
    return out;
  };
  p.foreground_strokes_px = strokes("foreground_strokes_px");
  p.background_strokes_px = strokes("background_strokes_px");
  p.background_stroke_width_px = n.getDoubleOr("background_stroke_width_px", p.background_stroke_width_px, 1.0, 50.0);
  p.grabcut_iterations = n.getIntOr("grabcut_iterations", p.grabcut_iterations, 1, 20);
  n.finish();
  if (const rt::Status status = validate(p); !status) n.fail("keypoints_px", status.error().message);
  return p;
}

rt::Expected<PersonCastSpec> parseFrom(rt::Expected<ConfigNode> root, const std::string& base_dir) {
  if (!root) return root.error();
  return rt::parseConfig<PersonCastSpec>([&] {
    PersonCastSpec cast;
    for (const ConfigNode& person : root->childList("people")) cast.people.push_back(parsePerson(person, base_dir));
    root->finish();
    if (const rt::Status status = validate(cast); !status) root->fail("people", status.error().message);
    return cast;
  });
}

}  // namespace

rt::Expected<PersonCastSpec> loadCastFile(const std::string& path) {
  return parseFrom(ConfigNode::loadFile(path), std::filesystem::path(path).parent_path().string());
}

rt::Expected<PersonCastSpec> parseCast(const std::string& yaml_text, const std::string& source_name,
                                       const std::string& base_dir) {
  return parseFrom(ConfigNode::fromString(yaml_text, source_name), base_dir);
}

}  // namespace aerotrack::hal::sim
