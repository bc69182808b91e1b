// Rig configuration (YAML, design brief) and intrinsics files. Every missing or malformed key throws
// ConfigError with a one-line message naming the file and the key, e.g.
//   "rig.yaml: markers.size: expected a positive number, got 'abc'".
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/marker.h"
#include "core/objects.h"

namespace mcmt {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Typed access to one YAML mapping with errors that name the file and the dotted key.
// Example: YamlSection s(rig.mapper, rig.path, "mapper");  double h = s.GetDouble("huber_px", 1.0);
class YamlSection {
 public:
  YamlSection() = default;
  YamlSection(YAML::Node node, std::string file, std::string prefix);

  bool Has(const std::string& key) const;
  double GetDouble(const std::string& key, double default_value) const;
  double GetPositiveDouble(const std::string& key, double default_value) const;
  int GetInt(const std::string& key, int default_value) const;
  bool GetBool(const std::string& key, bool default_value) const;
  std::string GetString(const std::string& key, const std::string& default_value) const;
  std::vector<int> GetIntList(const std::string& key) const;  // empty when absent
  // Required variants: throw "<file>: <prefix.key>: missing" when absent.
  double RequireDouble(const std::string& key) const;
  std::string RequireString(const std::string& key) const;
  YamlSection Child(const std::string& key) const;  // empty section when absent
  // Throws naming the first key not in `known` (catches typos such as "hubr_px").
  void CheckKnownKeys(const std::set<std::string>& known) const;

  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }
  std::string KeyName(const std::string& key) const;  // "prefix.key"
  // Throws OptionError (core/options.h, a ConfigError) naming the file and the key.
  [[noreturn]] void Fail(const std::string& key, const std::string& what) const;

 private:
  YAML::Node node_;
  std::string file_;
  std::string prefix_;
};

struct MarkerConfig {
  std::string dictionary = "DICT_6X6_250";  // predefined name, or a dictionary file (absolute path)
  double size = 0.0;                        // default side length, metres
  std::map<int, double> sizes;              // per-id overrides
  std::vector<int> ids;                     // only these ids belong to the object (empty: all)
  bool inverted = false;                    // white-on-black prints
  MarkerSizes Sizes() const { return MarkerSizes{size, sizes}; }
  bool Accepts(int id) const;  // whitelist check
};

struct CameraConfig {
  std::string name;
  std::string intrinsics_path;  // absolute
  std::string source;           // as written, resolved to an absolute path when it names a file/folder
  std::string timestamps_path;  // optional, absolute
  CameraModel model;            // loaded from intrinsics_path
};

struct RigConfig {
  std::string path;  // the YAML file
  std::string dir;   // its folder (relative paths are relative to it)
  MarkerConfig markers;
  ObjectsConfig objects;  // objects: and rig_frame: (core/objects.h); without them, one object
  std::vector<CameraConfig> cameras;
  std::string lcm_url;  // lcm.url, empty: LCM's default
  // Raw per-process sections (absent: empty nodes); components parse them with YamlSection.
  YamlSection detector, mapper, tracker, sync, lcm, logger, viz;
  YAML::Node root;

  const CameraConfig* FindCamera(const std::string& name) const;  // nullptr if absent
  const CameraConfig& GetCamera(const std::string& name) const;   // throws naming the valid names
};

// Loads and validates a rig YAML and the intrinsics files it names.
RigConfig LoadRigConfig(const std::string& path);

// OpenCV calibration YAML (camera_matrix, distortion_coefficients, image_width, image_height,
// optional distortion_model: radtan|fisheye|none, or OpenCV sample's fisheye_model: 1) or ROS camera_info
// YAML (image_width, image_height, camera_matrix.data, distortion_model
// plumb_bob|rational_polynomial|equidistant, distortion_coefficients.data). Without camera_matrix, rough
// intrinsics: `hfov_deg` (a datasheet's horizontal field of view; kDefaultHfovDeg when absent too), square
// pixels, principal point at the centre, to be refined by the mapper (mapper.refine_intrinsics). Throws
// ConfigError naming the file and key.
constexpr double kDefaultHfovDeg = 60.0;
CameraModel LoadIntrinsics(const std::string& path);
// Writes OpenCV calibration YAML (with the %YAML:1.0 header cv::FileStorage needs), atomically.
void WriteIntrinsicsOpenCv(const std::string& path, const CameraModel& model);

// Makes a path relative to base_dir absolute (absolute paths unchanged).
std::string ResolvePath(const std::string& base_dir, const std::string& path);

}  // namespace mcmt
