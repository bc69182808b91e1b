#include "core/files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "core/map_covariance.h"
#include "core/version.h"

namespace mcmt {

std::string YamlNumber(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

namespace {

std::string Num(double v) { return YamlNumber(v); }

std::string CsvNum(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

std::string List(std::initializer_list<double> values) {
  std::string out = "[";
  bool first = true;
  for (double v : values) {
    out += (first ? "" : ", ") + Num(v);
    first = false;
  }
  return out + "]";
}

std::string Quoted(const std::string& s) {
  // Double-quoted YAML scalar with escapes, so that any name survives.
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", static_cast<unsigned char>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// The pose block: translation, quaternion (w, x, y, z) for people and other tools, and the rotation
// matrix (row-major) so that the file round-trips bit-exactly.
void WritePose(std::ostringstream& out, const std::string& indent, const std::string& name, const Rigid3& t) {
  const auto q = QuaternionWxyz(t);
  const Eigen::Vector3d p = t.translation();
  const Eigen::Matrix3d r = t.linear();
  out << indent << name << ":\n";
  out << indent << "  translation: " << List({p.x(), p.y(), p.z()}) << "\n";
  out << indent << "  rotation_wxyz: " << List({q[0], q[1], q[2], q[3]}) << "\n";
  out << indent << "  rotation_matrix: "
      << List({r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)}) << "\n";
}

class MapReader {
 public:
  explicit MapReader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& key, const std::string& what) const {
    throw FileFormatError(path_ + ": " + key + ": " + what);
  }

  YAML::Node Get(const YAML::Node& parent, const std::string& parent_key, const std::string& key) const {
    const std::string full = parent_key.empty() ? key : parent_key + "." + key;
    if (!parent.IsMap()) Fail(parent_key, "expected a mapping");
    const YAML::Node n = parent[key];
    if (!n.IsDefined() || n.IsNull()) Fail(full, "missing");
    return n;
  }

  double Double(const YAML::Node& parent, const std::string& parent_key, const std::string& key,
                bool finite = true) const {
    const YAML::Node n = Get(parent, parent_key, key);
    double v = 0;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v))
      Fail(Key(parent_key, key), "expected a number, got '" + Text(n) + "'");
    if (finite && !std::isfinite(v))
      Fail(Key(parent_key, key), "expected a finite number, got '" + Text(n) + "'");
    return v;
  }

  int Int(const YAML::Node& parent, const std::string& parent_key, const std::string& key) const {
    const YAML::Node n = Get(parent, parent_key, key);
    int v = 0;
    if (!n.IsScalar() || !YAML::convert<int>::decode(n, v))
      Fail(Key(parent_key, key), "expected an integer, got '" + Text(n) + "'");
    return v;
  }

  // Statistics are optional (a hand-written map need not have them).
  double OptDouble(const YAML::Node& parent, const std::string& parent_key, const std::string& key) const {
    const YAML::Node n = parent[key];
    return n.IsDefined() && !n.IsNull() ? Double(parent, parent_key, key, /*finite=*/false) : 0.0;
  }
  int OptInt(const YAML::Node& parent, const std::string& parent_key, const std::string& key) const {
    const YAML::Node n = parent[key];
    return n.IsDefined() && !n.IsNull() ? Int(parent, parent_key, key) : 0;
  }

  std::string String(const YAML::Node& parent, const std::string& parent_key, const std::string& key) const {
    const YAML::Node n = Get(parent, parent_key, key);
    if (!n.IsScalar()) Fail(Key(parent_key, key), "expected a string");
    return n.Scalar();
  }

  std::vector<double> Numbers(const YAML::Node& parent, const std::string& parent_key, const std::string& key,
                              int expected) const {
    const YAML::Node n = Get(parent, parent_key, key);
    const std::string full = Key(parent_key, key);
    if (!n.IsSequence()) Fail(full, "expected a list of numbers");
    if (expected >= 0 && static_cast<int>(n.size()) != expected)
      Fail(full, "expected " + std::to_string(expected) + " numbers, got " + std::to_string(n.size()));
    std::vector<double> out;
    for (size_t i = 0; i < n.size(); ++i) {
      double v = 0;
      if (!n[i].IsScalar() || !YAML::convert<double>::decode(n[i], v) || !std::isfinite(v))
        Fail(full, "item " + std::to_string(i) + ": expected a finite number, got '" + Text(n[i]) + "'");
      out.push_back(v);
    }
    return out;
  }

  Rigid3 Pose(const YAML::Node& parent, const std::string& parent_key, const std::string& key) const {
    const YAML::Node n = Get(parent, parent_key, key);
    const std::string full = Key(parent_key, key);
    const std::vector<double> t = Numbers(n, full, "translation", 3);
    const std::vector<double> q = Numbers(n, full, "rotation_wxyz", 4);
    Rigid3 pose;
    try {
      pose = RigidFromQuaternion({q[0], q[1], q[2], q[3]}, Eigen::Vector3d(t[0], t[1], t[2]));
    } catch (const std::exception& e) {
      Fail(full + ".rotation_wxyz", e.what());
    }
    const YAML::Node m = n["rotation_matrix"];
    if (m.IsDefined() && !m.IsNull()) {
      // The exact rotation; it must agree with the quaternion (someone may have edited only one).
      const std::vector<double> r = Numbers(n, full, "rotation_matrix", 9);
      Eigen::Matrix3d rot;
      rot << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
      if (!((rot.transpose() * rot - Eigen::Matrix3d::Identity()).norm() < 1e-9) || !(rot.determinant() > 0))
        Fail(full + ".rotation_matrix", "not a rotation matrix");
      if (!(RotationAngle(rot, pose.linear()) < 1e-9))
        Fail(full + ".rotation_matrix",
             "disagrees with rotation_wxyz (edit both, or delete rotation_matrix)");
      pose.linear() = rot;
    }
    return pose;
  }

  static std::string Key(const std::string& parent_key, const std::string& key) {
    return parent_key.empty() ? key : parent_key + "." + key;
  }
  static std::string Text(const YAML::Node& n) {
    return n.IsScalar() ? n.Scalar() : std::string("not a scalar");
  }

 private:
  std::string path_;
};

bool ParseInt64(const std::string& s, int64_t* out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (errno != 0 || end != s.c_str() + s.size()) return false;
  *out = v;
  return true;
}

bool ParseDouble(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return false;
  *out = v;
  return true;
}

}  // namespace

