// People found in the depth camera's image (issue 22 item 2: the others known in image mode). The gimbal camera's
// network runs on a crop around the followed person (96 % of its runs in the image-mode crowd), so the other people
// are seldom on tracks of their own, and a look-alike who walks up to the hidden person is taken for them by a
// starved track whose gate has grown. The body-fixed depth camera sees everyone in its view in every frame, at
// centimetres: each upright body apart from the ground is a person's centre, which keeps the others' tracks
// (bystander_tracks.hpp) fed where the network does not look.
//
// The image is segmented where it lies (a range image's connected components, as in Bogoslavskyi and Stachniss's
// range-image clustering, IROS 2016): pixels whose point in W stands above the ground are joined to their
// 4-neighbours when their depths differ by less than depth_jump_m, so two people one behind the other part at the
// depth step between them and two side by side at the gap the camera sees between them. A component is a person if
// it has the shape of one: its highest point within [min_top_m, max_top_m] (a bench is lower, a kiosk, a tree, a
// wall taller), no wider across the line of sight than max_width_m nor deeper along it than max_depth_m, and not
// cut by the image's edges (a body whose top or side is out of view cannot be placed or sized). Its centre is the
// mean of its surface points, moved centre_behind_m farther along the horizontal line of sight (the surface the
// camera sees is the body's front: for a cylinder of radius r, uniform across the image, the mean lies pi r / 4 in
// front of the axis). The depth step grows with the stereo noise, and the size test is an area, so that a far post's
// noise does not break it into person-sized pieces.
//
// Written here, not taken from a library: Debian's PCL has a ground-based people detector, but it confirms each
// cluster with a HOG classifier on the colour image paired with the depth image, which hal::DepthFrame does not
// carry; OpenCV's connectedComponents labels a binary image, without the depth steps. Checked against where the
// simulator's D435 model renders the bodies (depth_people_test.cpp).
//
// Two people pressed together in view at one depth are one component, too wide for a body: it is split at the seam
// between them, where the nearest surface across the image lies behind the chord joining the nearest points on its
// two sides (each body's front is convex, nearest at its middle; a wall, a box or a bin has no such seam), and each
// side placed if it has a person's shape.
//
// What it cannot tell: who a person is (no colour: the depth camera sees shapes), a person from an upright obstacle
// of a person's size (a post 1.7 m high, the inside corner of two low walls), or three people pressed together.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::estimation {

struct DepthPeopleParams {
  bool enabled = false;      ///< Off unless configured.
  int stride_px = 1;         ///< Every this many pixels in both directions (a D435's 848 x 480: 4).
  double max_range_m = 8.0;  ///< Pixels farther than this (optical z) are not looked at (the stereo noise grows).
  double min_z_m = 0.3;      ///< A point this high above the ground (W z = 0) or more is not the ground.
  double min_top_m = 1.3;    ///< A person's highest point lies at least this high...
  double max_top_m = 2.2;    ///< ... and at most this high; a component with any point above it is not a person.
  double max_width_m = 0.8;  ///< Across the horizontal line of sight: shoulders and arms.
  double max_depth_m = 0.7;  ///< Along it.
  /// Neighbouring pixels whose depths differ by more than this plus three standard deviations of the difference of
  /// two pixels' stereo noise (sqrt(2) std_per_m2 z^2) are apart: with the step alone, a post 7-8 m away (noise 8-10
  /// cm a pixel) broke into fragments of a person's height, each taken for a person (traced: sharp_turn's pillars).
  double depth_jump_m = 0.25;
  /// A component whose pixels cover less than this (each pixel's footprint at its depth, times stride^2) is too little
  /// seen to place: a person from 0.3 m up is about 0.7 m^2, half of them hidden 0.35.
  double min_area_m2 = 0.2;
  /// A component wider than max_width_m (and at most twice it) is split at the seam between two bodies when the
  /// seam's nearest surface lies at least split_seam_m plus two standard deviations of the stereo noise (at the
  /// component's far side) behind the chord joining the nearest points on its two sides: two 0.25 m cylinders
  /// touching side by side at one depth, 0.14 m (a 5 cm bin's edge). false: a too-wide component is dropped.
  bool split_two = true;
  double split_seam_m = 0.05;
  double centre_behind_m = 0.2;  ///< From the surface's mean to the body's axis, along the line of sight.
  double std_m = 0.1;            ///< The centre's noise per horizontal axis: the body's shape and pose...
  double std_per_m2 = 0.0015;    ///< ... and the stereo noise k z^2 added to it (in quadrature; depth_range.hpp).
  /// The person the live followed track's gate alone takes (nobody else of the depth frame in it) updates it too:
  /// the track stays fed while the network does not find the person (turned, half hidden). false: only the others'.
  bool feed_followed = false;
  /// ... while the followed track's horizontal position spread (the larger axis) is at most this: the depth camera
  /// carries a fed track on, it does not re-acquire a starved one (its gate grown over whoever stands near), nor
  /// start a young one. 0.25 m: a track fed by the network (0.05-0.1 m at the following distance) that went about
  /// 0.7 s without a measurement (white acceleration 0.4 m^2/s^3).
  double feed_max_std_m = 0.25;
};

