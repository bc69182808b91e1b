#include "core/map_export.h"

#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <opencv2/core.hpp>
#include <utility>

#include "core/marker.h"
#include "core/se3.h"

namespace mcmt {
namespace {

void EmitMatrixRows(YAML::Emitter& y, const Eigen::Matrix4d& m) {
  y << YAML::BeginSeq;
  for (int r = 0; r < 4; ++r) {
    y << YAML::Flow << YAML::BeginSeq;
    for (int c = 0; c < 4; ++c) y << m(r, c);
    y << YAML::EndSeq;
  }
  y << YAML::EndSeq;
}

void EmitFlowList(YAML::Emitter& y, const std::vector<double>& values) {
  y << YAML::Flow << YAML::BeginSeq;
  for (double v : values) y << v;
  y << YAML::EndSeq;
}

std::string FinishYaml(const YAML::Emitter& y, const std::string& what) {
  if (!y.good()) throw std::runtime_error(what + ": cannot emit YAML: " + y.GetLastError());
  return std::string(y.c_str()) + "\n";
}

cv::Mat ToCvMat(const Eigen::Matrix4d& m) {
  cv::Mat out(4, 4, CV_64F);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.at<double>(r, c) = m(r, c);
  return out;
}

// The camera's coefficients as a format with `count` of them (missing ones are zero, which is exact);
// refuses a non-zero coefficient beyond `count`. `names` names the coefficients, for the message.
std::vector<double> Coefficients(const std::string& format, const MapCamera& camera, size_t count,
                                 const std::vector<std::string>& names, const std::string& why) {
  const std::vector<double>& d = camera.model.distortion;
  for (size_t k = count; k < d.size(); ++k)
    if (d[k] != 0.0)
      throw MapExportRefused(format + ": camera " + camera.name + ": " +
                             DistortionModelName(camera.model.model) + " coefficient " +
                             (k < names.size() ? names[k] : "#" + std::to_string(k + 1)) + " = " +
                             YamlNumber(d[k]) + " cannot be written (" + why + ")");
  std::vector<double> out(d.begin(), d.begin() + static_cast<long>(std::min(count, d.size())));
  out.resize(count, 0.0);
  return out;
}

const std::vector<std::string> kRadTanNames = {"k1", "k2", "p1", "p2", "k3", "k4",    "k5",
                                               "k6", "s1", "s2", "s3", "s4", "tau_x", "tau_y"};
const std::vector<std::string> kFisheyeNames = {"k1", "k2", "k3", "k4"};

// Kalibr distortion model name and coefficients of one camera.
std::pair<std::string, std::vector<double>> KalibrDistortion(const MapCamera& c) {
  const std::string format = "Kalibr camchain";
  switch (c.model.model) {
    case DistortionModel::kNone:
      return {"radtan", std::vector<double>(4, 0.0)};  // the same pixels
    case DistortionModel::kRadTan:
      return {"radtan",
              Coefficients(format, c, 4, kRadTanNames, "Kalibr's radtan has 4 coefficients, k1 k2 p1 p2")};
    case DistortionModel::kFisheye:
      return {"equidistant", Coefficients(format, c, 4, kFisheyeNames, "Kalibr's equidistant has k1..k4")};
  }
  throw MapExportRefused(format + ": camera " + c.name + ": unknown distortion model");
}

// ROS camera_info distortion model name and coefficients.
std::pair<std::string, std::vector<double>> RosDistortion(const MapCamera& c) {
  const std::string format = "ROS camera_info";
  switch (c.model.model) {
    case DistortionModel::kNone:
      return {"plumb_bob", std::vector<double>(5, 0.0)};
    case DistortionModel::kFisheye:
      return {"equidistant", Coefficients(format, c, 4, kFisheyeNames, "ROS equidistant has k1..k4")};
    case DistortionModel::kRadTan:
      if (c.model.distortion.size() <= 5) return {"plumb_bob", Coefficients(format, c, 5, kRadTanNames, "")};
      return {"rational_polynomial", Coefficients(format, c, 8, kRadTanNames,
                                                  "ROS rational_polynomial has k1 k2 p1 p2 k3 k4 k5 k6")};
  }
  throw MapExportRefused(format + ": camera " + c.name + ": unknown distortion model");
}

}  // namespace

std::string KalibrCamchain(const RigMap& map) {
  YAML::Emitter y;
  y.SetDoublePrecision(17);
  y << YAML::BeginMap;
  for (size_t i = 0; i < map.cameras.size(); ++i) {
    const MapCamera& cam = map.cameras[i];
    const CameraModel& m = cam.model;
    const auto [model, d] = KalibrDistortion(cam);
    y << YAML::Key << ("cam" + std::to_string(i)) << YAML::Value << YAML::BeginMap;
    if (i > 0) {
      const Rigid3 cn_from_cnm1 = Inverse(cam.rig_from_cam) * map.cameras[i - 1].rig_from_cam;
      y << YAML::Key << "T_cn_cnm1" << YAML::Value;
      EmitMatrixRows(y, cn_from_cnm1.matrix());
    }
    y << YAML::Key << "camera_model" << YAML::Value << "pinhole";
    y << YAML::Key << "intrinsics" << YAML::Value;
    EmitFlowList(y, {m.fx, m.fy, m.cx, m.cy});
    y << YAML::Key << "distortion_model" << YAML::Value << model;
    y << YAML::Key << "distortion_coeffs" << YAML::Value;
    EmitFlowList(y, d);
    y << YAML::Key << "resolution" << YAML::Value << YAML::Flow << YAML::BeginSeq << m.width << m.height
      << YAML::EndSeq;
    y << YAML::Key << "rostopic" << YAML::Value << ("/" + cam.name + "/image_raw");
    y << YAML::EndMap;
  }
  y << YAML::EndMap;
  return FinishYaml(y, "Kalibr camchain");
}

std::string RosCameraInfo(const MapCamera& camera) {
  const CameraModel& m = camera.model;
  const auto [model, d] = RosDistortion(camera);
  YAML::Emitter y;
  y.SetDoublePrecision(17);
  auto matrix = [&](const char* key, int rows, int cols, const std::vector<double>& data) {
    y << YAML::Key << key << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "rows" << YAML::Value << rows;
    y << YAML::Key << "cols" << YAML::Value << cols;
    y << YAML::Key << "data" << YAML::Value;
    EmitFlowList(y, data);
    y << YAML::EndMap;
  };
  y << YAML::BeginMap;
  y << YAML::Key << "image_width" << YAML::Value << m.width;
  y << YAML::Key << "image_height" << YAML::Value << m.height;
  y << YAML::Key << "camera_name" << YAML::Value << camera.name;
  matrix("camera_matrix", 3, 3, {m.fx, 0, m.cx, 0, m.fy, m.cy, 0, 0, 1});
  y << YAML::Key << "distortion_model" << YAML::Value << model;
  matrix("distortion_coefficients", 1, static_cast<int>(d.size()), d);
  matrix("rectification_matrix", 3, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1});
  matrix("projection_matrix", 3, 4, {m.fx, 0, m.cx, 0, 0, m.fy, m.cy, 0, 0, 0, 1, 0});
  y << YAML::EndMap;
  return FinishYaml(y, "camera_info " + camera.name);
}
namespace {
struct NamedTransform {
  std::string parent, child;
  Rigid3 parent_from_child;
};
std::vector<NamedTransform> StaticTransforms(const RigMap& map, const std::string& rig_frame,
                                             const std::string& object_frame) {
  std::vector<NamedTransform> out;
  for (const MapCamera& c : map.cameras)
    out.push_back({rig_frame, c.name + "_optical_frame", c.rig_from_cam});
  if (!HasSeveralBodies(map)) {
    for (const MapMarker& m : map.markers)
      out.push_back({object_frame, "marker_" + std::to_string(m.id), m.object_from_marker});
    return out;
  }
  for (const MapObject& o : map.objects) {
    if (o.is_static) out.push_back({rig_frame, o.name, o.rig_from_object});
    for (const MapMarker& m : o.markers)
      out.push_back({o.name, o.name + "_marker_" + std::to_string(m.id), m.object_from_marker});
  }
  return out;
}
}  // namespace