void WriteFileAtomic(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw FileFormatError(path + ": cannot write: " + std::strerror(errno));
  size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string reason = std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw FileFormatError(path + ": cannot write: " + reason);
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string reason = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw FileFormatError(path + ": cannot write: " + reason);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw FileFormatError(path + ": cannot rename " + tmp + ": " + reason);
  }
  // Make the rename itself durable (best effort: some file systems refuse fsync on folders).
  const std::string::size_type slash = path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const int dir_fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    (void)::fsync(dir_fd);
    ::close(dir_fd);
  }
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileFormatError(path + ": cannot open file");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw FileFormatError(path + ": read error");
  return s.str();
}

const MapCamera* RigMap::FindCamera(const std::string& name) const {
  for (const auto& c : cameras)
    if (c.name == name) return &c;
  return nullptr;
}

int64_t RigMap::ReferenceUtime(const std::string& camera, int64_t utime) const {
  const MapCamera* c = FindCamera(camera);
  return c ? utime - std::llround(c->ClockUs(utime, time_reference_utime)) : utime;
}

bool RigMap::HasClocks() const {
  for (const MapCamera& c : cameras)
    if (c.time_offset_us != 0 || c.time_drift_ppm != 0) return true;
  return false;
}

void ComposeClocks(const RigMap& applied, RigMap* map) {
  const int64_t reference =
      map->time_reference_utime != 0 ? map->time_reference_utime : applied.time_reference_utime;
  for (MapCamera& c : map->cameras) {
    double offset_us = c.ClockUs(reference, map->time_reference_utime);
    if (const MapCamera* a = applied.FindCamera(c.name)) {
      offset_us += a->ClockUs(reference, applied.time_reference_utime);
      c.time_drift_ppm += a->time_drift_ppm;
    }
    c.time_offset_us = offset_us;
  }
  map->time_reference_utime = reference;
}

const MapMarker* RigMap::FindMarker(int id) const {
  for (const auto& m : markers)
    if (m.id == id) return &m;
  return nullptr;
}

