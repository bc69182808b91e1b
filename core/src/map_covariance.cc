#include "core/map_covariance.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

namespace mcmt {
namespace {

// 9 significant digits: a covariance is not a pose, and a camera-and-marker map of a few dozen entries
// stays small.
std::string Short(double v) {
  if (!std::isfinite(v)) return YamlNumber(v);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// A YAML double-quoted string.
std::string QuotedName(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

[[noreturn]] void Fail(const std::string& path, const std::string& key, const std::string& what) {
  throw FileFormatError(path + ": covariance" + (key.empty() ? "" : "." + key) + ": " + what);
}

}  // namespace

int MapCovariance::CameraEntry(const std::string& name) const {
  for (size_t k = 0; k < cameras.size(); ++k)
    if (cameras[k] == name) return static_cast<int>(k);
  return -1;
}

int MapCovariance::MarkerEntry(int id) const {
  for (size_t k = 0; k < markers.size(); ++k)
    if (markers[k] == id) return static_cast<int>(cameras.size() + k);
  return -1;
}

std::string MapCovarianceYaml(const MapCovariance& c) {
  std::ostringstream out;
  out << "# The map's uncertainty (core/map_covariance.h): the joint covariance of the listed cameras' and\n"
         "# markers' poses, 6 rows each (dr, dt: R <- Exp(dr) R, t <- t + dt of cam_from_rig, then of\n"
         "# object_from_marker; rad, m), cameras first. The reference camera and marker are not listed.\n";
  out << "covariance:\n  cameras: [";
  for (size_t k = 0; k < c.cameras.size(); ++k) out << (k ? ", " : "") << QuotedName(c.cameras[k]);
  out << "]\n  markers: [";
  for (size_t k = 0; k < c.markers.size(); ++k) out << (k ? ", " : "") << c.markers[k];
  out << "]\n  matrix:" << (c.matrix.rows() ? "" : " []") << "\n";
  for (int r = 0; r < c.matrix.rows(); ++r) {
    out << "    - [";
    for (int k = 0; k < c.matrix.cols(); ++k) out << (k ? ", " : "") << Short(c.matrix(r, k));
    out << "]\n";
  }
  return out.str();
}

void WriteMapWithCovariance(const std::string& path, const RigMap& map, const MapCovariance* covariance) {
  WriteFileAtomic(path, MapYaml(map) + (covariance ? MapCovarianceYaml(*covariance) : std::string()));
}

std::optional<MapCovariance> ReadMapCovariance(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(ReadFile(path));
  } catch (const YAML::Exception& e) {
    throw FileFormatError(path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
  if (!root.IsMap() || !root["covariance"]) return std::nullopt;
  const YAML::Node n = root["covariance"];
  if (!n.IsMap()) Fail(path, "", "expected a mapping");
  MapCovariance c;
  try {
    if (n["cameras"]) c.cameras = n["cameras"].as<std::vector<std::string>>();
    if (n["markers"]) c.markers = n["markers"].as<std::vector<int>>();
  } catch (const YAML::Exception&) {
    Fail(path, "", "cameras must be a list of names and markers a list of ids");
  }
  if (std::set<std::string>(c.cameras.begin(), c.cameras.end()).size() != c.cameras.size())
    Fail(path, "cameras", "a camera is listed twice");
  if (std::set<int>(c.markers.begin(), c.markers.end()).size() != c.markers.size())
    Fail(path, "markers", "a marker is listed twice");
  const int size = static_cast<int>(6 * c.Entries());
  const YAML::Node m = n["matrix"];
  if (!m || !m.IsSequence() || static_cast<int>(m.size()) != size)
    Fail(path, "matrix", "expected " + std::to_string(size) + " rows (6 per camera and marker listed)");
  c.matrix.resize(size, size);
  for (int r = 0; r < size; ++r) {
    std::vector<double> row;
    try {
      row = m[r].as<std::vector<double>>();
    } catch (const YAML::Exception&) {
      Fail(path, "matrix[" + std::to_string(r) + "]", "expected a list of numbers");
    }
    if (static_cast<int>(row.size()) != size)
      Fail(path, "matrix[" + std::to_string(r) + "]", "expected " + std::to_string(size) + " numbers");
    for (int k = 0; k < size; ++k) {
      if (!std::isfinite(row[k])) Fail(path, "matrix[" + std::to_string(r) + "]", "a number is not finite");
      c.matrix(r, k) = row[k];
    }
  }
  for (int r = 0; r < size; ++r) {
    if (c.matrix(r, r) < 0) Fail(path, "matrix", "a negative variance on row " + std::to_string(r));
    for (int k = 0; k < r; ++k) {
      const double tol = 1e-6 * std::sqrt(c.matrix(r, r) * c.matrix(k, k)) + 1e-300;
      if (std::abs(c.matrix(r, k) - c.matrix(k, r)) > tol)
        Fail(path, "matrix",
             "not symmetric (row " + std::to_string(r) + ", column " + std::to_string(k) + ")");
    }
  }
  return c;
}

}  // namespace mcmt
