// Mapping time and peak memory of mcmt-mapper against frames and cameras, from detections-only logs,
// and accuracy at the paper's radii. Each mapping runs as its own process (`mcmt-mapper --log`), so the
// peak RSS is that process's (wait4 rusage) and the time includes reading the log.
//
//   bench_mapper [--quick] [--frames 300,1000,3000,10000] [--cameras 3,5,8] [--object four_sided]
//                [--threads N] [--no-accuracy]
//                [--rendered [--rendered-frames 100]]   (accuracy from rendered images, needs sim + detector)
//
// The peak memory of a long session (issue 15's mapmem, 2026-12-07): an 8-camera board session, about 31
// observations a frame, `bench_mapper --object board --cameras 8 --frames 1000,3000,10000 --no-accuracy`.
//
// Logs come from `mcmt-sim --detections-only`.
// Prints markdown tables.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/files.h"
#ifdef MCMT_HAVE_SIM
#include "sim/eval.h"
#include "sim/sim.h"
#endif
#ifdef MCMT_HAVE_DETECTOR
#include "core/config.h"
#include "detector/detector.h"
#include "mapper/mapper.h"
#endif

namespace fs = std::filesystem;

namespace {

const std::string kBin = MCMT_BIN_DIR;

struct ProcessResult {
  int code = -1;
  double seconds = 0.0;
  double peak_mib = 0.0;
};

ProcessResult RunProcess(const std::vector<std::string>& args, const std::string& output_path) {
  ProcessResult r;
  const auto start = std::chrono::steady_clock::now();
  std::cout.flush();
  std::cerr.flush();
  const pid_t pid = fork();
  if (pid == 0) {
    FILE* out = freopen(output_path.c_str(), "w", stdout);
    if (out) dup2(fileno(stdout), 2);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  struct rusage usage = {};
  wait4(pid, &status, 0, &usage);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.peak_mib = usage.ru_maxrss / 1024.0;
  return r;
}

std::vector<int> ParseList(const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stoi(item));
  return out;
}

// A number after "key": in report.json.
double JsonValue(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\":");
  if (at == std::string::npos) return NAN;
  return std::atof(json.c_str() + at + key.size() + 3);
}

