// Several rigid bodies (issue 16): the mapper on the simulator's bodies scene (`mcmt-sim --scene bodies
// --detections-only`: a static floor board, a tool and a patient that cross and occlude each other; 5
// cameras 640x480 at 1.0 m, 0.1 px corner noise), in-process.
//
//   bench_bodies [--quick] [--frames 150,300,600,1200] [--threads N]
//
// Prints markdown tables: each body's errors against its ground truth (sim::Evaluate after rigid
// alignment) mapped with the floor, without it, each moving body alone, and with objects: auto; then the
// mapping time against frames x bodies.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/config.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"

namespace fs = std::filesystem;

namespace {

struct Session {
  std::string dir;
  std::map<std::string, mcmt::sim::GroundTruth> truth;  // per body
  std::vector<mcmt::detections_t> detections;
};

Session Generate(const std::string& dir, int frames) {
  Session s;
  s.dir = dir;
  mcmt::sim::GenerateBodiesDataset(mcmt::sim::DetectionsOnlySession(dir, frames, 1));
  for (const char* body : {"tool", "patient", "floor"})
    s.truth[body] = mcmt::sim::ReadGroundTruth(dir + "/ground_truth_" + body + ".yaml");
  for (const mcmt::LogEvent& e : mcmt::ReadEventLog(dir + "/detections.lcmlog")) {
    mcmt::detections_t d;
    if (mcmt::Decode(e.data.data(), e.data.size(), &d)) s.detections.push_back(d);
  }
  return s;
}

mcmt::MapResult Map(const Session& s, const mcmt::MapperOptions& o) {
  mcmt::Mapper mapper(o);
  for (const mcmt::detections_t& d : s.detections) mapper.Add(d);
  return mapper.Solve();
}

mcmt::MapperOptions RigOptions(const Session& s, const std::string& rig, int threads) {
  mcmt::MapperOptions o = mcmt::MapperOptions::FromConfig(mcmt::LoadRigConfig(s.dir + "/" + rig));
  o.threads = threads;
  return o;
}

// One body as the only object (its ids, its sizes).
mcmt::MapperOptions Alone(mcmt::MapperOptions o, const std::string& body) {
  for (const mcmt::MapperBody& b : o.bodies)
    if (b.name == body) {
      o.marker_ids = b.ids;
      o.sizes = b.sizes;
    }
  o.bodies.clear();
  o.rig_frame.clear();
  return o;
}

// objects: auto with the scene's marker sides.
mcmt::MapperOptions Auto(mcmt::MapperOptions o, const Session& s) {
  mcmt::MapperBody all;
  all.auto_ids = true;
  all.sizes.default_size = s.truth.at("tool").marker_size;
  for (const auto& [name, truth] : s.truth)
    for (const auto& [id, size] : truth.marker_sizes)
      if (size != all.sizes.default_size) all.sizes.overrides[id] = size;
  o.bodies = {all};
  o.rig_frame.clear();
  return o;
}

// The map's object that holds marker `id` (auto names differ from the truth's).
const mcmt::MapObject* ObjectWith(const mcmt::RigMap& map, int id) {
  for (const mcmt::MapObject& o : map.objects)
    for (const mcmt::MapMarker& m : o.markers)
      if (m.id == id) return &o;
  return nullptr;
}

// A body's errors in a result (several bodies: its object; one object: the map itself).
bool EvaluateBody(const Session& s, const mcmt::MapResult& r, const std::string& body,
                  mcmt::sim::EvalResult* e) {
  const mcmt::sim::GroundTruth& truth = s.truth.at(body);
  if (r.map.objects.empty()) {
    *e = mcmt::sim::Evaluate(truth, &r.map, &r.trajectory);
    return true;
  }
  const mcmt::MapObject* object = ObjectWith(r.map, truth.markers.front().id);
  if (!object) return false;
  std::vector<mcmt::TrajectoryRow> trajectory;
  if (!object->is_static) trajectory = r.object_trajectories[object - r.map.objects.data()];
  const mcmt::RigMap own = mcmt::sim::SelectObject(r.map, object->name, truth, &trajectory);
  *e = mcmt::sim::Evaluate(truth, &own, &trajectory);
  return true;
}

std::string Fmt(double v, int digits = 3) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

void AccuracyTable(const Session& s, int threads) {
  struct Run {
    std::string name;
    mcmt::MapperOptions options;
    std::vector<std::string> bodies;
  };
  const mcmt::MapperOptions with_floor = RigOptions(s, "rig.yaml", threads);
  const std::vector<Run> runs = {
      {"tool + patient + static floor (rig.yaml)", with_floor, {"tool", "patient", "floor"}},
      {"tool + patient, no floor (rig_moving.yaml)",
       RigOptions(s, "rig_moving.yaml", threads),
       {"tool", "patient"}},
      {"tool alone", Alone(with_floor, "tool"), {"tool"}},
      {"patient alone", Alone(with_floor, "patient"), {"patient"}},
      {"objects: auto", Auto(with_floor, s), {"tool", "patient", "floor"}},
  };
  std::cout << "## Several rigid bodies: accuracy per body (" << s.truth.at("tool").frames.size()
            << " frames, 5 cameras 640x480 at 1.0 m, 0.1 px corner noise; sim::Evaluate after rigid "
               "alignment, mean / max)\n\n"
            << "| mapped as | body | layout (mm) | pose translation (mm) | pose rotation (deg) | frames with "
               "a pose | cameras (mm) | mapping (s) |\n"
            << "|---|---|---:|---:|---:|---:|---:|---:|\n";
  for (const Run& run : runs) {
    mcmt::MapResult r;
    try {
      r = Map(s, run.options);
    } catch (const std::exception& e) {
      std::cout << "| " << run.name << " | | " << e.what() << " | | | | | |\n";
      continue;
    }
    for (const std::string& body : run.bodies) {
      mcmt::sim::EvalResult e;
      std::cout << "| " << run.name << " | " << body << " | ";
      if (!EvaluateBody(s, r, body, &e)) {
        std::cout << "not mapped | | | | | |\n";
        continue;
      }
      const bool moving = body != "floor";
      std::cout << Fmt(e.configuration_mm.mean) << " / " << Fmt(e.configuration_mm.max) << " | "
                << (moving ? Fmt(e.object_translation_mm.mean) + " / " + Fmt(e.object_translation_mm.max)
                           : "static")
                << " | "
                << (moving ? Fmt(e.object_rotation_deg.mean) + " / " + Fmt(e.object_rotation_deg.max) : "")
                << " | "
                << (moving ? std::to_string(e.frames_with_pose) + " / " + std::to_string(e.gt_frames) : "")
                << " | " << Fmt(e.camera_position_mm.mean) << " / " << Fmt(e.camera_position_mm.max) << " | "
                << Fmt(r.report.total_seconds, 2) << " |" << std::endl;
    }
  }
  std::cout << "\n";
}

void TimeTable(const std::string& root, const std::vector<int>& frames, int threads) {
  std::cout
      << "## Several rigid bodies: mapping time against frames x bodies (threads " << threads
      << "; the mapper's own total, report.json)\n\n"
      << "| frames | bodies | frames x bodies | observations | mapping (s) | ms per 1000 observations | "
         "ms per frame x body |\n|---:|---|---:|---:|---:|---:|---:|\n";
  for (int f : frames) {
    const std::string dir = root + "/time_" + std::to_string(f);
    const Session s = Generate(dir, f);
    const mcmt::MapperOptions with_floor = RigOptions(s, "rig.yaml", threads);
    struct Case {
      std::string name;
      int bodies;
      mcmt::MapperOptions options;
    };
    const std::vector<Case> cases = {{"tool", 1, Alone(with_floor, "tool")},
                                     {"tool + patient", 2, RigOptions(s, "rig_moving.yaml", threads)},
                                     {"tool + patient + floor", 3, with_floor}};
    for (const Case& c : cases) {
      try {
        const mcmt::MapResult r = Map(s, c.options);
        const double seconds = r.report.total_seconds;
        std::cout << "| " << f << " | " << c.name << " | " << f * c.bodies << " | "
                  << r.report.observations_used << " | " << Fmt(seconds, 3) << " | "
                  << Fmt(1e6 * seconds / std::max(1, r.report.observations_used), 3) << " | "
                  << Fmt(1e3 * seconds / (f * c.bodies), 3) << " |" << std::endl;
      } catch (const std::exception& e) {
        std::cout << "| " << f << " | " << c.name << " | | " << e.what() << " | | | |\n";
      }
    }
    fs::remove_all(dir);
  }
  std::cout << "\n";
}

std::vector<int> ParseList(const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stoi(item));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  std::vector<int> frames = {150, 300, 600, 1200};
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      quick = true;
    } else if (a == "--frames" && i + 1 < argc) {
      frames = ParseList(argv[++i]);
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::stoi(argv[++i]);
    } else {
      std::cerr << "usage: bench_bodies [--quick] [--frames 150,300,600,1200] [--threads N]\n";
      return a == "--help" ? 0 : 2;
    }
  }
  if (quick) frames = {150, 300};
  const std::string root =
      (fs::temp_directory_path() / ("mcmt_bench_bodies_" + std::to_string(::getpid()))).string();
  fs::create_directories(root);
  try {
    const Session s = Generate(root + "/accuracy", 300);
    AccuracyTable(s, threads);
    TimeTable(root, frames, threads);
  } catch (const std::exception& e) {
    std::cerr << "bench_bodies: " << e.what() << "\n";
    fs::remove_all(root);
    return 1;
  }
  fs::remove_all(root);
  return 0;
}
