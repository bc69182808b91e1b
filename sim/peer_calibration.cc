#include "sim/peer_calibration.h"

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace mcmt {
namespace sim {
namespace {

std::vector<double> Numbers(const std::string& text) {
  static const std::regex number(R"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)");
  std::vector<double> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), number); it != std::sregex_iterator(); ++it)
    out.push_back(std::stod(it->str()));
  return out;
}

}  // namespace

std::vector<PeerCamera> ReadCaliscopeCameras(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  // key -> value text per [cameras.K] section (values may span lines until brackets balance).
  std::map<int, std::map<std::string, std::string>> sections;
  int current = -1;
  std::string line, key, value;
  int depth = 0;
  static const std::regex header(R"(^\s*\[cameras\.(\d+)\]\s*$)");
  static const std::regex other_header(R"(^\s*\[.*\]\s*$)");
  static const std::regex assign(R"(^\s*([A-Za-z_]+)\s*=\s*(.*)$)");
  std::smatch m;
  while (std::getline(in, line)) {
    if (depth > 0) {
      value += line;
    } else if (std::regex_match(line, m, header)) {
      current = std::stoi(m[1]);
      continue;
    } else if (std::regex_match(line, m, other_header)) {
      current = -1;
      continue;
    } else if (std::regex_match(line, m, assign)) {
      key = m[1];
      value = m[2];
      depth = 0;
    } else {
      continue;
    }
    depth = 0;
    for (char c : value) depth += (c == '[') - (c == ']');
    if (depth <= 0 && current >= 0) sections[current][key] = value;
  }
  if (sections.empty()) throw std::runtime_error(path + ": no [cameras.N] section");
  std::vector<PeerCamera> cameras;
  for (const auto& [index, keys] : sections) {
    const std::string where = path + ": cameras." + std::to_string(index);
    auto get = [&](const std::string& k, size_t count) {
      auto it = keys.find(k);
      if (it == keys.end()) throw std::runtime_error(where + "." + k + ": missing");
      std::vector<double> v = Numbers(it->second);
      if (v.size() != count)
        throw std::runtime_error(where + "." + k + ": expected " + std::to_string(count) + " numbers, got " +
                                 std::to_string(v.size()));
      return v;
    };
    if (keys.count("ignore") && keys.at("ignore").find("true") != std::string::npos) continue;
    const std::vector<double> r = get("rotation", 9), t = get("translation", 3);
    PeerCamera c;
    c.name = "cam" + std::to_string(index);
    Eigen::Matrix3d R;
    R << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
    if (std::abs(R.determinant() - 1.0) > 1e-3 ||
        (R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3)
      throw std::runtime_error(where + ".rotation: not a rotation matrix");
    c.cam_from_world.linear() = R;
    c.cam_from_world.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    c.cam_from_world = Normalized(c.cam_from_world);
    cameras.push_back(c);
  }
  return cameras;
}

PeerAgreement CompareWithPeer(const RigMap& map, const std::vector<PeerCamera>& peer) {
  PeerAgreement out;
  std::vector<Eigen::Vector3d> ours, theirs;
  std::vector<const MapCamera*> matched;
  std::vector<Rigid3> peer_world_from_cam;
  for (const PeerCamera& p : peer) {
    const MapCamera* c = map.FindCamera(p.name);
    if (!c) {
      out.missing.push_back(p.name);
      continue;
    }
    matched.push_back(c);
    const Rigid3 world_from_cam = Inverse(p.cam_from_world);
    peer_world_from_cam.push_back(world_from_cam);
    ours.push_back(c->rig_from_cam.translation());
    theirs.push_back(world_from_cam.translation());
  }
  if (matched.size() < 2)
    throw std::runtime_error("fewer than two cameras shared by the map and the peer calibration");
  const Rigid3 world_from_rig = AlignRigid(ours, theirs);
  double dist_ours = 0, dist_theirs = 0;
  for (size_t i = 0; i < ours.size(); ++i)
    for (size_t j = i + 1; j < ours.size(); ++j) {
      dist_ours += (ours[i] - ours[j]).norm();
      dist_theirs += (theirs[i] - theirs[j]).norm();
    }
  out.scale_ratio = dist_theirs > 0 ? dist_ours / dist_theirs : 1.0;
  for (size_t i = 0; i < matched.size(); ++i) {
    const Rigid3 aligned = world_from_rig * matched[i]->rig_from_cam;
    PeerCameraAgreement a;
    a.name = matched[i]->name;
    a.position_mm = 1000.0 * (aligned.translation() - peer_world_from_cam[i].translation()).norm();
    a.rotation_deg = RotationAngle(aligned, peer_world_from_cam[i]) * 180.0 / M_PI;
    out.max_position_mm = std::max(out.max_position_mm, a.position_mm);
    out.max_rotation_deg = std::max(out.max_rotation_deg, a.rotation_deg);
    out.cameras.push_back(a);
  }
  return out;
}

std::string FormatPeerAgreement(const PeerAgreement& a) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s << "Agreement with the peer calibration (camera centres rigidly aligned, no scale):\n\n"
    << "| camera | position difference (mm) | rotation difference (deg) |\n|---|---|---|\n";
  for (const auto& c : a.cameras) {
    s.precision(1);
    s << "| " << c.name << " | " << c.position_mm << " | ";
    s.precision(2);
    s << c.rotation_deg << " |\n";
  }
  s.precision(1);
  s << "\nlargest: " << a.max_position_mm << " mm, ";
  s.precision(2);
  s << a.max_rotation_deg << " deg; scale ratio (ours / peer's camera distances): ";
  s.precision(4);
  s << a.scale_ratio << "\n";
  for (const auto& m : a.missing) s << "not in the map: " << m << "\n";
  return s.str();
}

std::string FormatPeerAgreementJson(const PeerAgreement& a) {
  std::ostringstream s;
  s.precision(17);
  s << "{\"cameras\": [";
  for (size_t i = 0; i < a.cameras.size(); ++i)
    s << (i ? ", " : "") << "{\"name\": \"" << a.cameras[i].name
      << "\", \"position_mm\": " << a.cameras[i].position_mm
      << ", \"rotation_deg\": " << a.cameras[i].rotation_deg << "}";
  s << "], \"missing\": [";
  for (size_t i = 0; i < a.missing.size(); ++i) s << (i ? ", " : "") << "\"" << a.missing[i] << "\"";
  s << "], \"max_position_mm\": " << a.max_position_mm << ", \"max_rotation_deg\": " << a.max_rotation_deg
    << ", \"scale_ratio\": " << a.scale_ratio << "}\n";
  return s.str();
}

}  // namespace sim
}  // namespace mcmt
