// Exports of a map (core/files.h's RigMap, map.yaml) to other tools' formats: Kalibr camchain, ROS
// camera_info + static transforms, OpenCV FileStorage, PLY / OBJ of the object's marker squares.
//
// One table, MapExportFormats(), lists every format once: its command-line option (mcmt-export --NAME),
// what it writes, and its writer. A writer first checks that every camera's model can be expressed
// exactly in its format and throws MapExportRefused (one line naming the format, camera and coefficient)
// before writing anything; files are written atomically (temporary name, then rename). To add a format:
// write its text function below, add a row to the table in core/src/map_export.cc, document it in
// docs/processes.md.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/files.h"

namespace mcmt {

// A camera model the format cannot express: nothing of that output was written.
class MapExportRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MapExportOptions {
  std::string rig_frame = "mcmt_rig";        // ros-dir: name of the rig frame
  std::string object_frame = "mcmt_object";  // ros-dir: name of the object frame
};

struct MapExportFormat {
  std::string option;  // "kalibr", "ros-dir", "opencv", "ply", "obj"
  std::string help;    // what it writes, for --help
  // Writes the map to `path` (a file, or a folder for ros-dir). Throws MapExportRefused, or
  // std::runtime_error when the file cannot be written.
  std::function<void(const RigMap& map, const std::string& path, const MapExportOptions& options)> write;
};

// A map with several bodies (version 2, more than one object) writes PLY and OBJ as one file per body: the
// asked path with "_<body>" before its extension (--ply layout.ply: layout_tool.ply, layout_patient.ply,
// layout_floor.ply), each body's markers in its own frame (MeshLab opens the files as layers, Blender
// imports each as its own object). A map with one body keeps the asked name. ROS static transforms and
// OpenCV YAML hold every body in one file.
bool HasSeveralBodies(const RigMap& map);  // (file names: core/files.h's BodyPath)

// Every map export format, in the order --help lists them.
const std::vector<MapExportFormat>& MapExportFormats();

// Kalibr camchain YAML: cam0..camN-1 in map order, pinhole-radtan (k1 k2 p1 p2) or pinhole-equidistant
// (k1..k4), with T_cn_cnm1 = cam_n_from_cam_(n-1) for n >= 1. Refuses a camera whose model has a non-zero
// coefficient beyond those (e.g. radtan k3: Kalibr's radtan has 4 coefficients).
std::string KalibrCamchain(const RigMap& map);
// ROS camera_info YAML of one camera (camera_calibration_parsers format): plumb_bob (5 coefficients),
// rational_polynomial (8) or equidistant (4). Refuses a model with non-zero coefficients beyond those.
std::string RosCameraInfo(const MapCamera& camera);
// static_transforms.yaml (and .txt: ROS 2 static_transform_publisher commands): rig -> <cam>_optical_frame
// per camera, object -> marker_<id> per marker. Frame names given. With several bodies: each body is the
// frame <body> (object_frame is not used), its markers <body> -> <body>_marker_<id>, and a static body
// rig -> <body> (a moving body's rig -> <body> is dynamic: MCMT_POSE_<BODY>).
std::string RosStaticTransformsYaml(const RigMap& map, const std::string& rig_frame,
                                    const std::string& object_frame);
std::string RosStaticTransformsTxt(const RigMap& map, const std::string& rig_frame,
                                   const std::string& object_frame);
// Writes DIR/<camera>.yaml per camera, DIR/static_transforms.yaml and .txt (creates DIR). Every camera
// is checked before the first file is written.
void WriteRosDir(const RigMap& map, const std::string& dir, const std::string& rig_frame = "mcmt_rig",
                 const std::string& object_frame = "mcmt_object");
// OpenCV FileStorage YAML: cameras (name, camera_matrix, distortion_coefficients, distortion_model,
// image_width, image_height, rig_from_cam 4x4), markers (id, size, object_from_marker 4x4). With several
// bodies also objects (name, static, reference_marker, rig_from_object 4x4 for a static body, markers).
std::string OpenCvMapYaml(const RigMap& map);
// The object's marker squares in the object frame; faces wound counter-clockwise seen from the marker's
// +z (its printed face), so face normals point out of the markers. `name` (a body's) goes into the
// header comment.
std::string MarkersPly(const std::vector<MapMarker>& markers, const std::string& name = "object");
std::string MarkersObj(const std::vector<MapMarker>& markers, const std::string& name = "object");
std::string MarkersPly(const RigMap& map);  // the map's markers (a version 2 map: its first moving body)
std::string MarkersObj(const RigMap& map);
// Writes the map's layouts as `text(markers, name)` to `path`, or one file per body (BodyPath) for a map
// with several bodies; refuses (MapExportRefused, nothing written) a body without markers.
void WriteLayouts(const RigMap& map, const std::string& path, const std::string& format,
                  const std::function<std::string(const std::vector<MapMarker>&, const std::string&)>& text);

}  // namespace mcmt