namespace {

void WriteMarkers(std::ostringstream& out, const std::string& indent, const std::vector<MapMarker>& markers) {
  out << indent << "markers:" << (markers.empty() ? " []" : "") << "\n";
  for (const auto& m : markers) {
    out << indent << "  - id: " << m.id << "\n";
    out << indent << "    size: " << Num(m.size) << "\n";
    WritePose(out, indent + "    ", "object_from_marker", m.object_from_marker);
    out << indent << "    observations: " << m.observations << "\n";
    out << indent << "    rms_px: " << Num(m.rms_px) << "\n";
    out << indent << "    max_px: " << Num(m.max_px) << "\n";
  }
}

}  // namespace

size_t FirstMovingObject(const RigMap& map) {
  for (size_t k = 0; k < map.objects.size(); ++k)
    if (!map.objects[k].is_static) return k;
  return 0;
}

const MapObject* RigMap::FindObject(const std::string& name) const {
  for (const auto& o : objects)
    if (o.name == name) return &o;
  return nullptr;
}

RigMap RigMap::ObjectMap(size_t k) const {
  RigMap out = *this;
  out.version = kMapVersion;
  out.objects.clear();
  out.markers = objects.at(k).markers;
  out.reference_marker = objects.at(k).reference_marker;
  return out;
}

std::string MapYaml(const RigMap& map) {
  std::ostringstream out;
  out << "# mcmt map: rig frame = reference camera, object frame = reference marker.\n";
  out << "# rig_from_cam maps camera points into the rig frame; object_from_marker maps marker points into\n";
  out << "# the object frame. Quaternions w, x, y, z; rotation_matrix row-major (exact copy of the "
         "rotation).\n";
  out << "version: " << (map.objects.empty() ? kMapVersion : kMapVersionBodies) << "\n";
  out << "written_by: " << Quoted(std::string("mcmt ") + Version()) << "\n";
  out << "dictionary: " << Quoted(map.dictionary) << "\n";
  out << "reference_camera: " << Quoted(map.reference_camera) << "\n";
  if (map.objects.empty()) out << "reference_marker: " << map.reference_marker << "\n";
  if (!map.rig_frame.empty()) out << "rig_frame: " << Quoted(map.rig_frame) << "\n";
  out << "rms_px: " << Num(map.rms_px) << "\n";
  out << "num_frames: " << map.num_frames << "\n";
  out << "num_observations: " << map.num_observations << "\n";
  bool drift = false;
  for (const auto& c : map.cameras) drift = drift || c.time_drift_ppm != 0;
  if (drift) out << "time_reference_utime: " << map.time_reference_utime << "\n";
  out << "cameras:" << (map.cameras.empty() ? " []" : "") << "\n";
  for (const auto& c : map.cameras) {
    const CameraModel& k = c.model;
    out << "  - name: " << Quoted(c.name) << "\n";
    out << "    intrinsics:\n";
    out << "      width: " << k.width << "\n";
    out << "      height: " << k.height << "\n";
    out << "      fx: " << Num(k.fx) << "\n";
    out << "      fy: " << Num(k.fy) << "\n";
    out << "      cx: " << Num(k.cx) << "\n";
    out << "      cy: " << Num(k.cy) << "\n";
    out << "      distortion_model: " << DistortionModelName(k.model) << "\n";
    out << "      distortion: [";
    for (size_t i = 0; i < k.distortion.size(); ++i) out << (i ? ", " : "") << Num(k.distortion[i]);
    out << "]\n";
    WritePose(out, "    ", "rig_from_cam", c.rig_from_cam);
    out << "    observations: " << c.observations << "\n";
    out << "    rms_px: " << Num(c.rms_px) << "\n";
    out << "    max_px: " << Num(c.max_px) << "\n";
    if (c.time_offset_us != 0) out << "    time_offset_us: " << Num(c.time_offset_us) << "\n";
    if (c.time_drift_ppm != 0) out << "    time_drift_ppm: " << Num(c.time_drift_ppm) << "\n";
  }
  if (map.objects.empty()) {
    WriteMarkers(out, "", map.markers);
  } else {
    out << "objects:\n";
    for (const MapObject& o : map.objects) {
      out << "  - name: " << Quoted(o.name) << "\n";
      out << "    static: " << (o.is_static ? "true" : "false") << "\n";
      out << "    reference_marker: " << o.reference_marker << "\n";
      if (o.is_static) WritePose(out, "    ", "rig_from_object", o.rig_from_object);
      out << "    rms_px: " << Num(o.rms_px) << "\n";
      out << "    num_frames: " << o.num_frames << "\n";
      out << "    num_observations: " << o.num_observations << "\n";
      WriteMarkers(out, "    ", o.markers);
    }
  }
  return out.str();
}