std::string RosStaticTransformsYaml(const RigMap& map, const std::string& rig_frame,
                                    const std::string& object_frame) {
  YAML::Emitter y;
  y.SetDoublePrecision(17);
  y << YAML::Comment(
      "mcmt map as static transforms. Camera frames are optical frames (x right, y down, z forward); the rig "
      "frame is the reference camera's optical frame; the object frame is the reference marker's frame. "
      "rig -> object is dynamic (MCMT_POSE; with several bodies: rig -> <body> on MCMT_POSE_<BODY>, static "
      "bodies listed here).");
  y << YAML::BeginMap;
  y << YAML::Key << "rig_frame" << YAML::Value << rig_frame;
  y << YAML::Key << "reference_camera" << YAML::Value << map.reference_camera;
  if (HasSeveralBodies(map)) {  // each body its own frame, named as the body
    y << YAML::Key << "objects" << YAML::Value << YAML::BeginSeq;
    for (const MapObject& o : map.objects) {
      y << YAML::Flow << YAML::BeginMap << YAML::Key << "frame" << YAML::Value << o.name;
      y << YAML::Key << "static" << YAML::Value << o.is_static;
      y << YAML::Key << "reference_marker" << YAML::Value << o.reference_marker;
      y << YAML::EndMap;
    }
    y << YAML::EndSeq;
  } else {
    y << YAML::Key << "object_frame" << YAML::Value << object_frame;
    y << YAML::Key << "reference_marker" << YAML::Value << map.reference_marker;
  }
  y << YAML::Key << "transforms" << YAML::Value << YAML::BeginSeq;
  for (const NamedTransform& t : StaticTransforms(map, rig_frame, object_frame)) {
    const auto q = QuaternionWxyz(t.parent_from_child);
    const Eigen::Vector3d p = t.parent_from_child.translation();
    y << YAML::BeginMap;
    y << YAML::Key << "frame_id" << YAML::Value << t.parent;
    y << YAML::Key << "child_frame_id" << YAML::Value << t.child;
    y << YAML::Key << "translation" << YAML::Value;
    EmitFlowList(y, {p.x(), p.y(), p.z()});
    y << YAML::Key << "rotation_xyzw" << YAML::Value;
    EmitFlowList(y, {q[1], q[2], q[3], q[0]});
    y << YAML::EndMap;
  }
  y << YAML::EndSeq << YAML::EndMap;
  return FinishYaml(y, "static_transforms.yaml");
}

