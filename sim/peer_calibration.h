// Agreement of a map with a peer tool's camera calibration (caliscope's camera_array.toml): camera centres
// rigidly aligned (Horn, no scale), then per camera the position and rotation differences. The peer's world
// frame is its own choice, so only relative placement is compared.
#pragma once

#include <string>
#include <vector>

#include "core/files.h"
#include "core/se3.h"

namespace mcmt {
namespace sim {

struct PeerCamera {
  std::string name;  // "cam<K>" for caliscope's [cameras.K]
  Rigid3 cam_from_world = Rigid3::Identity();
};

// Reads caliscope's camera_array.toml ([cameras.K] with rotation 3x3 and translation, x_cam = R X + t).
// Throws std::runtime_error naming the file and the camera/key that is missing or malformed.
std::vector<PeerCamera> ReadCaliscopeCameras(const std::string& path);

struct PeerCameraAgreement {
  std::string name;
  double position_mm = 0;   // after rigid alignment of the camera centres
  double rotation_deg = 0;  // angle between the aligned orientations
};

struct PeerAgreement {
  std::vector<PeerCameraAgreement> cameras;
  std::vector<std::string> missing;  // peer cameras the map lacks
  double max_position_mm = 0, max_rotation_deg = 0;
  double scale_ratio = 1;  // map's mean centre distance / peer's (1 = same scale)
};

PeerAgreement CompareWithPeer(const RigMap& map, const std::vector<PeerCamera>& peer);
std::string FormatPeerAgreement(const PeerAgreement& agreement);      // markdown table
std::string FormatPeerAgreementJson(const PeerAgreement& agreement);  // the same figures as JSON

}  // namespace sim
}  // namespace mcmt
