// The maintain re-estimate of a bumped camera (mcmt-mapper --maintain's update, mapper/maintain.h), offline
// and deterministic: from a rendered session (mcmt-sim --video --move-camera CAM,FRAME,...) and its
// detections as diag_session prints them, the map of the session's start (its ground truth before the
// bump) updated with only CAM free from the first N frames from SINCE on in which CAM and another camera
// see markers (the live node takes the frames where the tracker has a pose without CAM: about these).
// Prints CAM's position / rotation error against the truth at the end. With B and a list of
// camera:seq:id, those markers are taken from B's detections instead of A's (absent in B: dropped).
//   diag_maintain SESSION_DIR CAM SINCE N A.txt [B.txt [cam:seq:id,...]]
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

#include "core/config.h"
#include "core/lcm_util.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"

using namespace mcmt;

namespace {
using Key = std::tuple<std::string, int64_t>;  // camera, seq
std::map<Key, std::map<int, marker_t>> Load(const std::string& path) {
  std::map<Key, std::map<int, marker_t>> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::string cam;
    long long seq;
    int id, k;
    double x, y;
    s >> cam >> seq >> id >> k >> x >> y;
    marker_t& m = out[{cam, seq}][id];
    m.id = id;
    m.corners[k][0] = x, m.corners[k][1] = y;
  }
  return out;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: diag_maintain SESSION_DIR CAM SINCE N A.txt [B.txt [cam:seq:id,...]]\n");
    return 2;
  }
  const std::string dir = argv[1], moved = argv[2];
  const int64_t since = std::atoll(argv[3]);
  const int frames = std::atoi(argv[4]);
  auto dets = Load(argv[5]);
  if (argc > 6) {
    const auto other = Load(argv[6]);
    std::set<std::tuple<std::string, int64_t, int>> swap;
    if (argc > 7) {
      std::istringstream list(argv[7]);
      std::string item;
      while (std::getline(list, item, ',')) {
        const size_t a = item.find(':'), b = item.rfind(':');
        swap.insert({item.substr(0, a), std::atoll(item.substr(a + 1, b - a - 1).c_str()),
                     std::atoi(item.substr(b + 1).c_str())});
      }
    }
    for (const auto& [cam, seq, id] : swap) {
      dets[{cam, seq}].erase(id);
      const auto it = other.find({cam, seq});
      if (it != other.end() && it->second.count(id)) dets[{cam, seq}][id] = it->second.at(id);
    }
  }
  const RigConfig rig = LoadRigConfig(dir + "/rig.yaml");
  const sim::GroundTruth truth = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
  const RigMap start = sim::MapFromGroundTruth(truth, 0, 0);
  Mapper mapper(MapperOptions::FromConfig(rig));
  mapper.SetBaseMap(start, false, {moved});
  int used = 0;
  for (const sim::SimFrame& f : truth.frames) {
    if (f.seq < since || used >= frames) continue;
    const auto own = dets.find({moved, f.seq});
    if (own == dets.end() || own->second.empty()) continue;
    bool others = false;
    for (const sim::SimCamera& c : truth.cameras)
      if (c.name != moved && dets.count({c.name, f.seq}) && !dets[{c.name, f.seq}].empty()) others = true;
    if (!others) continue;
    ++used;
    for (const sim::SimCamera& c : truth.cameras) {
      const auto it = dets.find({c.name, f.seq});
      if (it == dets.end()) continue;
      detections_t d;
      d.utime = f.utime;
      d.seq = f.seq;
      d.camera = c.name;
      d.dictionary = truth.dictionary;
      d.camera_model = ToCameraModelMsg(rig.GetCamera(c.name).model);
      for (const auto& [id, m] : it->second) d.markers.push_back(m);
      d.num_markers = static_cast<int32_t>(d.markers.size());
      mapper.Add(d);
    }
  }
  const MapResult result = mapper.Solve();
  const sim::EvalResult eval = sim::Evaluate(sim::TruthAtEnd(truth), &result.map, nullptr);
  std::printf("%s from %d frames (seq %lld on): cameras within %.3f mm, %.4f deg\n", moved.c_str(), used,
              static_cast<long long>(since), eval.camera_position_mm.max, eval.camera_rotation_deg.max);
  return 0;
}
