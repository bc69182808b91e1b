// Kalibr / TagSLAM cameras.yaml and TagSLAM tagslam.yaml (tag sizes).
#include <filesystem>

#include "core/config.h"
#include "import/import.h"

namespace mcmt {
namespace {

YAML::Node LoadYaml(const std::string& path) {
  if (!std::filesystem::exists(path)) throw ConfigError(path + ": file not found");
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": not valid YAML: " + e.what());
  }
}

std::vector<double> Numbers(const YamlSection& s, const std::string& key, size_t count,
                            const std::string& shape) {
  if (!s.Has(key)) s.Fail(key, "missing (expected " + shape + ")");
  const YAML::Node n = s.node()[key];
  std::vector<double> out;
  if (n.IsSequence()) {
    for (const YAML::Node& v : n) {
      double d = 0;
      if (!YAML::convert<double>::decode(v, d)) s.Fail(key, "expected " + shape + ", got a non-number");
      out.push_back(d);
    }
  }
  if (!n.IsSequence() || (count && out.size() != count))
    s.Fail(key, "expected " + shape + ", got " + std::to_string(out.size()) + " values");
  return out;
}

CameraModel KalibrModel(const YamlSection& s) {
  const std::string projection = s.GetString("camera_model", "pinhole");
  if (projection != "pinhole")
    s.Fail("camera_model", "'" + projection + "' is not supported (pinhole with radtan or equidistant)");
  CameraModel m;
  const std::vector<double> k = Numbers(s, "intrinsics", 4, "[fx, fy, cx, cy]");
  m.fx = k[0];
  m.fy = k[1];
  m.cx = k[2];
  m.cy = k[3];
  const std::vector<double> res = Numbers(s, "resolution", 2, "[width, height]");
  m.width = static_cast<int>(res[0]);
  m.height = static_cast<int>(res[1]);
  const std::string distortion = s.GetString("distortion_model", "none");
  std::vector<double> d;
  if (distortion == "equidistant") {
    m.model = DistortionModel::kFisheye;
    d = Numbers(s, "distortion_coeffs", 4, "[k1, k2, k3, k4]");
  } else if (distortion == "radtan") {
    m.model = DistortionModel::kRadTan;
    d = Numbers(s, "distortion_coeffs", 4, "[k1, k2, p1, p2]");
  } else if (distortion == "none") {
    m.model = DistortionModel::kNone;
  } else {
    s.Fail("distortion_model", "'" + distortion + "' is not supported (radtan, equidistant, none)");
  }
  m.distortion = d;
  try {
    m.Validate();
  } catch (const std::invalid_argument& e) {
    s.Fail("intrinsics", e.what());
  }
  return m;
}

}  // namespace

std::vector<KalibrCamera> LoadKalibrCameras(const std::string& path) {
  const YAML::Node root = LoadYaml(path);
  if (!root.IsMap() || root.size() == 0)
    throw ConfigError(path + ": expected a mapping of cameras (cam0: {intrinsics: ..., ...})");
  std::vector<KalibrCamera> cameras;
  for (auto it = root.begin(); it != root.end(); ++it) {
    KalibrCamera c;
    c.name = it->first.as<std::string>();
    if (!it->second.IsMap()) throw ConfigError(path + ": " + c.name + ": expected a mapping");
    const YamlSection s(it->second, path, c.name);
    c.model = KalibrModel(s);
    c.topic = s.GetString("tagtopic", s.GetString("rostopic", ""));
    if (c.topic.empty()) s.Fail("tagtopic", "missing (the bag topic of this camera's tag detections)");
    cameras.push_back(c);
  }
  return cameras;
}

TagSizes LoadTagslamSizes(const std::string& path) {
  const YAML::Node root = LoadYaml(path);
  if (!root.IsMap() || !root["bodies"] || !root["bodies"].IsSequence())
    throw ConfigError(path + ": bodies: missing (expected TagSLAM's list of bodies)");
  const std::string default_body = root["default_body"] ? root["default_body"].as<std::string>() : "";
  TagSizes t;
  double first_default = 0.0;
  const YAML::Node bodies = root["bodies"];
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies[i].IsMap() || bodies[i].size() != 1)
      throw ConfigError(path + ": bodies[" + std::to_string(i) + "]: expected {name: {...}}");
    const std::string name = bodies[i].begin()->first.as<std::string>();
    const YamlSection body(bodies[i].begin()->second, path, "bodies." + name);
    if (body.Has("default_tag_size")) {
      const double size = body.GetPositiveDouble("default_tag_size", 0.0);
      if (name == default_body) t.default_size = size;
      if (first_default == 0.0) first_default = size;
    }
    const YAML::Node tags = body.node()["tags"];
    if (!tags) continue;
    if (!tags.IsSequence()) body.Fail("tags", "expected a list");
    for (size_t j = 0; j < tags.size(); ++j) {
      const YamlSection tag(tags[j], path, body.KeyName("tags[" + std::to_string(j) + "]"));
      const int id = tag.GetInt("id", -1);
      if (id < 0) tag.Fail("id", "missing or negative");
      if (tag.Has("size")) t.sizes[id] = tag.GetPositiveDouble("size", 0.0);
    }
  }
  if (t.default_size == 0.0) t.default_size = first_default;
  return t;
}

std::string DictionaryForFamily(const std::string& family) {
  std::string f = family;
  for (const char* prefix : {"tag", "tf", "t"})
    if (f.rfind(prefix, 0) == 0 && f.size() > std::string(prefix).size() &&
        std::isdigit(static_cast<unsigned char>(f[std::string(prefix).size()]))) {
      f = f.substr(std::string(prefix).size());
      break;
    }
  if (f == "mit") f = "36h11";  // the MIT (Kaess) detector TagSLAM uses reports this for 36h11
  for (const char* known : {"16h5", "25h9", "36h10", "36h11"})
    if (f == known) return std::string("DICT_APRILTAG_") + known;
  return "";
}

}  // namespace mcmt
