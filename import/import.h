// mcmt-import's engine: foreign detections -> an mcmt session folder that mcmt-mapper and mcmt-tracker
// read as they are: DIR/session.lcmlog (detections_t on MCMT_DETECTIONS_<CAMERA>, event time = utime),
// DIR/rig.yaml and one OpenCV intrinsics file per camera. DIR is written as a whole: into a temporary
// sibling folder, renamed at the end; an existing DIR with a session or rig in it is never overwritten.
//
// Sources:
//  - a ROS 1 bag of apriltag_msgs/ApriltagArrayStamped, one topic per camera, with a Kalibr / TagSLAM
//    cameras.yaml (pinhole + radtan / equidistant) naming each camera's topic (`tagtopic`, else
//    `rostopic`). Corners are converted from AprilTag's order (bottom-left, bottom-right, top-right,
//    top-left of the tag as printed: counter-clockwise in the image) to ArUco's (top-left, top-right,
//    bottom-right, bottom-left: clockwise), i.e. reversed. Messages of all cameras with the same header
//    stamp form one frame: utime = the stamp, seq = the frame's index among the bag's distinct stamps.
//  - mcmt's own det.csv (utime,seq,camera,id,x0,y0,...,x3,y3; ArUco order) with the rig YAML it came from.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/camera.h"
#include "import/rosbag.h"

namespace mcmt {

class ImportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One camera of a Kalibr / TagSLAM cameras.yaml, in file order.
struct KalibrCamera {
  std::string name;   // the top-level key (cam0, cam1, ...)
  CameraModel model;  // equidistant -> fisheye (Kannala-Brandt k1..k4), radtan -> OpenCV k1 k2 p1 p2
  std::string topic;  // tagtopic, else rostopic
};
// Throws ConfigError naming the file and key (e.g. "cameras.yaml: cam1.distortion_model: ...").
std::vector<KalibrCamera> LoadKalibrCameras(const std::string& path);

// Tag sizes from a TagSLAM tagslam.yaml: every body's tags[].size and the default body's
// default_tag_size (else the first body that has one). Throws ConfigError naming file and key.
struct TagSizes {
  double default_size = 0.0;  // metres, 0: none
  std::map<int, double> sizes;
};
TagSizes LoadTagslamSizes(const std::string& path);

// AprilTag -> ArUco corner order (index i of the result is corner order[i] of the message).
constexpr int kAprilTagToAruco[4] = {3, 2, 1, 0};
// A message's tag family ("tf36h11", "36h11", "tag36h11", "mit": the MIT detector, 36h11) as an mcmt
// dictionary name; "" when unknown.
std::string DictionaryForFamily(const std::string& family);

struct RosbagImportOptions {
  std::string bag;         // .bag, or .bag.bz2 (bzip2 of the whole file)
  std::string cameras;     // Kalibr / TagSLAM cameras.yaml
  std::string out;         // session folder to create
  double tag_size = 0.0;   // metres; 0: from tagslam.yaml
  std::string tagslam;     // tagslam.yaml; empty: the one beside cameras.yaml, if any
  std::string dictionary;  // overrides the family found in the messages
};

struct ImportedCamera {
  std::string name, topic;
  int messages = 0;
  int tags = 0;
};

struct ImportSummary {
  std::string out;
  std::vector<ImportedCamera> cameras;
  int frames = 0;              // distinct stamps
  int duplicate_messages = 0;  // a second message of one camera with the same stamp (dropped)
  std::string dictionary;
  double tag_size = 0.0;
  std::map<int, double> sizes;
  std::string sizes_from;          // "--tag-size" or the tagslam.yaml used
  std::vector<std::string> notes;  // topics ignored, families seen, chunk compressions, ...
};

ImportSummary ImportRosbag(const RosbagImportOptions& options);

// det.csv + the rig YAML it belongs to -> session folder (rig.yaml keeps every section of the original;
// its cameras point at copies of their intrinsics; image sources are dropped).
ImportSummary ImportCsv(const std::string& csv, const std::string& config, const std::string& out);

std::string FormatImportSummary(const ImportSummary& summary);

}  // namespace mcmt