// Writes DIR/rig.yaml, DIR/ground_truth.yaml and DIR/detections.lcmlog with mcmt-sim; returns the log.
// Exits with a one-line reason when mcmt-sim fails.
std::string MakeLog(const std::string& dir, int frames, int cameras, double radius,
                    const std::string& object) {
  fs::create_directories(dir);
  const std::string sim = kBin + "/mcmt-sim";
  const ProcessResult r = RunProcess(
      {sim, "--out", dir, "--detections-only", "--object", object, "--cameras", std::to_string(cameras),
       "--frames", std::to_string(frames), "--radius", std::to_string(radius), "--seed", "1"},
      dir + "/sim.out");
  if (r.code != 0 || !fs::exists(dir + "/detections.lcmlog")) {
    std::cerr << "bench_mapper: error: " << sim << " failed (exit " << r.code << ", see " << dir
              << "/sim.out)\n";
    std::exit(1);
  }
  return dir + "/detections.lcmlog";
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> frames_list = {300, 1000, 3000, 10000}, cameras_list = {3, 5, 8};
  bool accuracy = true, rendered = false;
  int rendered_frames = 100;
  std::string threads = "0", object = "four_sided";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      frames_list = {300, 1000};
      cameras_list = {3, 5};
    } else if (a == "--frames" && i + 1 < argc) {
      frames_list = ParseList(argv[++i]);
    } else if (a == "--cameras" && i + 1 < argc) {
      cameras_list = ParseList(argv[++i]);
    } else if (a == "--object" && i + 1 < argc) {
      object = argv[++i];
    } else if (a == "--threads" && i + 1 < argc) {
      threads = argv[++i];
    } else if (a == "--rendered") {
      rendered = true;
    } else if (a == "--rendered-frames" && i + 1 < argc) {
      rendered_frames = std::stoi(argv[++i]);
    } else if (a == "--no-accuracy") {
      accuracy = false;
    } else {
      std::cerr
          << "usage: bench_mapper [--quick] [--frames LIST] [--cameras LIST] [--object NAME] [--threads N] "
             "[--no-accuracy] [--rendered [--rendered-frames N]]\n";
      return a == "--help" ? 0 : 2;
    }
  }
  const std::string mapper = kBin + "/mcmt-mapper";
  if (!fs::exists(mapper)) {
    std::cerr << "bench_mapper: build mcmt-mapper first (" << mapper << ")\n";
    return 1;
  }
  const std::string root =
      (fs::temp_directory_path() / ("mcmt_bench_mapper_" + std::to_string(getpid()))).string();
  std::cout << "## mcmt-mapper: time and peak memory (" << std::thread::hardware_concurrency()
            << " cores, --threads " << threads << ")\n\n";
  std::cout << "| frames | cameras | observations | process wall (s) | mapping (s) | init (s) | refine (s) | "
               "iterations | peak RSS (MiB) | final rms (px) |\n";
  std::cout << "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (int cameras : cameras_list) {
    for (int frames : frames_list) {
      const std::string dir = root + "/f" + std::to_string(frames) + "_c" + std::to_string(cameras);
      const std::string log = MakeLog(dir, frames, cameras, 1.0, object);
      const ProcessResult r = RunProcess(
          {mapper, "--config", dir + "/rig.yaml", "--log", log, "--out", dir + "/out", "--threads", threads},
          dir + "/mapper.out");
      std::string report;
      try {
        report = mcmt::ReadFile(dir + "/out/report.json");
      } catch (...) {
      }
      const double total = JsonValue(report, "total");
      const double refine = JsonValue(report, "refine");
      std::cout << "| " << frames << " | " << cameras << " | "
                << static_cast<long>(JsonValue(report, "observations_used")) << " | " << std::fixed
                << std::setprecision(3) << r.seconds << " | " << total << " | " << total - refine << " | "
                << refine << " | " << std::setprecision(0) << JsonValue(report, "iterations") << " | "
                << std::setprecision(1) << r.peak_mib << " | " << std::setprecision(3)
                << JsonValue(report, "final_rms_px") << (r.code == 0 ? "" : " (FAILED)") << " |" << std::endl;
      fs::remove_all(dir);
    }
  }
  std::cout
      << "\nlogs: "
      << "mcmt-sim --detections-only --object " << object
      << ", corner noise 0.1 px; mapping = the mapper's own total (report.json), init = everything before "
         "the bundle adjustment.\n";

