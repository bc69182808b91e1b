#include "tests/mapper/synth.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

#include "core/config.h"
#include "core/lcm_util.h"
#include "core/marker.h"
#include "core/math.h"
#include "mcmt/mapper_command_t.hpp"

namespace mcmt {
namespace testing {
namespace {

Rigid3 FacePose(const Eigen::Vector3d& normal, const Eigen::Vector3d& centre) {
  Rigid3 pose = Rigid3::Identity();
  const Eigen::Vector3d z = normal.normalized();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  if (std::abs(z.dot(up)) > 0.9) up = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d y = (up - up.dot(z) * z).normalized();
  const Eigen::Vector3d x = y.cross(z);
  pose.linear().col(0) = x;
  pose.linear().col(1) = y;
  pose.linear().col(2) = z;
  pose.translation() = centre;
  return pose;
}

Eigen::Matrix3d Rot(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// Visible corners of a marker at cam_from_marker, or false.
bool Visible(const CameraModel& model, const Rigid3& cam_from_marker, double side, MarkerCorners2d* corners) {
  const MarkerCorners3d c3 = MarkerCornersInMarker(side);
  const Eigen::Vector3d centre = cam_from_marker.translation();
  const Eigen::Vector3d normal = cam_from_marker.linear().col(2);
  if (centre.z() <= 0.05) return false;
  if (-normal.dot(centre.normalized()) < std::cos(75.0 * M_PI / 180.0)) return false;
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector2d px;
    if (!model.Project(cam_from_marker * c3[k], &px, nullptr)) return false;
    if (!model.InImage(px, 2.0)) return false;
    (*corners)[k] = px;
  }
  return true;
}

marker_t MakeMarker(int id, const MarkerCorners2d& corners) {
  marker_t m;
  m.id = id;
  for (int k = 0; k < 4; ++k) {
    m.corners[k][0] = corners[k].x();
    m.corners[k][1] = corners[k].y();
  }
  return m;
}

}  // namespace

SynthScene MakeScene(const SynthOptions& o) {
  SynthScene scene;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> noise(0.0, o.noise_px);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int c = 0; c < o.cameras; ++c) {
    const double a = 2 * M_PI * c / o.cameras + 0.1;
    scene.names.push_back("cam" + std::to_string(c));
    CameraModel model;
    model.width = 640;
    model.height = 480;
    model.fx = 600 + 10 * c;
    model.fy = 600 + 10 * c;
    model.cx = 319.5 + c;
    model.cy = 239.5 - c;
    if (o.radtan_k1 != 0) {
      model.model = DistortionModel::kRadTan;
      model.distortion = {o.radtan_k1, 0.02, 0.001, -0.001, 0.0};
    }
    scene.models.push_back(model);
    scene.rig_from_cam.push_back(
        LookAt(Eigen::Vector3d(o.radius * std::cos(a), o.radius * std::sin(a), o.camera_height),
               Eigen::Vector3d(0, 0, 0)));
  }
  // Object: a prism with `sides` faces, markers_per_side stacked vertically on each.
  int next_id = 1;
  for (int k = 0; k < o.sides; ++k) {
    const double theta = 2 * M_PI * k / o.sides;
    const Eigen::Vector3d n(std::cos(theta), std::sin(theta), 0);
    for (int j = 0; j < o.markers_per_side; ++j) {
      const double z =
          o.markers_per_side == 1 ? 0.0 : (j - 0.5 * (o.markers_per_side - 1)) * (o.marker_size + 0.01);
      scene.ids.push_back(next_id);
      next_id += 3;
      scene.object_from_marker.push_back(FacePose(n, o.side_half_width * n + Eigen::Vector3d(0, 0, z)));
    }
  }
  // Trajectory.
  const double ph[6] = {uniform(rng) * 6, uniform(rng) * 6, uniform(rng) * 6,
                        uniform(rng) * 6, uniform(rng) * 6, uniform(rng) * 6};
  const double reach = 0.12 * o.radius;
  for (int t = 0; t < o.frames; ++t) {
    Rigid3 pose = Rigid3::Identity();
    const double yaw = 3 * M_PI * t / std::max(1, o.frames - 1) + 0.3 * std::sin(0.05 * t + ph[0]);
    pose.linear() = Rot(yaw, 0.35 * std::sin(0.11 * t + ph[1]), 0.3 * std::sin(0.07 * t + ph[2]));
    pose.translation() =
        Eigen::Vector3d(reach * std::sin(0.031 * t + ph[3]), reach * std::sin(0.023 * t + ph[4]),
                        0.5 * reach * std::sin(0.041 * t + ph[5]));
    scene.rig_from_object.push_back(pose);
    scene.utimes.push_back(1000000000000LL + t * o.frame_period_us);
  }
  const Rigid3 rig_from_static = FacePose(Eigen::Vector3d(0.2, 0.3, 1.0), Eigen::Vector3d(0.25, -0.1, -0.15));
  for (int t = 0; t < o.frames; ++t) {
    for (int c = 0; c < o.cameras; ++c) {
      if (o.drop_rate > 0 && uniform(rng) < o.drop_rate) continue;
      detections_t d;
      d.utime = scene.utimes[t] + c * o.camera_jitter_us;
      d.seq = t;
      d.camera = scene.names[c];
      d.dictionary = "DICT_6X6_250";
      d.camera_model = ToCameraModelMsg(scene.models[c]);
      d.detection_ms = 1.0;
      const Rigid3 cam_from_rig = Inverse(scene.rig_from_cam[c]);
      for (size_t m = 0; m < scene.ids.size(); ++m) {
        MarkerCorners2d corners;
        if (!Visible(scene.models[c], cam_from_rig * scene.rig_from_object[t] * scene.object_from_marker[m],
                     o.marker_size, &corners))
          continue;
        for (auto& p : corners) p += Eigen::Vector2d(noise(rng), noise(rng));
        d.markers.push_back(MakeMarker(scene.ids[m], corners));
      }
      if (o.static_false_id >= 0) {
        MarkerCorners2d corners;
        if (Visible(scene.models[c], cam_from_rig * rig_from_static, o.marker_size, &corners)) {
          for (auto& p : corners) p += Eigen::Vector2d(noise(rng), noise(rng));
          d.markers.push_back(MakeMarker(o.static_false_id, corners));
          ++scene.false_detections;
        }
      }
      if (o.false_rate > 0 && uniform(rng) < o.false_rate) {
        const int id = 200 + static_cast<int>(uniform(rng) * 50);
        const Eigen::Vector2d centre(60 + uniform(rng) * 520, 60 + uniform(rng) * 360);
        const double half = 10 + uniform(rng) * 20, angle = uniform(rng) * 2 * M_PI;
        MarkerCorners2d corners;
        for (int k = 0; k < 4; ++k) {
          const double a = angle - k * M_PI / 2;
          corners[k] = centre + half * std::sqrt(2.0) * Eigen::Vector2d(std::cos(a), std::sin(a)) +
                       Eigen::Vector2d(uniform(rng) * 4 - 2, uniform(rng) * 4 - 2);
        }
        d.markers.push_back(MakeMarker(id, corners));
        ++scene.false_detections;
        if (std::find(scene.false_ids.begin(), scene.false_ids.end(), id) == scene.false_ids.end())
          scene.false_ids.push_back(id);
      }
      d.num_markers = static_cast<int32_t>(d.markers.size());
      scene.detections.push_back(d);
    }
  }
  if (o.static_false_id >= 0) scene.false_ids.push_back(o.static_false_id);
  return scene;
}

MapperOptions SceneMapperOptions(const SynthScene& scene, double marker_size) {
  MapperOptions options;
  options.cameras = scene.names;
  options.sizes.default_size = marker_size;
  options.dictionary = "DICT_6X6_250";
  options.sync_tolerance_ms = 5.0;
  return options;
}

MapErrors CompareToTruth(const SynthScene& scene, const RigMap& map,
                         const std::vector<TrajectoryRow>& trajectory, double marker_size) {
  MapErrors e;
  // Cameras: align the estimated centres to the true ones.
  std::vector<Eigen::Vector3d> est, gt;
  std::vector<Rigid3> est_pose, gt_pose;
  for (const MapCamera& c : map.cameras) {
    const auto it = std::find(scene.names.begin(), scene.names.end(), c.name);
    if (it == scene.names.end()) continue;
    const Rigid3& truth = scene.rig_from_cam[it - scene.names.begin()];
    est.push_back(c.rig_from_cam.translation());
    gt.push_back(truth.translation());
    est_pose.push_back(c.rig_from_cam);
    gt_pose.push_back(truth);
  }
  e.cameras_compared = static_cast<int>(est.size());
  const Rigid3 world_from_rig = AlignRigid(est, gt);
  for (size_t i = 0; i < est.size(); ++i) {
    e.camera_position_m = std::max(e.camera_position_m, (world_from_rig * est[i] - gt[i]).norm());
    e.camera_rotation_deg =
        std::max(e.camera_rotation_deg, RotationAngle(world_from_rig * est_pose[i], gt_pose[i]) * 180 / M_PI);
  }
  // Markers: align all corners.
  std::vector<Eigen::Vector3d> est_c, gt_c;
  const MarkerCorners3d corners = MarkerCornersInMarker(marker_size);
  for (const MapMarker& m : map.markers) {
    const auto it = std::find(scene.ids.begin(), scene.ids.end(), m.id);
    if (it == scene.ids.end()) continue;
    const Rigid3& truth = scene.object_from_marker[it - scene.ids.begin()];
    for (const auto& u : corners) {
      est_c.push_back(m.object_from_marker * u);
      gt_c.push_back(truth * u);
    }
    ++e.markers_compared;
  }
  const Rigid3 body_from_object = AlignRigid(est_c, gt_c);
  for (size_t i = 0; i < est_c.size(); ++i)
    e.configuration_m = std::max(e.configuration_m, (body_from_object * est_c[i] - gt_c[i]).norm());
  // Object poses: the estimate in body terms, aligned to the true trajectory.
  std::vector<Eigen::Vector3d> est_t, gt_t;
  std::vector<Rigid3> est_p, gt_p;
  for (const TrajectoryRow& row : trajectory) {
    const auto it = std::find(scene.utimes.begin(), scene.utimes.end(), row.utime);
    if (it == scene.utimes.end()) continue;
    const Rigid3 estimate = row.rig_from_object * Inverse(body_from_object);
    est_p.push_back(estimate);
    gt_p.push_back(scene.rig_from_object[it - scene.utimes.begin()]);
    est_t.push_back(estimate.translation());
    gt_t.push_back(gt_p.back().translation());
  }
  e.frames_compared = static_cast<int>(est_t.size());
  if (!est_t.empty()) {
    const Rigid3 align = AlignRigid(est_t, gt_t);
    for (size_t i = 0; i < est_t.size(); ++i) {
      const double d = (align * est_t[i] - gt_t[i]).norm();
      e.object_translation_m += d / est_t.size();
      e.object_translation_max_m = std::max(e.object_translation_max_m, d);
      e.object_rotation_deg += RotationAngle(align * est_p[i], gt_p[i]) * 180 / M_PI / est_t.size();
    }
  }
  return e;
}

std::string WriteSceneRig(const std::string& dir, const SynthScene& scene, double marker_size,
                          const std::string& extra) {
  std::ofstream rig(dir + "/rig.yaml");
  rig << "markers:\n  dictionary: DICT_6X6_250\n  size: " << marker_size << "\ncameras:\n";
  for (size_t c = 0; c < scene.names.size(); ++c) {
    WriteIntrinsicsOpenCv(dir + "/" + scene.names[c] + ".yml", scene.models[c]);
    rig << "  - name: " << scene.names[c] << "\n    intrinsics: " << scene.names[c] << ".yml\n";
  }
  rig << "sync:\n  tolerance_ms: 5\n" << extra;
  return dir + "/rig.yaml";
}

bool WriteSceneLog(const std::string& path, const SynthScene& scene, bool add_foreign) {
  lcm::LogFile log(path, "w");
  if (!log.good()) return false;
  int64_t event = 0;
  bool ok = true;
  auto write = [&](const std::string& channel, const std::vector<uint8_t>& data, int64_t utime) {
    lcm::LogEvent e;
    e.eventnum = event++;
    e.timestamp = utime;
    e.channel = channel;
    e.datalen = static_cast<int32_t>(data.size());
    e.data = const_cast<uint8_t*>(data.data());
    ok = ok && log.writeEvent(&e) == 0;
  };
  for (size_t i = 0; i < scene.detections.size(); ++i) {
    const detections_t& d = scene.detections[i];
    write(DetectionsChannel(d.camera), Encode(d), d.utime);
    if (add_foreign && i == 3) {
      mapper_command_t other;
      other.utime = d.utime;
      other.command = "not detections";
      write(DetectionsChannel("cam0"), Encode(other), d.utime);
    }
  }
  return ok;
}

}  // namespace testing
}  // namespace mcmt