std::string RosStaticTransformsTxt(const RigMap& map, const std::string& rig_frame,
                                   const std::string& object_frame) {
  std::string out =
      "# ROS 2 static_transform_publisher commands (one per transform) for the mcmt map; camera frames are\n"
      "# optical frames. ROS 1: rosrun tf2_ros static_transform_publisher x y z qx qy qz qw frame_id "
      "child_frame_id\n";
  for (const NamedTransform& t : StaticTransforms(map, rig_frame, object_frame)) {
    const auto q = QuaternionWxyz(t.parent_from_child);
    const Eigen::Vector3d p = t.parent_from_child.translation();
    out += "ros2 run tf2_ros static_transform_publisher --x " + YamlNumber(p.x()) + " --y " +
           YamlNumber(p.y()) + " --z " + YamlNumber(p.z()) + " --qx " + YamlNumber(q[1]) + " --qy " +
           YamlNumber(q[2]) + " --qz " + YamlNumber(q[3]) + " --qw " + YamlNumber(q[0]) + " --frame-id " +
           t.parent + " --child-frame-id " + t.child + "\n";
  }
  return out;
}

void WriteRosDir(const RigMap& map, const std::string& dir, const std::string& rig_frame,
                 const std::string& object_frame) {
  std::vector<std::pair<std::string, std::string>> files;  // every file's text first: refuse before writing
  for (const MapCamera& c : map.cameras) files.emplace_back(c.name + ".yaml", RosCameraInfo(c));
  files.emplace_back("static_transforms.yaml", RosStaticTransformsYaml(map, rig_frame, object_frame));
  files.emplace_back("static_transforms.txt", RosStaticTransformsTxt(map, rig_frame, object_frame));
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST)
    throw std::runtime_error(dir + ": cannot create directory: " + std::strerror(errno));
  for (const auto& [name, text] : files) WriteFileAtomic(dir + "/" + name, text);
}