#ifdef MCMT_HAVE_SIM
  if (accuracy && fs::exists(kBin + "/mcmt-sim")) {
    std::cout
        << "\n## mcmt-mapper accuracy at the paper's radii (mcmt-sim detections-only, 5 cameras, 300 frames, "
           "0.1 px corner noise; sim::Evaluate after rigid alignment, means)\n\n";
    std::cout
        << "| object | radius (m) | object rotation (deg) | object translation (mm) | camera position (mm) | "
           "configuration (mm) | rms (px) | time (s) |\n|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const char* object : {"four_sided", "box", "pentagon"}) {
      for (double radius : {0.7, 0.9, 1.1, 1.3}) {
        std::ostringstream name;
        name << root << "/acc_" << object << "_" << radius;
        const std::string dir = name.str();
        fs::create_directories(dir);
        RunProcess({kBin + "/mcmt-sim", "--out", dir, "--detections-only", "--object", object, "--cameras",
                    "5", "--frames", "300", "--radius", std::to_string(radius), "--seed", "2"},
                   dir + "/sim.out");
        const ProcessResult m = RunProcess({mapper, "--config", dir + "/rig.yaml", "--log",
                                            dir + "/detections.lcmlog", "--out", dir + "/out"},
                                           dir + "/mapper.out");
        std::cout << "| " << object << " | " << radius << " | " << std::fixed << std::setprecision(3);
        try {
          if (m.code != 0) throw std::runtime_error("mapping failed");
          const mcmt::sim::GroundTruth truth = mcmt::sim::ReadGroundTruth(dir + "/ground_truth.yaml");
          const mcmt::RigMap map = mcmt::ReadMap(dir + "/out/map.yaml");
          const std::vector<mcmt::TrajectoryRow> trajectory =
              mcmt::ReadTrajectory(dir + "/out/trajectory.csv");
          const mcmt::sim::EvalResult e = mcmt::sim::Evaluate(truth, &map, &trajectory);
          std::cout << e.object_rotation_deg.mean << " | " << e.object_translation_aligned_mm.mean << " | "
                    << e.camera_position_mm.mean << " | " << e.configuration_mm.mean << " | " << map.rms_px
                    << " | " << m.seconds << " |" << std::endl;
        } catch (const std::exception& ex) {
          std::cout << ex.what() << " | | | | | |" << std::endl;
        }
        fs::remove_all(dir);
      }
    }
  }
#else
  (void)accuracy;
#endif
#if defined(MCMT_HAVE_SIM) && defined(MCMT_HAVE_DETECTOR)
  if (rendered) {
    std::cout
        << "\n## Accuracy from rendered images (mcmt-sim renderer -> DetectRecording -> Mapper; 5 cameras, "
        << rendered_frames << " frames; sim::Evaluate means)\n\n";
    std::cout
        << "| object | radius (m) | object rotation (deg) | object translation (mm) | camera position (mm) | "
           "configuration (mm) | rms (px) | mapping (s) |\n|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const char* object : {"four_sided", "box", "pentagon"}) {
      for (double radius : {0.7, 0.9, 1.1, 1.3}) {
        std::ostringstream name;
        name << root << "/render_" << object << "_" << radius;
        mcmt::sim::DatasetOptions options;
        options.out_dir = name.str();
        options.object.kind = mcmt::sim::ObjectKindFromName(object);
        if (options.object.kind == mcmt::sim::ObjectKind::kPentagon) options.object.marker_size = 0.025;
        options.rig.num_cameras = 5;
        options.rig.radius = radius;
        options.trajectory.frames = rendered_frames;
        options.threads = 2;
        std::cout << "| " << object << " | " << std::setprecision(1) << radius << " | "
                  << std::setprecision(3);
        try {
          const mcmt::sim::DatasetSummary summary = mcmt::sim::GenerateDataset(options);
          const mcmt::RigConfig rig = mcmt::LoadRigConfig(options.out_dir + "/rig.yaml");
          mcmt::Mapper mapper(mcmt::MapperOptions::FromConfig(rig));
          for (const mcmt::CameraConfig& c : rig.cameras)
            for (const mcmt::detections_t& d : mcmt::DetectRecording(rig, c.name)) mapper.Add(d);
          const mcmt::MapResult result = mapper.Solve();
          const mcmt::sim::EvalResult e = mcmt::sim::Evaluate(summary.truth, &result.map, &result.trajectory);
          std::cout << e.object_rotation_deg.mean << " | " << e.object_translation_aligned_mm.mean << " | "
                    << e.camera_position_mm.mean << " | " << e.configuration_mm.mean << " | "
                    << result.map.rms_px << " | " << result.report.total_seconds << " |" << std::endl;
        } catch (const std::exception& ex) {
          std::cout << ex.what() << " | | | | | |" << std::endl;
        }
        fs::remove_all(options.out_dir);
      }
    }
  }
#else
  (void)rendered_frames;
  if (rendered) std::cerr << "bench_mapper: --rendered needs the sim and detector components\n";
#endif
  fs::remove_all(root);
  return 0;
}
