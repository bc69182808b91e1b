// mcmt-eval: accuracy of a map (and trajectory) against mcmt-sim's ground truth, as the paper measures.
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "core/cli.h"
#include "core/files.h"
#include "sim/eval.h"
#include "sim/peer_calibration.h"

namespace {

int Main(int argc, char** argv) {
  using namespace mcmt;
  std::string ground_truth, caliscope, map_path, trajectory_path, object;
  bool json = false;
  ArgParser args(
      "mcmt-eval",
      "Compares the mapper's map.yaml (cameras, marker layout) and optionally a trajectory with "
      "mcmt-sim's ground_truth.yaml after rigid (Horn/Umeyama, no scale) alignments: camera centres "
      "for the rig, marker corners for the object; object poses are compared through both alignments. "
      "With --caliscope instead, compares the map's cameras with a caliscope calibration of the same rig.");
  args.AddString("ground-truth", &ground_truth, "ground_truth.yaml written by mcmt-sim");
  args.AddString("caliscope", &caliscope,
                 "caliscope's camera_array.toml: report the map's agreement with it (camera centres aligned "
                 "rigidly; position and rotation differences per camera) instead of ground-truth errors");
  args.AddString("map", &map_path, "map.yaml written by mcmt-mapper", true);
  args.AddString(
      "trajectory", &trajectory_path,
      "trajectory.csv / poses.csv, or an LCM log with object_pose_t on MCMT_POSE; a map with several "
      "bodies: the mapper's OUTDIR (trajectory_<body>.csv), the tracker's --out PATH (PATH_<body>.csv) or a "
      "log with MCMT_POSE_<BODY>");
  args.AddString(
      "object", &object,
      "a map with several bodies (version 2): evaluate only this body, against its own ground truth "
      "(mcmt-sim --scene bodies writes ground_truth_<body>.yaml); without it every body is "
      "evaluated (cameras once, then each body's layout and poses); a static body's one pose is "
      "compared in every ground-truth frame");
  args.AddFlag("json", &json, "print the figures as JSON instead of a table");
  args.AddEpilog(
      "\nFigures: object rotation (deg) and translation (mm) errors per frame, camera position (mm) and "
      "rotation (deg) errors, object configuration error (mm, mean marker-corner distance), each with "
      "mean / median / max; fraction of frames with a pose. Exit 1 with a one-line reason when the inputs "
      "do not match (camera names, marker ids, frame seqs).\n"
      "example:\n  mcmt-eval --ground-truth sim/ground_truth.yaml --map out/map.yaml --trajectory "
      "out/poses.csv\n"
      "  mcmt-eval --ground-truth sim/ground_truth.yaml --map out/map.yaml --trajectory out/   (several "
      "bodies)\n"
      "  mcmt-eval --caliscope data/camera_array.toml --map out/map.yaml\n");
  int exit_code = 0;
  if (!args.Parse(argc, argv, &exit_code)) return exit_code;
  if (ground_truth.empty() == caliscope.empty()) {
    throw std::invalid_argument("give exactly one of --ground-truth and --caliscope");
  }
  if (!caliscope.empty()) {
    if (!trajectory_path.empty()) throw std::invalid_argument("--trajectory needs --ground-truth");
    const sim::PeerAgreement agreement =
        sim::CompareWithPeer(ReadMap(map_path), sim::ReadCaliscopeCameras(caliscope));
    if (json) {
      std::cout << sim::FormatPeerAgreementJson(agreement);
    } else {
      std::cout << "mcmt-eval: " << map_path << " vs caliscope " << caliscope << "\n\n"
                << sim::FormatPeerAgreement(agreement);
    }
    return 0;
  }
  const RigMap full = ReadMap(map_path);
  if (!full.objects.empty() && object.empty()) {  // several bodies: every body against its own truth
    std::map<std::string, std::vector<TrajectoryRow>> trajectories;
    if (!trajectory_path.empty()) trajectories = sim::ReadBodyTrajectories(trajectory_path, full);
    const std::vector<sim::BodyResult> bodies = sim::EvaluateBodies(
        sim::ReadBodyTruths(ground_truth, full), full, trajectory_path.empty() ? nullptr : &trajectories);
    if (json) {
      std::cout << sim::FormatBodiesJson(bodies);
    } else {
      std::cout << "mcmt-eval: " << map_path << (trajectory_path.empty() ? "" : " + " + trajectory_path)
                << " vs " << ground_truth << " (every body: ground_truth_<body>.yaml)\n\n"
                << sim::FormatBodiesTable(bodies);
    }
    return 0;
  }
  const sim::GroundTruth truth = sim::ReadGroundTruth(ground_truth);
  std::vector<TrajectoryRow> trajectory;
  if (!trajectory_path.empty()) trajectory = sim::ReadTrajectoryAny(trajectory_path);
  const RigMap map = sim::SelectObject(full, object, truth, &trajectory);
  const bool with_poses = !trajectory_path.empty() || !trajectory.empty();
  const sim::EvalResult result = sim::Evaluate(truth, &map, with_poses ? &trajectory : nullptr);
  if (json) {
    std::cout << sim::FormatJson(result);
  } else {
    std::cout << "mcmt-eval: " << map_path << (trajectory_path.empty() ? "" : " + " + trajectory_path)
              << " vs " << ground_truth << "\n\n"
              << sim::FormatTable(result);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-eval", [&]() { return Main(argc, argv); });
}