/// Ok if every field is finite and in range (stride >= 1, 0 < min_z < min_top < max_top, widths > 0, ...).
rt::Status validate(const DepthPeopleParams& params);

/// Reads the `depth_people:` section of `estimation:` (every key required). Throws rt::ConfigError naming the key.
DepthPeopleParams parseDepthPeopleParams(const rt::ConfigNode& node);

/// A person the depth camera sees.
struct DepthPerson {
  Eigen::Vector2d p_W_m = Eigen::Vector2d::Zero();  ///< The body's axis on the ground plane, in W.
  double range_m = 0.0;                             ///< Horizontal distance from the depth camera.
  double top_m = 0.0;                               ///< The highest point seen, above the ground.
  double std_m = 0.0;                               ///< Noise per horizontal axis of p_W_m.
  int pixels = 0;                                   ///< Sampled pixels of the component.
  double area_m2 = 0.0;                             ///< The silhouette's area the camera sees.
};

/// Finds the people in depth frames. Holds its work buffers: the first frame of a size allocates them, later frames
/// of that size do not.
class DepthPeopleFinder {
 public:
  explicit DepthPeopleFinder(const DepthPeopleParams& params) : params_(params) {}

  /// The people in `depth` seen from T_WD (the depth camera's optical frame, x right, y down, z forward, in W),
  /// written into `out` (as many as fit, nearest first); returns their number. An image that is not CV_32FC1 of
  /// the intrinsics' size, or a pose that is not finite, has nobody.
  std::size_t find(const hal::DepthFrame& depth, const Eigen::Isometry3d& T_WD, std::span<DepthPerson> out);

 private:
  struct Component {
    int pixels = 0;
    double area_m2 = 0.0;
    Eigen::Vector3d sum_W = Eigen::Vector3d::Zero();
    double top_m = 0.0;
    bool too_tall = false;
    bool cut = false;                         ///< Touches the image's top, left or right edge.
    double min_depth = 0.0, max_depth = 0.0;  ///< Optical z.
    std::int32_t first = -1;                  ///< First pixel (to revisit its points).
  };
  /// The horizontal line of sight from the camera to a component's mean, and across it (to the left).
  struct Axes {
    Eigen::Vector2d camera_W;
    Eigen::Vector2d along;
    Eigen::Vector2d across() const { return {-along.y(), along.x()}; }
  };
  /// A component's pixels within an interval across the line of sight, summed.
  struct Extent {
    int pixels = 0;
    double area_m2 = 0.0;
    Eigen::Vector3d sum_W = Eigen::Vector3d::Zero();
    double top_m = 0.0;
    double min_depth = 0.0;        ///< Optical z.
    double lo = 0.0, hi = 0.0;     ///< Across the line of sight from the camera.
    double near = 0.0, far = 0.0;  ///< Along it.
  };
  /// The pixels of `comp` whose across coordinate lies in [from_m, to_m).
  Extent extent(const Component& comp, const Axes& axes, double from_m, double to_m, double pixel_area_per_z2,
                std::size_t n) const;
  /// The across coordinate of the seam between two bodies in `comp` (its extent `whole`), if it has one.
  std::optional<double> seamAcross(const Component& comp, const Axes& axes, const Extent& whole, double fx_px,
                                   std::size_t n);
  DepthPeopleParams params_;
  std::vector<Eigen::Vector3f> points_W_;  ///< Per sampled pixel; NaN: not a body pixel.
  std::vector<float> depth_;               ///< Per sampled pixel, optical z (0: none).
  std::vector<std::int32_t> label_;        ///< Per sampled pixel: its component, -1: none.
  std::vector<std::int32_t> stack_;
  std::vector<Component> components_;
  /// Per bin across a too-wide component: its nearest surface along the line of sight.
  std::vector<double> seam_near_;
};

}  // namespace aerotrack::estimation