void WriteMap(const std::string& path, const RigMap& map) { WriteFileAtomic(path, MapYaml(map)); }

std::string DuplicateYamlKey(const YAML::Node& root) {
  if (root.IsSequence()) {
    for (const YAML::Node& item : root) {
      const std::string found = DuplicateYamlKey(item);
      if (!found.empty()) return found;
    }
  } else if (root.IsMap()) {
    std::map<std::string, int> first_line;
    for (auto it = root.begin(); it != root.end(); ++it) {
      if (it->first.IsScalar()) {
        const int line = it->first.Mark().line + 1;
        const auto [where, fresh] = first_line.emplace(it->first.Scalar(), line);
        if (!fresh)
          return std::to_string(line) + ": duplicated key '" + it->first.Scalar() + "' (first at line " +
                 std::to_string(where->second) + ")";
      }
      const std::string found = DuplicateYamlKey(it->second);
      if (!found.empty()) return found;
    }
  }
  return "";
}

namespace {

// A marker list at `parent_key` + "markers" (ids unique within it).
std::vector<MapMarker> ReadMarkers(const MapReader& r, const YAML::Node& parent,
                                   const std::string& parent_key) {
  const std::string list_key = parent_key.empty() ? "markers" : parent_key + ".markers";
  const YAML::Node markers = r.Get(parent, parent_key, "markers");
  if (!markers.IsSequence()) r.Fail(list_key, "expected a list");
  std::vector<MapMarker> out;
  for (size_t i = 0; i < markers.size(); ++i) {
    const std::string key = list_key + "[" + std::to_string(i) + "]";
    const YAML::Node m = markers[i];
    if (!m.IsMap()) r.Fail(key, "expected a mapping");
    MapMarker marker;
    marker.id = r.Int(m, key, "id");
    marker.size = r.Double(m, key, "size");
    if (!(marker.size > 0)) r.Fail(key + ".size", "must be positive");
    marker.object_from_marker = r.Pose(m, key, "object_from_marker");
    marker.observations = r.OptInt(m, key, "observations");
    marker.rms_px = r.OptDouble(m, key, "rms_px");
    marker.max_px = r.OptDouble(m, key, "max_px");
    for (const MapMarker& seen : out)
      if (seen.id == marker.id) r.Fail(key + ".id", "duplicated marker id " + std::to_string(marker.id));
    out.push_back(marker);
  }
  return out;
}

// Version 2: objects: [{name, static, reference_marker, rig_from_object (static), markers}]; the first
// object's markers are also map.markers (what a single-object reader uses).
void ReadObjects(const MapReader& r, const YAML::Node& root, RigMap* map) {
  const YAML::Node objects = r.Get(root, "", "objects");
  if (!objects.IsSequence() || objects.size() == 0) r.Fail("objects", "expected a non-empty list");
  std::map<int, std::string> owner;
  for (size_t i = 0; i < objects.size(); ++i) {
    const std::string key = "objects[" + std::to_string(i) + "]";
    const YAML::Node n = objects[i];
    if (!n.IsMap()) r.Fail(key, "expected a mapping");
    MapObject o;
    o.name = r.String(n, key, "name");
    if (map->FindObject(o.name)) r.Fail(key + ".name", "duplicated object '" + o.name + "'");
    const std::string is_static = r.String(n, key, "static");
    if (is_static != "true" && is_static != "false") r.Fail(key + ".static", "expected true or false");
    o.is_static = is_static == "true";
    o.reference_marker = r.Int(n, key, "reference_marker");
    if (o.is_static) o.rig_from_object = r.Pose(n, key, "rig_from_object");
    o.rms_px = r.OptDouble(n, key, "rms_px");
    o.num_frames = r.OptInt(n, key, "num_frames");
    o.num_observations = r.OptInt(n, key, "num_observations");
    o.markers = ReadMarkers(r, n, key);
    for (const MapMarker& m : o.markers) {
      const auto [it, fresh] = owner.emplace(m.id, o.name);
      if (!fresh)
        r.Fail(key + ".markers",
               "marker id " + std::to_string(m.id) + " is in both '" + it->second + "' and '" + o.name + "'");
    }
    map->objects.push_back(o);
  }
  if (!map->rig_frame.empty() && !map->FindObject(map->rig_frame))
    r.Fail("rig_frame", "no object named '" + map->rig_frame + "'");
  const MapObject& first = map->objects[FirstMovingObject(*map)];
  map->markers = first.markers;
  map->reference_marker = first.reference_marker;
}

}  // namespace

