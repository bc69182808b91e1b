// The simulator's scene with several bodies (mcmt-sim --scene bodies --detections-only: a static floor
// board, a tool and a patient that cross and occlude each other; 5 cameras at 1.0 m, 300 frames), mapped
// once by the mapper, for the tracker's bodies tests: poses against each body's ground truth.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/support/mapper_sim.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace tracker_test {

struct BodiesSession {
  std::unique_ptr<test::TempDir> dir;
  std::map<std::string, sim::GroundTruth> truth;  // tool, patient, floor
  std::vector<detections_t> detections;           // the log's, in its order
  RigMap map;                                     // mcmt-mapper's, rig frame = the floor's
  std::string map_path;                           // map.yaml of it
  // DIR/NAME: the session's rig.yaml with `tracker_section` appended (a `tracker:` section).
  std::string Rig(const std::string& name, const std::string& tracker_section) const {
    return dir->Write(name, ReadFile(dir->File("rig.yaml")) + tracker_section);
  }
};

// Generated and mapped on first use (the simulator and the mapper are deterministic).
inline const BodiesSession& Bodies() {
  static const BodiesSession* session = [] {
    auto* s = new BodiesSession;
    s->dir = std::make_unique<test::TempDir>("tracker_bodies");
    sim::GenerateBodiesDataset(sim::DetectionsOnlySession(s->dir->str(), 300, 1));
    for (const char* body : {"tool", "patient", "floor"})
      s->truth[body] = sim::ReadGroundTruth(s->dir->File(std::string("ground_truth_") + body + ".yaml"));
    for (const LogEvent& e : ReadEventLog(s->dir->File("detections.lcmlog"))) {
      detections_t d;
      if (Decode(e.data.data(), e.data.size(), &d)) s->detections.push_back(d);
    }
    s->map =
        test::MapMessages(s->detections, MapperOptions::FromConfig(LoadRigConfig(s->dir->File("rig.yaml"))))
            .map;
    s->map_path = s->dir->File("map.yaml");
    WriteMap(s->map_path, s->map);
    return s;
  }();
  return *session;
}

// A body's poses against its ground truth (mcmt-eval --object): map and trajectory aligned as Evaluate does.
inline sim::EvalResult EvaluateBody(const BodiesSession& s, const std::string& body,
                                    std::vector<TrajectoryRow> poses) {
  const RigMap own = sim::SelectObject(s.map, body, s.truth.at(body), &poses);
  return sim::Evaluate(s.truth.at(body), &own, &poses);
}

// The true in_from_of for a frame seq in the estimate's body frames (each body's frame as the map
// defines it: gt_object_from_est_object of its evaluation).
inline Rigid3 TrueRelative(const BodiesSession& s, const std::string& of, const std::string& in, int64_t seq,
                           const Rigid3& gt_of_from_est_of, const Rigid3& gt_in_from_est_in) {
  auto pose = [&](const std::string& body) {
    for (const sim::SimFrame& f : s.truth.at(body).frames)
      if (f.seq == seq) return f.rig_from_object;
    ADD_FAILURE() << "no ground truth of " << body << " at seq " << seq;
    return Rigid3(Rigid3::Identity());
  };
  const Rigid3 gt_in_from_gt_of = Inverse(pose(in)) * pose(of);
  return Inverse(gt_in_from_est_in) * gt_in_from_gt_of * gt_of_from_est_of;
}

}  // namespace tracker_test
}  // namespace mcmt
