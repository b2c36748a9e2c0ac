// Our types as Foxglove messages: see foxglove_messages.hpp.
#include "foxglove_messages.hpp"

#include <google/protobuf/descriptor.pb.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <set>

namespace aerotrack::app::foxglove_log {
namespace {

struct Rgba {
  double r, g, b, a;
};
constexpr Rgba kGreen{0.2, 0.85, 0.3, 1.0};
constexpr Rgba kOrange{1.0, 0.55, 0.1, 1.0};
constexpr Rgba kGrey{0.6, 0.6, 0.6, 1.0};
constexpr Rgba kBlue{0.3, 0.5, 1.0, 0.8};
constexpr Rgba kYellow{1.0, 0.85, 0.1, 0.9};

void setColor(foxglove::Color& c, const Rgba& rgba) {
  c.set_r(rgba.r);
  c.set_g(rgba.g);
  c.set_b(rgba.b);
  c.set_a(rgba.a);
}

void setVector(foxglove::Vector3& v, const Eigen::Vector3d& x) {
  v.set_x(x.x());
  v.set_y(x.y());
  v.set_z(x.z());
}

void setPoint(foxglove::Point3& p, const Eigen::Vector3d& x) {
  p.set_x(x.x());
  p.set_y(x.y());
  p.set_z(x.z());
}

void setQuaternion(foxglove::Quaternion& q, const Eigen::Quaterniond& x) {
  q.set_x(x.x());
  q.set_y(x.y());
  q.set_z(x.z());
  q.set_w(x.w());
}

void setPose(foxglove::Pose& pose, const Eigen::Vector3d& p,
             const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  setVector(*pose.mutable_position(), p);
  setQuaternion(*pose.mutable_orientation(), q);
}

void addTransform(foxglove::FrameTransforms& m, rt::TimeNs stamp_ns, const char* parent, const char* child,
                  const Eigen::Isometry3d& T) {
  foxglove::FrameTransform& t = *m.add_transforms();
  setTime(*t.mutable_timestamp(), stamp_ns);
  t.set_parent_frame_id(parent);
  t.set_child_frame_id(child);
  setVector(*t.mutable_translation(), T.translation());
  setQuaternion(*t.mutable_rotation(), Eigen::Quaterniond(T.rotation()));
}

foxglove::SceneEntity& addEntity(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, const std::string& id) {
  foxglove::SceneEntity& e = *m.add_entities();
  setTime(*e.mutable_timestamp(), stamp_ns);
  e.set_frame_id("world");
  e.set_id(id);
  return e;
}

}  // namespace

std::string fileDescriptorSet(const google::protobuf::Descriptor& descriptor) {
  google::protobuf::FileDescriptorSet set;
  std::set<std::string> seen;
  // Dependencies first, as protoc writes them.
  auto add = [&](auto& self, const google::protobuf::FileDescriptor* file) -> void {
    if (!seen.insert(file->name()).second) return;
    for (int i = 0; i < file->dependency_count(); ++i) self(self, file->dependency(i));
    file->CopyTo(set.add_file());
  };
  add(add, descriptor.file());
  return set.SerializeAsString();
}

void setTime(google::protobuf::Timestamp& t, rt::TimeNs ns) {
  const rt::TimeNs s = ns >= 0 ? ns / 1'000'000'000 : -((-ns + 999'999'999) / 1'000'000'000);
  t.set_seconds(s);
  t.set_nanos(static_cast<std::int32_t>(ns - s * 1'000'000'000));
}

void fillTransforms(foxglove::FrameTransforms& m, const hal::OdometrySample& odometry, double gimbal_angle_rad,
                    const estimation::GimbalCameraExtrinsics* extrinsics, const Eigen::Isometry3d* T_BD) {
  m.Clear();
  const rt::TimeNs t = odometry.stamp_ns;
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() = odometry.q_WB.normalized().toRotationMatrix();
  T_WB.translation() = odometry.p_WB_m;
  addTransform(m, t, "world", "base_link", T_WB);
  if (extrinsics != nullptr) {
    Eigen::Isometry3d T_BG = Eigen::Isometry3d::Identity();
    T_BG.translation() = extrinsics->p_BG_m;
    T_BG.linear() = Eigen::AngleAxisd(gimbal_angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    addTransform(m, t, "base_link", "gimbal", T_BG);
    addTransform(m, t, "gimbal", "camera", extrinsics->T_GC);
    Eigen::Isometry3d T_C_optical = Eigen::Isometry3d::Identity();
    T_C_optical.linear() = estimation::opticalAxesInCamera();
    addTransform(m, t, "camera", "camera_optical", T_C_optical);
  }
  if (T_BD != nullptr) addTransform(m, t, "base_link", "depth_optical", *T_BD);
}

void fillCalibration(foxglove::CameraCalibration& m, rt::TimeNs stamp_ns, const hal::CameraIntrinsics& k) {
  m.Clear();
  setTime(*m.mutable_timestamp(), stamp_ns);
  m.set_frame_id("camera_optical");
  m.set_width(static_cast<std::uint32_t>(k.width_px));
  m.set_height(static_cast<std::uint32_t>(k.height_px));
  m.set_distortion_model("plumb_bob");
  for (const double d : k.distortion) m.add_d(d);
  for (const double v : {k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0}) m.add_k(v);
  for (const double v : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) m.add_r(v);
  for (const double v : {k.fx_px, 0.0, k.cx_px, 0.0, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 0.0, 1.0, 0.0}) m.add_p(v);
}

void fillAnnotations(foxglove::ImageAnnotations& m, const hal::DetectionFrame& frame, double min_score) {
  m.Clear();
  for (std::size_t i = 0; i < std::min(frame.person_count, hal::kMaxPersons); ++i) {
    const hal::PersonDetection& person = frame.persons[i];
    const bool followed = static_cast<int>(i) == frame.target_index;
    const Rgba colour = followed ? kGreen : kOrange;
    foxglove::PointsAnnotation& limbs = *m.add_points();
    setTime(*limbs.mutable_timestamp(), frame.stamp_ns);
    limbs.set_type(foxglove::PointsAnnotation::LINE_LIST);
    setColor(*limbs.mutable_outline_color(), colour);
    limbs.set_thickness(followed ? 4.0 : 2.0);
    for (const auto& [a, b] : hal::kCocoSkeleton) {
      const hal::Keypoint2D& ka = person.keypoints[static_cast<std::size_t>(a)];
      const hal::Keypoint2D& kb = person.keypoints[static_cast<std::size_t>(b)];
      if (ka.score < min_score || kb.score < min_score) continue;
      for (const hal::Keypoint2D* k : {&ka, &kb}) {
        foxglove::Point2& p = *limbs.add_points();
        p.set_x(k->u_px);
        p.set_y(k->v_px);
      }
    }
    foxglove::PointsAnnotation& joints = *m.add_points();
    setTime(*joints.mutable_timestamp(), frame.stamp_ns);
    joints.set_type(foxglove::PointsAnnotation::POINTS);
    setColor(*joints.mutable_outline_color(), colour);
    joints.set_thickness(5.0);
    for (const hal::Keypoint2D& k : person.keypoints) {
      if (k.score < min_score) continue;
      foxglove::Point2& p = *joints.add_points();
      p.set_x(k.u_px);
      p.set_y(k.v_px);
    }
    foxglove::TextAnnotation& label = *m.add_texts();
    setTime(*label.mutable_timestamp(), frame.stamp_ns);
    label.mutable_position()->set_x(person.bbox_u_px);
    label.mutable_position()->set_y(std::max(0.0, person.bbox_v_px - 4.0));
    char text[48];
    std::snprintf(text, sizeof(text), "%s %.2f", followed ? "target" : "person", person.score);
    label.set_text(text);
    label.set_font_size(14.0);
    setColor(*label.mutable_text_color(), colour);
    setColor(*label.mutable_background_color(), Rgba{0.0, 0.0, 0.0, 0.5});
  }
}

void fillEstimate(foxglove::SceneUpdate& m, const estimation::TargetEstimate& e) {
  m.Clear();
  foxglove::SceneEntity& entity = addEntity(m, e.stamp_ns, "person/estimate");
  if (!e.initialised) return;
  const Rgba colour = e.lost ? kGrey : kGreen;
  foxglove::SpherePrimitive& centre = *entity.add_spheres();
  setPose(*centre.mutable_pose(), e.p_WT_m);
  setVector(*centre.mutable_size(), Eigen::Vector3d::Constant(0.25));
  setColor(*centre.mutable_color(), colour);
  // The 2-sigma ellipsoid of the position: axes along the covariance's eigenvectors.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(e.covariance.topLeftCorner<3, 3>());
  Eigen::Matrix3d axes = eig.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  foxglove::SpherePrimitive& ellipsoid = *entity.add_spheres();
  setPose(*ellipsoid.mutable_pose(), e.p_WT_m, Eigen::Quaterniond(axes));
  setVector(*ellipsoid.mutable_size(), 4.0 * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt());
  setColor(*ellipsoid.mutable_color(), Rgba{colour.r, colour.g, colour.b, 0.25});
  const double speed_mps = e.v_WT_mps.norm();
  if (speed_mps > 1e-3) {
    foxglove::ArrowPrimitive& arrow = *entity.add_arrows();
    const Eigen::Quaterniond along = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), e.v_WT_mps);
    setPose(*arrow.mutable_pose(), e.p_WT_m, along);
    arrow.set_shaft_length(speed_mps);
    arrow.set_shaft_diameter(0.05);
    arrow.set_head_length(0.15);
    arrow.set_head_diameter(0.12);
    setColor(*arrow.mutable_color(), colour);
  }
  for (std::size_t i = 0; i < std::min(e.other_count, e.others.size()); ++i) {
    foxglove::SpherePrimitive& other = *entity.add_spheres();
    setPose(*other.mutable_pose(), e.others[i].p_W_m);
    setVector(*other.mutable_size(), Eigen::Vector3d::Constant(0.2));
    setColor(*other.mutable_color(), kBlue);
  }
}

namespace {

/// The trajectory's line (cyan, 6 cm), points added by the caller.
foxglove::LinePrimitive& addTrajectoryLine(foxglove::SceneEntity& entity) {
  foxglove::LinePrimitive& line = *entity.add_lines();
  line.set_type(foxglove::LinePrimitive::LINE_STRIP);
  setPose(*line.mutable_pose(), Eigen::Vector3d::Zero());
  line.set_thickness(0.06);
  setColor(*line.mutable_color(), Rgba{0.1, 0.8, 0.9, 1.0});
  return line;
}

}  // namespace

void fillTrajectoryPoints(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, std::span<const Eigen::Vector3d> points_W_m) {
  m.Clear();
  foxglove::LinePrimitive& line = addTrajectoryLine(addEntity(m, stamp_ns, "plan/trajectory"));
  for (const Eigen::Vector3d& p : points_W_m) setPoint(*line.add_points(), p);
}

void fillTrajectory(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, const trajectory_server::TimedTrajectory& t,
                    int samples) {
  m.Clear();
  foxglove::SceneEntity& entity = addEntity(m, stamp_ns, "plan/trajectory");
  if (!t.trajectory) return;
  foxglove::LinePrimitive& line = addTrajectoryLine(entity);
  const double duration_s = t.trajectory->durationS();
  for (int i = 0; i <= samples; ++i) {
    setPoint(*line.add_points(), t.trajectory->sample(duration_s * i / samples).p_W_m);
  }
}

void fillPlan(foxglove::SceneUpdate& m, const planning::PlanSnapshot& plan) {
  m.Clear();
  foxglove::SceneEntity& corridor = addEntity(m, plan.stamp_ns, "plan/corridor");
  for (std::size_t i = 0; i < plan.box_count; ++i) {
    foxglove::CubePrimitive& cube = *corridor.add_cubes();
    setPose(*cube.mutable_pose(), 0.5 * (plan.box_lo_W_m[i] + plan.box_hi_W_m[i]));
    setVector(*cube.mutable_size(), plan.box_hi_W_m[i] - plan.box_lo_W_m[i]);
    setColor(*cube.mutable_color(), Rgba{0.4, 0.6, 1.0, 0.12});
  }
  auto polyline = [&](const char* id, std::span<const Eigen::Vector3d> points, const Rgba& colour) {
    foxglove::SceneEntity& entity = addEntity(m, plan.stamp_ns, id);
    if (points.size() < 2) return;
    foxglove::LinePrimitive& line = *entity.add_lines();
    line.set_type(foxglove::LinePrimitive::LINE_STRIP);
    setPose(*line.mutable_pose(), Eigen::Vector3d::Zero());
    line.set_thickness(0.04);
    setColor(*line.mutable_color(), colour);
    for (const Eigen::Vector3d& p : points) setPoint(*line.add_points(), p);
  };
  polyline("plan/search", std::span(plan.search_W_m.data(), plan.search_count), Rgba{1.0, 0.3, 0.9, 1.0});
  polyline("person/predict", std::span(plan.prediction_W_m.data(), plan.prediction_count), kYellow);
}

void fillPathSegment(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, int index,
                     std::span<const Eigen::Vector3d> points_W_m) {
  m.Clear();
  foxglove::SceneEntity& entity = addEntity(m, stamp_ns, "path/" + std::to_string(index));
  foxglove::LinePrimitive& line = *entity.add_lines();
  line.set_type(foxglove::LinePrimitive::LINE_STRIP);
  setPose(*line.mutable_pose(), Eigen::Vector3d::Zero());
  line.set_thickness(0.04);
  setColor(*line.mutable_color(), Rgba{0.3, 0.9, 0.3, 1.0});
  for (const Eigen::Vector3d& p : points_W_m) setPoint(*line.add_points(), p);
}

bool FlownPath::add(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WB_m, foxglove::SceneUpdate& scene) {
  if (start_ns_ < 0) start_ns_ = stamp_ns;
  last_ns_ = stamp_ns;
  points_W_m_.push_back(p_WB_m);
  if (rt::nsToSeconds(stamp_ns - start_ns_) < stretch_s_ || points_W_m_.size() < 2) return false;
  fillPathSegment(scene, stamp_ns, stretches_++, points_W_m_);
  points_W_m_.erase(points_W_m_.begin(), points_W_m_.end() - 1);  // keeps the capacity
  start_ns_ = stamp_ns;
  return true;
}

bool FlownPath::flush(foxglove::SceneUpdate& scene) {
  if (points_W_m_.size() < 2) return false;
  fillPathSegment(scene, last_ns_, stretches_++, points_W_m_);
  points_W_m_.erase(points_W_m_.begin(), points_W_m_.end() - 1);
  return true;
}

void fillDepthPoints(foxglove::PointCloud& m, const hal::DepthFrame& frame, int step) {
  setTime(*m.mutable_timestamp(), frame.stamp_ns);
  m.set_frame_id("depth_optical");
  setPose(*m.mutable_pose(), Eigen::Vector3d::Zero());
  m.set_point_stride(12);
  if (m.fields_size() != 3) {
    m.clear_fields();
    const char* names[] = {"x", "y", "z"};
    for (std::uint32_t i = 0; i < 3; ++i) {
      foxglove::PackedElementField& field = *m.add_fields();
      field.set_name(names[i]);
      field.set_offset(4 * i);
      field.set_type(foxglove::PackedElementField::FLOAT32);
    }
  }
  std::string& data = *m.mutable_data();
  data.clear();  // keeps its capacity
  const hal::CameraIntrinsics& k = frame.intrinsics;
  if (frame.depth_m.type() != CV_32FC1 || k.fx_px <= 0.0 || k.fy_px <= 0.0) return;
  for (int v = 0; v < frame.depth_m.rows; v += step) {
    const float* row = frame.depth_m.ptr<float>(v);
    for (int u = 0; u < frame.depth_m.cols; u += step) {
      const float z = row[u];
      if (!(z > 0.0F) || !std::isfinite(z)) continue;
      const float xyz[3] = {static_cast<float>((u - k.cx_px) / k.fx_px * static_cast<double>(z)),
                            static_cast<float>((v - k.cy_px) / k.fy_px * static_cast<double>(z)), z};
      data.append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
    }
  }
}

void fillOccupied(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, const mapping::LocalGrid& grid) {
  m.Clear();
  foxglove::SceneEntity& entity = addEntity(m, stamp_ns, "map/occupied");
  const double cell_m = grid.params().resolution_m;
  const mapping::CellIndex lo = grid.windowMinCell();
  const mapping::CellIndex size = grid.windowSizeCells();
  for (int x = 0; x < size.x(); ++x) {
    for (int y = 0; y < size.y(); ++y) {
      for (int z = 0; z < size.z(); ++z) {
        const mapping::CellIndex cell = lo + mapping::CellIndex(x, y, z);
        if (grid.cellState(cell) != mapping::CellState::kOccupied) continue;
        foxglove::CubePrimitive& cube = *entity.add_cubes();
        setPose(*cube.mutable_pose(), grid.cellCenterM(cell));
        setVector(*cube.mutable_size(), Eigen::Vector3d::Constant(cell_m));
        // Coloured by height, as map views usually are.
        const double h = std::clamp(grid.cellCenterM(cell).z() / 4.0, 0.0, 1.0);
        setColor(*cube.mutable_color(), Rgba{0.9 - 0.6 * h, 0.3 + 0.3 * h, 0.2 + 0.7 * h, 0.9});
      }
    }
  }
}

void fillObstacles(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, const hal::sim::ObstacleWorld& world) {
  m.Clear();
  foxglove::SceneEntity& entity = addEntity(m, stamp_ns, "sim/obstacles");
  const Rgba colour{0.55, 0.45, 0.35, 0.6};
  for (const hal::sim::Box& box : world.boxes()) {
    foxglove::CubePrimitive& cube = *entity.add_cubes();
    setPose(*cube.mutable_pose(), 0.5 * (box.min_W_m + box.max_W_m));
    setVector(*cube.mutable_size(), box.max_W_m - box.min_W_m);
    setColor(*cube.mutable_color(), colour);
  }
  for (const hal::sim::Cylinder& c : world.cylinders()) {
    foxglove::CylinderPrimitive& cylinder = *entity.add_cylinders();
    setPose(*cylinder.mutable_pose(),
            Eigen::Vector3d(c.center_W_m.x(), c.center_W_m.y(), 0.5 * (c.z_min_m + c.z_max_m)));
    setVector(*cylinder.mutable_size(), Eigen::Vector3d(2.0 * c.radius_m, 2.0 * c.radius_m, c.z_max_m - c.z_min_m));
    cylinder.set_bottom_scale(1.0);
    cylinder.set_top_scale(1.0);
    setColor(*cylinder.mutable_color(), colour);
  }
}

void fillTruth(foxglove::SceneUpdate& m, const hal::sim::TruthSnapshot& truth) {
  m.Clear();
  foxglove::SceneEntity& entity = addEntity(m, truth.stamp_ns, "sim/truth");
  foxglove::CylinderPrimitive& person = *entity.add_cylinders();
  // The truth is the ground point under the pelvis (hal/sim/person); drawn as a 1.75 m body above it
  // (the snapshot carries no height: a picture, not a measurement).
  setPose(*person.mutable_pose(), truth.person_p_W_m + Eigen::Vector3d(0.0, 0.0, 0.875));
  setVector(*person.mutable_size(), Eigen::Vector3d(0.45, 0.45, 1.75));
  person.set_bottom_scale(1.0);
  person.set_top_scale(1.0);
  setColor(*person.mutable_color(), kYellow);
  foxglove::SpherePrimitive& drone = *entity.add_spheres();
  setPose(*drone.mutable_pose(), truth.drone_p_W_m);
  setVector(*drone.mutable_size(), Eigen::Vector3d::Constant(0.3));
  setColor(*drone.mutable_color(), Rgba{1.0, 1.0, 1.0, 0.5});
}

std::string_view estimateJson(const estimation::TargetEstimate& e, JsonLine& out) {
  return out.boolean("initialised", e.initialised)
      .boolean("lost", e.lost)
      .vector3("p_WT_m", e.p_WT_m)
      .vector3("v_WT_mps", e.v_WT_mps)
      .number("sigma_p_m", std::sqrt(std::max(0.0, e.covariance.topLeftCorner<3, 3>().trace())))
      .number("manoeuvre_probability", e.manoeuvre_probability)
      .number("measurement_age_s", rt::nsToSeconds(e.stamp_ns - e.last_accepted_ns))
      .integer("other_people", static_cast<std::int64_t>(e.other_count))
      .view();
}

std::string_view setpointJson(const hal::Setpoint& s, JsonLine& out) {
  return out.vector3("p_W_m", s.p_W_m)
      .vector3("v_W_mps", s.v_W_mps)
      .vector3("a_W_mps2", s.a_W_mps2)
      .number("speed_mps", s.v_W_mps.norm())
      .number("yaw_rad", s.yaw_rad)
      .number("yaw_rate_radps", s.yaw_rate_radps)
      .view();
}

std::string_view gimbalCommandJson(const hal::GimbalCommand& c, JsonLine& out) {
  return out.text("mode", c.mode == hal::GimbalCommand::Mode::kRate ? "rate" : "angle")
      .number("rate_radps", c.rate_radps)
      .number("angle_rad", c.angle_rad)
      .number("max_rate_radps", c.max_rate_radps)
      .view();
}

std::string_view planCycleJson(const planning::PlanSnapshot& plan, JsonLine& out) {
  const planning::PlanReport& r = plan.report;
  return out.text("status", planning::toString(r.status))
      .text("search", planning::toString(r.search_status))
      .integer("search_expansions", r.search_expansions)
      .integer("corridor_boxes", r.corridor_boxes)
      .integer("optimizer_iterations", r.optimizer_iterations)
      .text("check", planning::toString(r.check))
      .number("repair_stretch", r.repair_stretch)
      .boolean("predicted", r.predicted)
      .number("cycle_ms", plan.cycle_ms)
      .view();
}

std::string_view supervisorJson(const supervisor::SupervisorState& state, JsonLine& out) {
  return out.text("mode", supervisor::toString(state.mode))
      .text("reason", supervisor::toString(state.reason))
      .number("since_s", rt::nsToSeconds(state.since_ns))
      .integer("transitions", static_cast<std::int64_t>(state.transitions))
      .view();
}

std::string_view truthJson(const hal::sim::TruthSnapshot& truth, const estimation::TargetEstimate* live_estimate,
                           JsonLine& out) {
  out.vector3("person_p_W_m", truth.person_p_W_m)
      .vector3("drone_p_W_m", truth.drone_p_W_m)
      .number("distance_m", (truth.drone_p_W_m - truth.person_p_W_m).head<2>().norm());
  // The estimate's error against the truth while it is live: what a plot wants most.
  if (live_estimate != nullptr)
    out.number("estimate_error_m", (live_estimate->p_WT_m - truth.person_p_W_m).head<2>().norm());
  return out.view();
}

}  // namespace aerotrack::app::foxglove_log