RigMap ReadMap(const std::string& path) {
  const std::string text = ReadFile(path);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FileFormatError(path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
  const std::string duplicate = DuplicateYamlKey(root);
  if (!duplicate.empty()) throw FileFormatError(path + ":" + duplicate);
  MapReader r(path);
  if (!root.IsMap()) throw FileFormatError(path + ": not a map file (expected a YAML mapping)");
  RigMap map;
  map.version = r.Int(root, "", "version");
  if (map.version != kMapVersion && map.version != kMapVersionBodies)
    r.Fail("version", "unsupported map version " + std::to_string(map.version) + " (this build reads " +
                          std::to_string(kMapVersion) + " and " + std::to_string(kMapVersionBodies) + ")");
  map.dictionary = r.String(root, "", "dictionary");
  map.reference_camera = r.String(root, "", "reference_camera");
  if (map.version == kMapVersion) map.reference_marker = r.Int(root, "", "reference_marker");
  if (root["rig_frame"]) map.rig_frame = r.String(root, "", "rig_frame");
  map.rms_px = r.OptDouble(root, "", "rms_px");
  map.num_frames = r.OptInt(root, "", "num_frames");
  map.num_observations = r.OptInt(root, "", "num_observations");
  const double reference_utime = r.OptDouble(root, "", "time_reference_utime");
  if (!(std::abs(reference_utime) < 9e18)) r.Fail("time_reference_utime", "expected a utime (us)");
  map.time_reference_utime = static_cast<int64_t>(std::llround(reference_utime));
  const YAML::Node cams = r.Get(root, "", "cameras");
  if (!cams.IsSequence()) r.Fail("cameras", "expected a list");
  for (size_t i = 0; i < cams.size(); ++i) {
    const std::string key = "cameras[" + std::to_string(i) + "]";
    const YAML::Node c = cams[i];
    if (!c.IsMap()) r.Fail(key, "expected a mapping");
    MapCamera cam;
    cam.name = r.String(c, key, "name");
    const std::string ik = key + ".intrinsics";
    const YAML::Node in = r.Get(c, key, "intrinsics");
    CameraModel& k = cam.model;
    k.width = r.Int(in, ik, "width");
    k.height = r.Int(in, ik, "height");
    k.fx = r.Double(in, ik, "fx");
    k.fy = r.Double(in, ik, "fy");
    k.cx = r.Double(in, ik, "cx");
    k.cy = r.Double(in, ik, "cy");
    try {
      k.model = DistortionModelFromName(r.String(in, ik, "distortion_model"));
    } catch (const std::invalid_argument& e) {
      r.Fail(ik + ".distortion_model", e.what());
    }
    k.distortion = r.Numbers(in, ik, "distortion", -1);
    try {
      k.Validate();
    } catch (const std::invalid_argument& e) {
      r.Fail(ik, e.what());
    }
    cam.rig_from_cam = r.Pose(c, key, "rig_from_cam");
    cam.observations = r.OptInt(c, key, "observations");
    cam.rms_px = r.OptDouble(c, key, "rms_px");
    cam.max_px = r.OptDouble(c, key, "max_px");
    cam.time_offset_us = r.OptDouble(c, key, "time_offset_us");
    if (!std::isfinite(cam.time_offset_us)) r.Fail(key + ".time_offset_us", "expected a finite number");
    cam.time_drift_ppm = r.OptDouble(c, key, "time_drift_ppm");
    if (!std::isfinite(cam.time_drift_ppm) || !(std::abs(cam.time_drift_ppm) < 1e5))
      r.Fail(key + ".time_drift_ppm", "expected a number within +-1e5");
    if (map.FindCamera(cam.name)) r.Fail(key + ".name", "duplicated camera '" + cam.name + "'");
    map.cameras.push_back(cam);
  }
  if (map.version == kMapVersion) {
    map.markers = ReadMarkers(r, root, "");
  } else {
    ReadObjects(r, root, &map);
  }
  if (!map.reference_camera.empty() && !map.cameras.empty() && !map.FindCamera(map.reference_camera))
    r.Fail("reference_camera", "'" + map.reference_camera + "' is not among the cameras");
  return map;
}

const char kTrajectoryHeader[] = "utime,seq,tx,ty,tz,qw,qx,qy,qz,rms_px,cameras,markers";
const char kTrajectoryVelocityHeader[] =
    "utime,seq,tx,ty,tz,qw,qx,qy,qz,rms_px,cameras,markers,wx,wy,wz,vx,vy,vz";

namespace {

const char kQualityColumns[] = ",status,sigma_position_m,sigma_rotation_rad";
const char kStatusTracking[] = "tracking";
const char kStatusAmbiguous[] = "ambiguous";

}  // namespace

PoseQuality QualityOfPose(const Rigid3& rig_from_object, const Matrix6d& covariance, bool ambiguous) {
  // The largest eigenvalue of each block: the standard deviation along the worst direction. A covariance
  // that is not positive semi-definite (a degenerate solve) has no finite sigma.
  auto worst_sigma = [](const Eigen::Matrix3d& c) {
    const Eigen::Vector3d ev =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c, Eigen::EigenvaluesOnly).eigenvalues();
    return std::isfinite(ev(2)) && ev(0) >= -1e-12 * std::abs(ev(2)) ? std::sqrt(std::max(0.0, ev(2))) : NAN;
  };
  PoseQuality q;
  q.ambiguous = ambiguous;
  q.sigma_position_m = worst_sigma(PositionCovariance(rig_from_object, covariance));
  q.sigma_rotation_rad = worst_sigma(covariance.bottomRightCorner<3, 3>());
  return q;
}

