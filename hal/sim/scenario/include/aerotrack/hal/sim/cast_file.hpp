// Cast files: the people image mode draws (person_cast.hpp), as YAML. A scenario names one with
// sensors.gimbal_camera.people (a path relative to the scenario's folder); without it, the built-in
// defaultCast(). Format (config/scenarios/README.md):
//   people:
//     - name: vtest_glasses            # unique
//       image: /usr/share/doc/opencv-doc/examples/data/vtest.avi   # relative: to the cast file's folder
//       frame: 200                     # a video's frame; absent for a still image
//       view: front                    # or back: which side of the person the photo shows
//       crop_px: [605, 262, 52, 108]   # x, y, width, height
//       keypoints_px: [[u, v], ...]    # the 17 COCO keypoints, the person's left and right
//       foreground_strokes_px: [[u0, v0, u1, v1], ...]   # optional extra sure foreground
//       background_strokes_px: [[u0, v0, u1, v1], ...]   # optional sure background
//       background_stroke_width_px: 4  # optional, [1, 50]
//       grabcut_iterations: 5          # optional, [1, 20]
#pragma once

#include <string>

#include "aerotrack/hal/sim/person_cast.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Reads and validates a cast file. Errors are one line naming the file and the key.
rt::Expected<PersonCastSpec> loadCastFile(const std::string& path);
/// The same from YAML text; relative image paths resolve against base_dir.
rt::Expected<PersonCastSpec> parseCast(const std::string& yaml_text, const std::string& source_name,
                                       const std::string& base_dir);

}  // namespace aerotrack::hal::sim
