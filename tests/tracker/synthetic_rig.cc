#include "tests/tracker/synthetic_rig.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <sstream>
#include <stdexcept>

#include "core/lcm_util.h"
#include "core/math.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace tracker_test {
namespace {

// Marker frame on a cube face with outward normal n (object = cube centre).
Rigid3 FaceMarker(const Eigen::Vector3d& n, const Eigen::Vector3d& up_hint, double half_side) {
  const Eigen::Vector3d z = n.normalized();
  const Eigen::Vector3d x = up_hint.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Rigid3 t = Rigid3::Identity();
  t.linear().col(0) = x;
  t.linear().col(1) = y;
  t.linear().col(2) = z;
  t.translation() = z * half_side;
  return t;
}

}  // namespace

double TranslationError(const Rigid3& a, const Rigid3& b) {
  return (a.translation() - b.translation()).norm();
}

double RotationError(const Rigid3& a, const Rigid3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

std::vector<detections_t> Detect(const RigMap& map, const Rigid3& rig_from_object, int64_t utime, int64_t seq,
                                 double noise_px, std::mt19937_64* rng) {
  std::normal_distribution<double> noise(0.0, noise_px);
  std::vector<detections_t> out;
  for (const auto& cam : map.cameras) {
    detections_t d;
    d.utime = utime;
    d.seq = seq;
    d.camera = cam.name;
    d.dictionary = map.dictionary;
    d.camera_model = ToCameraModelMsg(cam.model);
    d.detection_ms = 1.0;
    const Rigid3 cam_from_object = Inverse(cam.rig_from_cam) * rig_from_object;
    for (const auto& mk : map.markers) {
      const Rigid3 cam_from_marker = cam_from_object * mk.object_from_marker;
      const Eigen::Vector3d normal = cam_from_marker.linear().col(2);
      const Eigen::Vector3d to_cam = -cam_from_marker.translation().normalized();
      if (normal.dot(to_cam) < std::cos(75.0 * M_PI / 180.0)) continue;  // facing away or too oblique
      const MarkerCorners3d corners = MarkerCornersInMarker(mk.size);
      marker_t m;
      m.id = mk.id;
      bool ok = true;
      for (int k = 0; k < 4; ++k) {
        Eigen::Vector2d px;
        if (!cam.model.Project(cam_from_marker * corners[k], &px, nullptr) || !cam.model.InImage(px, 2.0)) {
          ok = false;
          break;
        }
        m.corners[k][0] = px.x() + (noise_px > 0 ? noise(*rng) : 0.0);
        m.corners[k][1] = px.y() + (noise_px > 0 ? noise(*rng) : 0.0);
      }
      if (ok) d.markers.push_back(m);
    }
    d.num_markers = static_cast<int32_t>(d.markers.size());
    out.push_back(d);
  }
  return out;
}

SyntheticSession MakeSession(const SyntheticOptions& o) {
  SyntheticSession s;
  std::mt19937_64 rng(o.seed);
  // Cameras.
  std::vector<Rigid3> world_from_cam;
  for (int c = 0; c < o.cameras; ++c) {
    const double a = 2.0 * M_PI * c / std::max(1, o.cameras) + 0.1;
    world_from_cam.push_back(LookAt(Eigen::Vector3d(o.radius * std::cos(a), o.radius * std::sin(a), o.height),
                                    Eigen::Vector3d::Zero()));
  }
  const Rigid3 rig_from_world = Inverse(world_from_cam[0]);
  s.map.dictionary = "DICT_6X6_250";
  s.map.reference_camera = "cam0";
  s.map.reference_marker = 0;
  for (int c = 0; c < o.cameras; ++c) {
    MapCamera cam;
    cam.name = "cam" + std::to_string(c);
    cam.model.width = 640;
    cam.model.height = 480;
    cam.model.fx = 554.0 + 3.0 * c;
    cam.model.fy = 554.0 + 3.0 * c;
    cam.model.cx = 320.0 + c;
    cam.model.cy = 240.0 - c;
    if (o.distortion && c % 2 == 1) {
      cam.model.model = DistortionModel::kRadTan;
      cam.model.distortion = {-0.12, 0.05, 0.0005, -0.0003, 0.0};
    }
    cam.rig_from_cam = Normalized(rig_from_world * world_from_cam[c]);
    s.map.cameras.push_back(cam);
  }
  // Cube markers (grid x grid per face); object frame = marker 0's.
  const double h = 0.5 * o.cube_side;
  const std::vector<Rigid3> cube_from_face = {
      FaceMarker({0, 0, 1}, {0, 1, 0}, h),  FaceMarker({1, 0, 0}, {0, 0, 1}, h),
      FaceMarker({0, 1, 0}, {0, 0, 1}, h),  FaceMarker({-1, 0, 0}, {0, 0, 1}, h),
      FaceMarker({0, -1, 0}, {0, 0, 1}, h), FaceMarker({0, 0, -1}, {0, 1, 0}, h)};
  std::vector<Rigid3> cube_from_marker;
  const int rows = o.grid_rows > 0 ? o.grid_rows : o.grid;
  const double pitch_x = o.cube_side / o.grid, pitch_y = o.cube_side / rows;
  for (const Rigid3& face : cube_from_face) {
    for (int gy = 0; gy < rows; ++gy) {
      for (int gx = 0; gx < o.grid; ++gx) {
        Rigid3 offset = Rigid3::Identity();
        offset.translation() = Eigen::Vector3d((gx + 0.5) * pitch_x - h, h - (gy + 0.5) * pitch_y, 0.0);
        cube_from_marker.push_back(face * offset);
      }
    }
  }
  const Rigid3 object_from_cube = Inverse(cube_from_marker[0]);
  for (size_t m = 0; m < cube_from_marker.size(); ++m) {
    MapMarker mk;
    mk.id = static_cast<int>(m);
    mk.size = o.marker_size;
    mk.object_from_marker = Normalized(object_from_cube * cube_from_marker[m]);
    s.map.markers.push_back(mk);
  }
  // Trajectory: the cube wanders around the centre, turning and tilting.
  std::uniform_real_distribution<double> phase(0, 2 * M_PI);
  const double p1 = phase(rng), p2 = phase(rng), p3 = phase(rng);
  for (int f = 0; f < o.frames; ++f) {
    const double t = f / o.fps;
    Rigid3 world_from_cube = Rigid3::Identity();
    world_from_cube.translation() = Eigen::Vector3d(
        0.12 * std::sin(0.7 * t + p1), 0.10 * std::sin(0.9 * t + p2), 0.06 * std::sin(1.3 * t + p3));
    world_from_cube.linear() = (Eigen::AngleAxisd(0.8 * t + p1, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(0.5 * std::sin(0.6 * t + p2), Eigen::Vector3d::UnitX()) *
                                Eigen::AngleAxisd(0.4 * std::sin(0.4 * t + p3), Eigen::Vector3d::UnitY()))
                                   .toRotationMatrix();
    const Rigid3 rig_from_object = Normalized(rig_from_world * world_from_cube * cube_from_marker[0]);
    const int64_t utime = 1000000000000LL + static_cast<int64_t>(std::llround(f * 1e6 / o.fps));
    s.utimes.push_back(utime);
    s.rig_from_object.push_back(rig_from_object);
    s.views.push_back(Detect(s.map, rig_from_object, utime, f, o.noise_px, &rng));
  }
  return s;
}

std::string WriteRigFiles(const std::string& dir, const RigMap& map, const std::string& extra_yaml) {
  std::ostringstream y;
  y << "markers:\n  dictionary: " << map.dictionary << "\n  size: " << map.markers.front().size
    << "\ncameras:\n";
  for (const auto& c : map.cameras) {
    WriteIntrinsicsOpenCv(dir + "/" + c.name + ".yml", c.model);
    y << "  - name: " << c.name << "\n    intrinsics: " << c.name << ".yml\n    source: " << c.name << "/\n";
  }
  y << extra_yaml;
  const std::string path = dir + "/rig.yaml";
  WriteFileAtomic(path, y.str());
  return path;
}

void WriteLog(const std::string& path, const SyntheticSession& session, int kill_camera,
              int kill_from_frame) {
  lcm::LogFile log(path, "w");
  if (!log.good()) throw std::runtime_error("cannot write " + path);
  int64_t event = 0;
  for (size_t f = 0; f < session.views.size(); ++f) {
    for (size_t c = 0; c < session.views[f].size(); ++c) {
      if (static_cast<int>(c) == kill_camera && static_cast<int>(f) >= kill_from_frame) continue;
      const detections_t& d = session.views[f][c];
      std::vector<uint8_t> bytes = Encode(d);
      const std::string channel = DetectionsChannel(d.camera);
      lcm::LogEvent e;
      e.eventnum = event++;
      e.timestamp = d.utime + static_cast<int64_t>(c) * 100;  // detectors finish a little apart
      e.channel = channel;
      e.datalen = static_cast<int32_t>(bytes.size());
      e.data = bytes.data();
      log.writeEvent(&e);
    }
  }
}

std::string MakeTempDir(const std::string& name) { return mcmt::test::MakeTempDir("tracker_" + name); }

}  // namespace tracker_test
}  // namespace mcmt