void MoveToRig(const Rigid3& new_rig_from_rig, TrajectoryRow* row) {
  row->rig_from_object = Normalized(new_rig_from_rig * row->rig_from_object);
  if (row->velocity) row->velocity = TwistIn(new_rig_from_rig, *row->velocity);
}

std::string TrajectoryHeader(bool velocity, bool quality) {
  return std::string(velocity ? kTrajectoryVelocityHeader : kTrajectoryHeader) +
         (quality ? kQualityColumns : "");
}

namespace {

// Which of the four headers `line` is (a trailing '\r' allowed): {velocity, quality}; none for another line.
std::optional<std::pair<bool, bool>> TrajectoryHeaderColumns(const std::string& line) {
  const std::string s = !line.empty() && line.back() == '\r' ? line.substr(0, line.size() - 1) : line;
  for (bool velocity : {false, true})
    for (bool quality : {false, true})
      if (s == TrajectoryHeader(velocity, quality)) return std::make_pair(velocity, quality);
  return std::nullopt;
}

}  // namespace

bool IsTrajectoryHeader(const std::string& line) { return TrajectoryHeaderColumns(line).has_value(); }

std::string TrajectoryCsvLine(const TrajectoryRow& row, bool velocity, bool quality) {
  const auto q = QuaternionWxyz(row.rig_from_object);
  const Eigen::Vector3d t = row.rig_from_object.translation();
  std::string line = std::to_string(row.utime) + "," + std::to_string(row.seq);
  for (double v : {t.x(), t.y(), t.z(), q[0], q[1], q[2], q[3], row.rms_px}) line += "," + CsvNum(v);
  line += "," + std::to_string(row.cameras) + "," + std::to_string(row.markers);
  if (velocity)
    for (int k = 0; k < 6; ++k) line += "," + (row.velocity ? CsvNum((*row.velocity)[k]) : std::string());
  if (quality) line += PoseQualityCsv(row.quality);
  return line;
}

