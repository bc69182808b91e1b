#include "core/config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/dictionary.h"
#include "core/files.h"
#include "core/options.h"

namespace mcmt {
namespace fs = std::filesystem;

namespace {

std::string ScalarText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

// Parses a YAML file with yaml-cpp. OpenCV's "%YAML:1.0" first line is not valid YAML 1.2: drop it.
YAML::Node LoadYamlFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  int skipped_lines = 0;
  if (text.rfind("%YAML:", 0) == 0) {
    const size_t eol = text.find('\n');
    text = eol == std::string::npos ? std::string() : text.substr(eol + 1);
    skipped_lines = 1;
  }
  try {
    YAML::Node root = YAML::Load(text);
    const std::string duplicate = DuplicateYamlKey(root);
    if (!duplicate.empty()) {  // line numbers of the text as read (the %YAML line dropped)
      const size_t colon = duplicate.find(':');
      throw ConfigError(path + ":" + std::to_string(std::stoi(duplicate.substr(0, colon)) + skipped_lines) +
                        duplicate.substr(colon));
    }
    return root;
  } catch (const YAML::ParserException& e) {
    throw ConfigError(path + ":" + std::to_string(e.mark.line + 1 + skipped_lines) +
                      ": YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": cannot parse YAML: " + e.msg);
  }
}

std::string FormatDouble(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// YamlSection

YamlSection::YamlSection(YAML::Node node, std::string file, std::string prefix)
    : node_(std::move(node)), file_(std::move(file)), prefix_(std::move(prefix)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap())
    throw ConfigError(file_ + ": " + (prefix_.empty() ? std::string("(top level)") : prefix_) +
                      ": expected a mapping, got " + ScalarText(node_));
}

std::string YamlSection::KeyName(const std::string& key) const {
  return prefix_.empty() ? key : prefix_ + "." + key;
}

void YamlSection::Fail(const std::string& key, const std::string& what) const {
  throw OptionError(file_, KeyName(key), what);
}

bool YamlSection::Has(const std::string& key) const {
  if (!node_.IsDefined() || !node_.IsMap()) return false;
  const YAML::Node child = node_[key];
  return child.IsDefined() && !child.IsNull();
}

double YamlSection::GetDouble(const std::string& key, double default_value) const {
  if (!Has(key)) return default_value;
  const YAML::Node child = node_[key];
  double v = 0;
  if (!child.IsScalar() || !YAML::convert<double>::decode(child, v) || std::isnan(v))
    Fail(key, "expected a number, got '" + ScalarText(child) + "'");
  return v;
}

double YamlSection::GetPositiveDouble(const std::string& key, double default_value) const {
  if (!Has(key)) return default_value;
  const YAML::Node child = node_[key];
  double v = 0;
  if (!child.IsScalar() || !YAML::convert<double>::decode(child, v) || !(v > 0) || !std::isfinite(v))
    Fail(key, "expected a positive number, got '" + ScalarText(child) + "'");
  return v;
}

int YamlSection::GetInt(const std::string& key, int default_value) const {
  if (!Has(key)) return default_value;
  const YAML::Node child = node_[key];
  int v = 0;
  if (!child.IsScalar() || !YAML::convert<int>::decode(child, v))
    Fail(key, "expected an integer, got '" + ScalarText(child) + "'");
  return v;
}

bool YamlSection::GetBool(const std::string& key, bool default_value) const {
  if (!Has(key)) return default_value;
  const YAML::Node child = node_[key];
  bool v = false;
  if (!child.IsScalar() || !YAML::convert<bool>::decode(child, v))
    Fail(key, "expected true or false, got '" + ScalarText(child) + "'");
  return v;
}

std::string YamlSection::GetString(const std::string& key, const std::string& default_value) const {
  if (!Has(key)) return default_value;
  const YAML::Node child = node_[key];
  if (!child.IsScalar()) Fail(key, "expected a string, got " + ScalarText(child));
  return child.Scalar();
}

std::vector<int> YamlSection::GetIntList(const std::string& key) const {
  std::vector<int> out;
  if (!Has(key)) return out;
  const YAML::Node child = node_[key];
  if (!child.IsSequence()) Fail(key, "expected a list of integers, got '" + ScalarText(child) + "'");
  for (size_t i = 0; i < child.size(); ++i) {
    int v = 0;
    if (!child[i].IsScalar() || !YAML::convert<int>::decode(child[i], v))
      Fail(key, "item " + std::to_string(i) + ": expected an integer, got '" + ScalarText(child[i]) + "'");
    out.push_back(v);
  }
  return out;
}

double YamlSection::RequireDouble(const std::string& key) const {
  if (!Has(key)) Fail(key, "missing");
  return GetDouble(key, 0.0);
}

std::string YamlSection::RequireString(const std::string& key) const {
  if (!Has(key)) Fail(key, "missing");
  return GetString(key, "");
}

YamlSection YamlSection::Child(const std::string& key) const {
  if (!Has(key)) return YamlSection(YAML::Node(), file_, KeyName(key));
  const YAML::Node child = node_[key];
  if (!child.IsMap()) Fail(key, "expected a mapping, got " + ScalarText(child));
  return YamlSection(child, file_, KeyName(key));
}

void YamlSection::CheckKnownKeys(const std::set<std::string>& known) const {
  if (!node_.IsDefined() || !node_.IsMap()) return;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("?");
    if (!known.count(key))
      Fail(key, "unknown key (valid: " + Join(std::vector<std::string>(known.begin(), known.end())) + ")");
  }
}

// ---------------------------------------------------------------------------------------------

bool MarkerConfig::Accepts(int id) const {
  return ids.empty() || std::find(ids.begin(), ids.end(), id) != ids.end();
}

const CameraConfig* RigConfig::FindCamera(const std::string& name) const {
  for (const auto& c : cameras)
    if (c.name == name) return &c;
  return nullptr;
}

const CameraConfig& RigConfig::GetCamera(const std::string& name) const {
  const CameraConfig* c = FindCamera(name);
  if (!c) {
    std::vector<std::string> names;
    for (const auto& cam : cameras) names.push_back(cam.name);
    throw ConfigError(path + ": no camera named '" + name + "' (cameras: " + Join(names) + ")");
  }
  return *c;
}

std::string ResolvePath(const std::string& base_dir, const std::string& path) {
  if (path.empty()) return path;
  fs::path p(path);
  if (p.is_absolute()) return p.lexically_normal().string();
  fs::path base = base_dir.empty() ? fs::current_path() : fs::path(base_dir);
  if (!base.is_absolute()) base = fs::absolute(base);
  return (base / p).lexically_normal().string();
}

// ---------------------------------------------------------------------------------------------
// Intrinsics

namespace {

std::vector<double> ReadNumberList(const YamlSection& s, const std::string& key, const YAML::Node& node) {
  if (!node.IsSequence()) s.Fail(key, "expected a list of numbers, got '" + ScalarText(node) + "'");
  std::vector<double> out;
  for (size_t i = 0; i < node.size(); ++i) {
    double v = 0;
    if (!node[i].IsScalar() || !YAML::convert<double>::decode(node[i], v) || !std::isfinite(v))
      s.Fail(key, "item " + std::to_string(i) + ": expected a number, got '" + ScalarText(node[i]) + "'");
    out.push_back(v);
  }
  return out;
}

// A matrix node: {rows, cols, [dt], data: [...]} (OpenCV's !!opencv-matrix and ROS both).
std::vector<double> ReadMatrix(const YamlSection& parent, const std::string& key, int* rows, int* cols) {
  if (!parent.Has(key)) parent.Fail(key, "missing");
  const YAML::Node node = parent.node()[key];
  if (node.IsSequence()) {  // a bare list is accepted too
    std::vector<double> data = ReadNumberList(parent, key, node);
    *rows = 1;
    *cols = static_cast<int>(data.size());
    return data;
  }
  const YamlSection m = parent.Child(key);
  if (!m.Has("data")) m.Fail("data", "missing");
  std::vector<double> data = ReadNumberList(m, "data", m.node()["data"]);
  *rows = m.GetInt("rows", 1);
  *cols = m.GetInt("cols", static_cast<int>(data.size()));
  if (*rows < 0 || *cols < 0 || static_cast<size_t>(*rows) * static_cast<size_t>(*cols) != data.size())
    m.Fail("data", "has " + std::to_string(data.size()) + " values, expected rows*cols = " +
                       std::to_string(*rows) + "*" + std::to_string(*cols));
  return data;
}

}  // namespace

namespace {

void ReadCameraMatrix(const YamlSection& s, CameraModel* model) {
  int rows = 0, cols = 0;
  const std::vector<double> k = ReadMatrix(s, "camera_matrix", &rows, &cols);
  if (k.size() != 9) s.Fail("camera_matrix", "expected 3x3 (9 values), got " + std::to_string(k.size()));
  model->fx = k[0];
  model->fy = k[4];
  model->cx = k[2];
  model->cy = k[5];
  if (!(model->fx > 0) || !(model->fy > 0))
    s.Fail("camera_matrix", "focal lengths must be positive, got fx=" + FormatDouble(model->fx) +
                                " fy=" + FormatDouble(model->fy));
  if (k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0)
    s.Fail("camera_matrix", "expected [fx 0 cx; 0 fy cy; 0 0 1] (skew is not supported)");
}

// No camera_matrix: a datasheet's horizontal field of view (hfov_deg), or kDefaultHfovDeg, with square
// pixels and the principal point at the image centre: fx = fy = (width / 2) / tan(hfov / 2).
// Any other key (a misspelt camera_matrix, a ROS file's camera_name) says the file is a calibration that
// lacks its matrix: an error, not a silent field of view.
void RoughIntrinsics(const YamlSection& s, CameraModel* model) {
  static const std::set<std::string> rough_keys = {"image_width", "image_height", "hfov_deg",
                                                   "distortion_model", "distortion_coefficients"};
  for (const auto& entry : s.node()) {
    const std::string key = entry.first.as<std::string>();
    if (!rough_keys.count(key))
      s.Fail("camera_matrix",
             "missing (a file without it may hold only image_width, image_height, hfov_deg, "
             "distortion_model, distortion_coefficients; found '" +
                 key + "')");
  }
  const double hfov = s.GetDouble("hfov_deg", kDefaultHfovDeg);
  if (!(hfov > 5 && hfov < 170)) s.Fail("hfov_deg", "expected 5..170 degrees, got " + FormatDouble(hfov));
  model->fx = model->fy = 0.5 * model->width / std::tan(0.5 * hfov * M_PI / 180.0);
  model->cx = 0.5 * (model->width - 1);
  model->cy = 0.5 * (model->height - 1);
}

}  // namespace

CameraModel LoadIntrinsics(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  if (!root.IsMap()) throw ConfigError(path + ": not an intrinsics file (expected a YAML mapping)");
  const YamlSection s(root, path, "");
  CameraModel model;
  model.width = s.GetInt("image_width", 0);
  model.height = s.GetInt("image_height", 0);
  if (!s.Has("image_width")) s.Fail("image_width", "missing");
  if (!s.Has("image_height")) s.Fail("image_height", "missing");
  if (model.width <= 0) s.Fail("image_width", "must be positive, got " + std::to_string(model.width));
  if (model.height <= 0) s.Fail("image_height", "must be positive, got " + std::to_string(model.height));

  int rows = 0, cols = 0;
  if (!s.Has("camera_matrix")) {
    RoughIntrinsics(s, &model);
  } else {
    if (s.Has("hfov_deg")) s.Fail("hfov_deg", "given together with camera_matrix (give one or the other)");
    ReadCameraMatrix(s, &model);
  }

  std::vector<double> d;
  if (s.Has("distortion_coefficients")) d = ReadMatrix(s, "distortion_coefficients", &rows, &cols);
  std::string model_name = s.GetString("distortion_model", "");
  if (model_name.empty()) {
    // OpenCV's calibration sample marks fisheye calibrations with "fisheye_model: 1".
    int fisheye_flag = 0;
    if (s.Has("fisheye_model")) {
      const YAML::Node f = root["fisheye_model"];
      bool b = false;
      const bool is_int = YAML::convert<int>::decode(f, fisheye_flag);
      if (!is_int && !YAML::convert<bool>::decode(f, b))
        s.Fail("fisheye_model", "expected 0 or 1, got '" + ScalarText(f) + "'");
      if (!is_int) fisheye_flag = b ? 1 : 0;
    }
    model_name = fisheye_flag ? "fisheye" : (d.empty() ? "none" : "radtan");
  }
  try {
    model.model = DistortionModelFromName(model_name);
  } catch (const std::invalid_argument& e) {
    s.Fail("distortion_model",
           std::string(e.what()) + " (ROS names plumb_bob, rational_polynomial, equidistant are accepted)");
  }
  const bool all_zero = std::all_of(d.begin(), d.end(), [](double v) { return v == 0.0; });
  switch (model.model) {
    case DistortionModel::kNone:
      if (!all_zero) s.Fail("distortion_coefficients", "non-zero coefficients with distortion_model none");
      d.clear();
      break;
    case DistortionModel::kRadTan:
      // OpenCV may write 12 or 14 coefficients (thin prism, tilt): accept them when the extra ones are 0.
      if (d.size() > 8) {
        if (!std::all_of(d.begin() + 8, d.end(), [](double v) { return v == 0.0; }))
          s.Fail("distortion_coefficients", "thin-prism/tilt coefficients (beyond 8) are not supported");
        d.resize(8);
      }
      if (d.size() == 6 || d.size() == 7) d.resize(8, 0.0);
      if (d.size() < 4)
        s.Fail("distortion_coefficients", "radtan needs 4, 5 or 8 values, got " + std::to_string(d.size()));
      break;
    case DistortionModel::kFisheye:
      if (d.size() != 4)
        s.Fail("distortion_coefficients", "fisheye needs 4 values, got " + std::to_string(d.size()));
      break;
  }
  model.distortion = d;
  try {
    model.Validate();
  } catch (const std::invalid_argument& e) {
    throw ConfigError(path + ": " + e.what());
  }
  return model;
}

void WriteIntrinsicsOpenCv(const std::string& path, const CameraModel& model) {
  model.Validate();
  std::ostringstream out;
  auto matrix = [&out](const std::string& name, int rows, int cols, const std::vector<double>& data) {
    out << name << ": !!opencv-matrix\n   rows: " << rows << "\n   cols: " << cols
        << "\n   dt: d\n   data: [ ";
    for (size_t i = 0; i < data.size(); ++i) out << (i ? ", " : "") << FormatDouble(data[i]);
    out << " ]\n";
  };
  out << "%YAML:1.0\n---\n";
  out << "image_width: " << model.width << "\n";
  out << "image_height: " << model.height << "\n";
  matrix("camera_matrix", 3, 3, {model.fx, 0, model.cx, 0, model.fy, model.cy, 0, 0, 1});
  out << "distortion_model: " << DistortionModelName(model.model) << "\n";
  std::vector<double> d = model.distortion;
  if (d.empty()) d.assign(5, 0.0);  // cv::FileStorage cannot hold an empty matrix; "none" ignores zeros
  matrix("distortion_coefficients", 1, static_cast<int>(d.size()), d);
  WriteFileAtomic(path, out.str());
}

// ---------------------------------------------------------------------------------------------
// Rig config

namespace {

constexpr double kMaxMarkerSize_m = 10.0;

// Number of ids of the dictionary (-1 when it does not load: reported by the dictionary check).
int DictionarySize(const std::string& dictionary) {
  try {
    return LoadDictionary(dictionary)->bytesList.rows;
  } catch (const std::exception&) {
    return -1;
  }
}

// ids: non-negative, no repeats, and (with `sizes` keys) within the dictionary.
void CheckMarkerIds(const YamlSection& m, const MarkerConfig& mc) {
  const int dictionary_size = DictionarySize(mc.dictionary);
  std::set<int> seen;
  for (int id : mc.ids) {
    if (id < 0) m.Fail("ids", "marker ids must be non-negative, got " + std::to_string(id));
    if (!seen.insert(id).second) m.Fail("ids", "marker id " + std::to_string(id) + " is listed twice");
    if (dictionary_size >= 0 && id >= dictionary_size)
      m.Fail("ids", "marker id " + std::to_string(id) + " is not in " + mc.dictionary + " (ids 0-" +
                        std::to_string(dictionary_size - 1) + ")");
  }
  if (dictionary_size >= 0)
    for (const auto& [id, size] : mc.sizes)
      if (id >= dictionary_size)
        m.Fail("sizes." + std::to_string(id), "marker id " + std::to_string(id) + " is not in " +
                                                  mc.dictionary + " (ids 0-" +
                                                  std::to_string(dictionary_size - 1) + ")");
}

}  // namespace

RigConfig LoadRigConfig(const std::string& path) {
  RigConfig rig;
  rig.path = path;
  rig.dir = fs::absolute(fs::path(path)).parent_path().lexically_normal().string();
  if (!fs::exists(path)) throw ConfigError(path + ": file not found");
  rig.root = LoadYamlFile(path);
  if (!rig.root.IsMap()) throw ConfigError(path + ": expected a YAML mapping with markers: and cameras:");
  const YamlSection top(rig.root, path, "");
  top.CheckKnownKeys({"markers", "cameras", "detector", "mapper", "tracker", "sync", "lcm", "logger", "viz",
                      "sim", "eval", "export", "launch", "object", "name", "description", "objects",
                      "rig_frame"});

  // markers
  if (!top.Has("markers")) top.Fail("markers", "missing");
  const YamlSection m = top.Child("markers");
  m.CheckKnownKeys({"dictionary", "size", "sizes", "ids", "inverted"});
  MarkerConfig& mc = rig.markers;
  mc.dictionary = m.GetString("dictionary", mc.dictionary);
  {
    const auto& names = PredefinedDictionaryNames();
    if (std::find(names.begin(), names.end(), mc.dictionary) == names.end()) {
      const std::string resolved = ResolvePath(rig.dir, mc.dictionary);
      const bool looks_like_file = mc.dictionary.find('/') != std::string::npos ||
                                   mc.dictionary.find('.') != std::string::npos || fs::exists(resolved);
      if (!looks_like_file)
        m.Fail("dictionary", "unknown dictionary '" + mc.dictionary + "' (valid: " + Join(names) +
                                 ", or a dictionary file)");
      if (!fs::exists(resolved)) m.Fail("dictionary", "dictionary file not found: " + resolved);
      try {
        LoadDictionary(resolved);
      } catch (const std::exception& e) {
        m.Fail("dictionary", e.what());
      }
      mc.dictionary = resolved;
    }
  }
  if (!m.Has("size") && !top.Has("objects")) m.Fail("size", "missing");
  mc.size = m.GetPositiveDouble("size", 0.0);
  if (mc.size > kMaxMarkerSize_m)
    m.Fail("size", "absurd marker side length " + ScalarText(m.node()["size"]) + " m (at most " +
                       FormatDouble(kMaxMarkerSize_m) + " m)");
  if (m.Has("sizes")) {
    const YAML::Node sizes = m.node()["sizes"];
    if (!sizes.IsMap()) m.Fail("sizes", "expected a mapping id: size, got '" + ScalarText(sizes) + "'");
    for (auto it = sizes.begin(); it != sizes.end(); ++it) {
      int id = 0;
      const std::string key_text = it->first.IsScalar() ? it->first.Scalar() : "?";
      if (!it->first.IsScalar() || !YAML::convert<int>::decode(it->first, id) || id < 0)
        m.Fail("sizes", "expected a non-negative marker id as key, got '" + key_text + "'");
      double v = 0;
      if (!it->second.IsScalar() || !YAML::convert<double>::decode(it->second, v) || !(v > 0) ||
          !std::isfinite(v))
        m.Fail("sizes." + key_text, "expected a positive number, got '" + ScalarText(it->second) + "'");
      if (v > kMaxMarkerSize_m)
        m.Fail("sizes." + key_text, "absurd marker side length " + ScalarText(it->second) + " m (at most " +
                                        FormatDouble(kMaxMarkerSize_m) + " m)");
      mc.sizes[id] = v;
    }
  }
  mc.ids = m.GetIntList("ids");
  CheckMarkerIds(m, mc);
  mc.inverted = m.GetBool("inverted", false);
  rig.objects =
      ParseObjects(top, mc.size, mc.Sizes(), mc.ids, top.Child("tracker").GetString("object", "object"),
                   DictionarySize(mc.dictionary));

  // cameras
  if (!top.Has("cameras")) top.Fail("cameras", "missing");
  const YAML::Node cams = rig.root["cameras"];
  if (!cams.IsSequence()) top.Fail("cameras", "expected a list of cameras, got '" + ScalarText(cams) + "'");
  if (cams.size() == 0) top.Fail("cameras", "empty camera list");
  for (size_t i = 0; i < cams.size(); ++i) {
    const std::string prefix = "cameras[" + std::to_string(i) + "]";
    const YamlSection c(cams[i], path, prefix);
    if (!cams[i].IsMap())
      throw ConfigError(path + ": " + prefix + ": expected a mapping with name, intrinsics, source");
    c.CheckKnownKeys({"name", "intrinsics", "source", "timestamps"});
    CameraConfig cam;
    cam.name = c.RequireString("name");
    if (cam.name.empty()) c.Fail("name", "empty");
    if (rig.FindCamera(cam.name)) c.Fail("name", "duplicated camera name '" + cam.name + "'");
    const std::string intrinsics = c.RequireString("intrinsics");
    cam.intrinsics_path = ResolvePath(rig.dir, intrinsics);
    if (!fs::exists(cam.intrinsics_path)) c.Fail("intrinsics", "file not found: " + cam.intrinsics_path);
    try {
      cam.model = LoadIntrinsics(cam.intrinsics_path);
    } catch (const ConfigError& e) {
      c.Fail("intrinsics", e.what());
    }
    cam.source = c.GetString("source", "");
    if (!cam.source.empty()) {
      const std::string resolved = ResolvePath(rig.dir, cam.source);
      std::error_code ec;
      if (fs::exists(resolved, ec)) cam.source = resolved;
    }
    if (c.Has("timestamps")) {
      cam.timestamps_path = ResolvePath(rig.dir, c.GetString("timestamps", ""));
      if (!fs::exists(cam.timestamps_path)) c.Fail("timestamps", "file not found: " + cam.timestamps_path);
    }
    rig.cameras.push_back(std::move(cam));
  }

  // per-process sections
  rig.detector = top.Child("detector");
  rig.mapper = top.Child("mapper");
  rig.tracker = top.Child("tracker");
  rig.sync = top.Child("sync");
  rig.lcm = top.Child("lcm");
  rig.logger = top.Child("logger");
  rig.viz = top.Child("viz");
  LcmOptions lcm;
  LcmOptionTable().Load(rig.lcm, &lcm);
  rig.lcm_url = lcm.url;
  return rig;
}

}  // namespace mcmt