namespace {
// A `markers` sequence of the OpenCV map: id, size (m), object_from_marker (4x4).
void WriteMarkers(const std::vector<MapMarker>& markers, cv::FileStorage& fs) {
  fs << "markers"
     << "[";
  for (const MapMarker& mk : markers) {
    fs << "{";
    fs << "id" << mk.id;
    fs << "size" << mk.size;
    fs << "object_from_marker" << ToCvMat(mk.object_from_marker.matrix());
    fs << "}";
  }
  fs << "]";
}
}  // namespace

std::string OpenCvMapYaml(const RigMap& map) {
  cv::FileStorage fs(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "mcmt_map_version" << map.version;
  fs << "dictionary" << map.dictionary;
  fs << "reference_camera" << map.reference_camera;
  fs << "reference_marker" << map.reference_marker;
  fs << "rms_px" << map.rms_px;
  fs << "cameras"
     << "[";
  for (const MapCamera& c : map.cameras) {
    const CameraModel& m = c.model;
    cv::Mat k = (cv::Mat_<double>(3, 3) << m.fx, 0, m.cx, 0, m.fy, m.cy, 0, 0, 1);
    std::string model = DistortionModelName(m.model);
    std::vector<double> d = m.distortion;
    if (m.model == DistortionModel::kNone) {  // same pixels, and a matrix every reader can load
      model = "radtan";
      d.assign(5, 0.0);
    }
    cv::Mat dist(1, static_cast<int>(d.size()), CV_64F);
    for (size_t i = 0; i < d.size(); ++i) dist.at<double>(0, static_cast<int>(i)) = d[i];
    fs << "{";
    fs << "name" << c.name;
    fs << "image_width" << m.width;
    fs << "image_height" << m.height;
    fs << "camera_matrix" << k;
    fs << "distortion_model" << model;
    fs << "distortion_coefficients" << dist;
    fs << "rig_from_cam" << ToCvMat(c.rig_from_cam.matrix());
    fs << "}";
  }
  fs << "]";
  WriteMarkers(map.markers, fs);
  if (HasSeveralBodies(map)) {
    fs << "objects"
       << "[";
    for (const MapObject& o : map.objects) {
      fs << "{";
      fs << "name" << o.name;
      fs << "static" << static_cast<int>(o.is_static);
      fs << "reference_marker" << o.reference_marker;
      if (o.is_static) fs << "rig_from_object" << ToCvMat(o.rig_from_object.matrix());
      WriteMarkers(o.markers, fs);
      fs << "}";
    }
    fs << "]";
  }
  return fs.releaseAndGetString();
}

namespace {
// Corners in the object frame, wound counter-clockwise seen from the marker's +z: BL, BR, TR, TL.
std::array<Eigen::Vector3d, 4> FaceCorners(const MapMarker& m) {
  const MarkerCorners3d c = MarkerCornersInMarker(m.size);
  return {m.object_from_marker * c[3], m.object_from_marker * c[2], m.object_from_marker * c[1],
          m.object_from_marker * c[0]};
}
}  // namespace

std::string MarkersPly(const std::vector<MapMarker>& markers, const std::string& name) {
  std::string out =
      "ply\nformat ascii 1.0\ncomment mcmt " + name + ": marker squares in the object frame, metres\n";
  out += "element vertex " + std::to_string(4 * markers.size()) + "\n";
  out += "property double x\nproperty double y\nproperty double z\n";
  out += "element face " + std::to_string(markers.size()) + "\n";
  out += "property list uchar int vertex_indices\nproperty int marker_id\nend_header\n";
  for (const MapMarker& m : markers)
    for (const Eigen::Vector3d& p : FaceCorners(m))
      out += YamlNumber(p.x()) + " " + YamlNumber(p.y()) + " " + YamlNumber(p.z()) + "\n";
  for (size_t i = 0; i < markers.size(); ++i) {
    const size_t b = 4 * i;
    out += "4 " + std::to_string(b) + " " + std::to_string(b + 1) + " " + std::to_string(b + 2) + " " +
           std::to_string(b + 3) + " " + std::to_string(markers[i].id) + "\n";
  }
  return out;
}

std::string MarkersObj(const std::vector<MapMarker>& markers, const std::string& name) {
  std::string out = "# mcmt " + name + ": marker squares in the object frame, metres\n";
  for (size_t i = 0; i < markers.size(); ++i) {
    const MapMarker& m = markers[i];
    out += "o marker_" + std::to_string(m.id) + "\n";
    for (const Eigen::Vector3d& p : FaceCorners(m))
      out += "v " + YamlNumber(p.x()) + " " + YamlNumber(p.y()) + " " + YamlNumber(p.z()) + "\n";
    const size_t b = 4 * i + 1;
    out += "f " + std::to_string(b) + " " + std::to_string(b + 1) + " " + std::to_string(b + 2) + " " +
           std::to_string(b + 3) + "\n";
  }
  return out;
}

std::string MarkersPly(const RigMap& map) { return MarkersPly(map.markers); }
std::string MarkersObj(const RigMap& map) { return MarkersObj(map.markers); }

bool HasSeveralBodies(const RigMap& map) { return map.objects.size() > 1; }

void WriteLayouts(const RigMap& map, const std::string& path, const std::string& format,
                  const std::function<std::string(const std::vector<MapMarker>&, const std::string&)>& text) {
  if (!HasSeveralBodies(map)) {
    if (map.markers.empty()) throw MapExportRefused(format + ": the map has no marker");
    const std::string name = map.objects.empty() ? std::string("object") : map.objects[0].name;
    WriteFileAtomic(path, text(map.markers, name));
    return;
  }
  std::vector<std::pair<std::string, std::string>> files;  // every body's text first: refuse before writing
  for (const MapObject& o : map.objects) {
    if (o.markers.empty()) throw MapExportRefused(format + ": body '" + o.name + "' has no marker");
    files.emplace_back(BodyPath(path, o.name), text(o.markers, o.name));
  }
  for (const auto& [file, content] : files) WriteFileAtomic(file, content);
}

const std::vector<MapExportFormat>& MapExportFormats() {
  using Options = MapExportOptions;
  static const std::vector<MapExportFormat> formats = {
      {"kalibr", "Kalibr camchain YAML",
       [](const RigMap& m, const std::string& p, const Options&) { WriteFileAtomic(p, KalibrCamchain(m)); }},
      {"ros-dir", "folder of camera_info YAML per camera + static_transforms.yaml/.txt",
       [](const RigMap& m, const std::string& p, const Options& o) {
         WriteRosDir(m, p, o.rig_frame, o.object_frame);
       }},
      {"opencv", "OpenCV FileStorage YAML",
       [](const RigMap& m, const std::string& p, const Options&) { WriteFileAtomic(p, OpenCvMapYaml(m)); }},
      {"ply", "the object's marker squares as PLY (several bodies: one file per body, PATH_<body>.ply)",
       [](const RigMap& m, const std::string& p, const Options&) {
         WriteLayouts(m, p, "PLY",
                      [](const auto& markers, const auto& name) { return MarkersPly(markers, name); });
       }},
      {"obj",
       "the object's marker squares as Wavefront OBJ (several bodies: one file per body, PATH_<body>.obj)",
       [](const RigMap& m, const std::string& p, const Options&) {
         WriteLayouts(m, p, "OBJ",
                      [](const auto& markers, const auto& name) { return MarkersObj(markers, name); });
       }},
  };
  return formats;
}

}  // namespace mcmt