std::string PoseQualityCsv(const std::optional<PoseQuality>& q) {
  if (!q) return ",,,";
  return std::string(",") + (q->ambiguous ? kStatusAmbiguous : kStatusTracking) + "," +
         CsvNum(q->sigma_position_m) + "," + CsvNum(q->sigma_rotation_rad);
}

void WriteTrajectory(const std::string& path, const std::vector<TrajectoryRow>& rows, bool quality) {
  const bool velocity =
      std::any_of(rows.begin(), rows.end(), [](const TrajectoryRow& r) { return r.velocity.has_value(); });
  quality = quality || std::any_of(rows.begin(), rows.end(),
                                   [](const TrajectoryRow& r) { return r.quality.has_value(); });
  std::string content = TrajectoryHeader(velocity, quality) + "\n";
  for (const auto& row : rows) content += TrajectoryCsvLine(row, velocity, quality) + "\n";
  WriteFileAtomic(path, content);
}

namespace {

const char* const kTrajectoryColumns[] = {"utime",  "seq",     "tx",      "ty", "tz", "qw", "qx", "qy", "qz",
                                          "rms_px", "cameras", "markers", "wx", "wy", "wz", "vx", "vy", "vz"};

bool AllEmpty(const std::vector<std::string>& fields, size_t begin, size_t end) {
  return std::all_of(fields.begin() + begin, fields.begin() + end,
                     [](const std::string& f) { return f.empty(); });
}

// The three quality fields from fields[at..at+2]: all empty (none) or a status word and two sigmas.
std::optional<PoseQuality> ParseQuality(const std::vector<std::string>& fields, size_t at,
                                        const std::string& where) {
  if (AllEmpty(fields, at, at + 3)) return std::nullopt;
  PoseQuality q;
  if (fields[at] == kStatusAmbiguous)
    q.ambiguous = true;
  else if (fields[at] != kStatusTracking)
    throw FileFormatError(where + "status: expected '" + kStatusTracking + "' or '" + kStatusAmbiguous +
                          "', got '" + fields[at] +
                          "' (the status and sigma columns are all given or all empty)");
  const char* names[2] = {"sigma_position_m", "sigma_rotation_rad"};
  double* values[2] = {&q.sigma_position_m, &q.sigma_rotation_rad};
  for (int k = 0; k < 2; ++k)  // "nan": a pose whose covariance had no finite sigma (QualityOfPose)
    if (!ParseDouble(fields[at + 1 + k], values[k]) || *values[k] < 0 || std::isinf(*values[k]))
      throw FileFormatError(where + names[k] + ": not a number >= 0: '" + fields[at + 1 + k] + "'");
  return q;
}

// One row of the trajectory's fields (12, + 6 velocity columns: all six given or all empty, + 3 quality
// columns); `where` is "FILE:LINE: ".
TrajectoryRow ParseTrajectoryRow(const std::vector<std::string>& fields, bool velocity, bool quality,
                                 const std::string& where) {
  TrajectoryRow row;
  int64_t cams = 0, marks = 0;
  double v[8];
  if (!ParseInt64(fields[0], &row.utime))
    throw FileFormatError(where + "utime: not an integer: '" + fields[0] + "'");
  if (!ParseInt64(fields[1], &row.seq))
    throw FileFormatError(where + "seq: not an integer: '" + fields[1] + "'");
  for (int i = 0; i < 8; ++i)
    if (!ParseDouble(fields[2 + i], &v[i]))
      throw FileFormatError(where + kTrajectoryColumns[2 + i] + ": not a number: '" + fields[2 + i] + "'");
  if (!ParseInt64(fields[10], &cams))
    throw FileFormatError(where + "cameras: not an integer: '" + fields[10] + "'");
  if (!ParseInt64(fields[11], &marks))
    throw FileFormatError(where + "markers: not an integer: '" + fields[11] + "'");
  try {
    row.rig_from_object = RigidFromQuaternion({v[3], v[4], v[5], v[6]}, Eigen::Vector3d(v[0], v[1], v[2]));
  } catch (const std::exception& e) {
    throw FileFormatError(where + "qw..qz: " + e.what());
  }
  row.rms_px = v[7];
  row.cameras = static_cast<int>(cams);
  row.markers = static_cast<int>(marks);
  if (velocity && !AllEmpty(fields, 12, 18)) {
    row.velocity.emplace();
    for (int k = 0; k < 6; ++k)
      if (!ParseDouble(fields[12 + k], &(*row.velocity)[k]) || !std::isfinite((*row.velocity)[k]))
        throw FileFormatError(where + kTrajectoryColumns[12 + k] + ": not a finite number: '" +
                              fields[12 + k] + "' (the velocity columns are all given or all empty)");
  }
  if (quality) row.quality = ParseQuality(fields, velocity ? 18 : 12, where);
  return row;
}

}  // namespace

std::vector<TrajectoryRow> ReadTrajectory(const std::string& path) {
  std::istringstream in(ReadFile(path));
  std::vector<TrajectoryRow> rows;
  std::string line;
  int line_number = 0;
  size_t columns = 0;  // of the header; 0 before it
  bool velocity = false, quality = false;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    if (columns == 0) {
      const auto header = TrajectoryHeaderColumns(line);
      if (!header)
        throw FileFormatError(where + "expected the header '" + std::string(kTrajectoryHeader) +
                              "' (optionally followed by ',wx,wy,wz,vx,vy,vz' and then '" + kQualityColumns +
                              "')");
      std::tie(velocity, quality) = *header;
      columns = 12 + (velocity ? 6 : 0) + (quality ? 3 : 0);
      continue;
    }
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) fields.push_back(field);
    if (!line.empty() && line.back() == ',') fields.push_back("");
    if (fields.size() != columns)
      throw FileFormatError(where + "expected " + std::to_string(columns) + " fields, got " +
                            std::to_string(fields.size()));
    rows.push_back(ParseTrajectoryRow(fields, velocity, quality, where));
  }
  if (columns == 0)
    throw FileFormatError(path + ": empty file (expected the header '" + std::string(kTrajectoryHeader) +
                          "')");
  return rows;
}

std::vector<std::pair<std::string, std::string>> MapperTrajectories(const std::string& outdir) {
  const std::string map_path = outdir + "/map.yaml";
  std::vector<std::pair<std::string, std::string>> out;
  struct stat st;
  if (::stat(map_path.c_str(), &st) != 0) {
    out.emplace_back("", outdir + "/trajectory.csv");
  } else {
    const RigMap map = ReadMap(map_path);
    if (map.objects.empty()) out.emplace_back("", outdir + "/trajectory.csv");
    for (const MapObject& o : map.objects)
      if (!o.is_static) out.emplace_back(o.name, outdir + "/trajectory_" + o.name + ".csv");
    if (out.empty())
      throw FileFormatError(map_path +
                            ": every body is static: no trajectory to export (their poses are "
                            "rig_from_object in the map)");
  }
  for (const auto& [body, path] : out)
    if (::stat(path.c_str(), &st) != 0)
      throw FileFormatError(path + ": no such trajectory (is " + outdir + " an mcmt-mapper OUTDIR?)");
  return out;
}

std::string BodyPath(const std::string& path, const std::string& body) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  const bool has_ext = dot != std::string::npos && dot > (slash == std::string::npos ? 0 : slash + 1);
  return has_ext ? path.substr(0, dot) + "_" + body + path.substr(dot) : path + "_" + body;
}

std::vector<std::pair<std::string, std::string>> BodyTrajectoryFiles(const std::string& path,
                                                                     const RigMap& map) {
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) return MapperTrajectories(path);
  std::vector<std::pair<std::string, std::string>> out;
  std::string looked;
  for (const MapObject& o : map.objects) {
    if (o.is_static) continue;
    const std::string file = BodyPath(path, o.name);
    looked += (looked.empty() ? "" : ", ") + file;
    if (::stat(file.c_str(), &st) == 0) out.emplace_back(o.name, file);
  }
  if (out.empty())
    throw FileFormatError(path + ": neither the mapper's OUTDIR nor the tracker's per-body files (" +
                          (looked.empty() ? std::string("the map has no moving body") : looked) + ")");
  return out;
}

}  // namespace mcmt
