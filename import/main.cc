// mcmt-import: foreign detections (ROS bags of AprilTag detections, mcmt's det.csv) -> a session folder
// for mcmt-mapper and mcmt-tracker.
#include <iostream>

#include "core/cli.h"
#include "import/import.h"

namespace {

int Run(int argc, char** argv) {
  std::string rosbag, cameras, csv, config, out, tagslam, dictionary;
  double tag_size = 0.0;
  mcmt::ArgParser args("mcmt-import",
                       "Turns foreign marker detections into an mcmt session: OUT/session.lcmlog "
                       "(detections_t on MCMT_DETECTIONS_<CAMERA>) and OUT/rig.yaml with intrinsics.");
  args.AddString("rosbag", &rosbag,
                 "ROS 1 bag (.bag or .bag.bz2) of apriltag_msgs/ApriltagArrayStamped, one topic per camera");
  args.AddString("cameras", &cameras,
                 "--rosbag: Kalibr / TagSLAM cameras.yaml (pinhole, radtan|equidistant)");
  args.AddDouble("tag-size", &tag_size,
                 "--rosbag: tag side length in metres (default: default_tag_size of tagslam.yaml)");
  args.AddString("tagslam", &tagslam,
                 "--rosbag: TagSLAM tagslam.yaml giving tag sizes (default: the one beside cameras.yaml)");
  args.AddString("dictionary", &dictionary,
                 "--rosbag: mcmt dictionary name (default: from the messages' tag family)");
  args.AddString("csv", &csv, "mcmt det.csv (utime,seq,camera,id,x0,y0,...,x3,y3; ArUco corner order)");
  args.AddString("config", &config, "--csv: the rig YAML the detections belong to");
  args.AddString("out", &out, "session folder to create (never overwritten)", true);
  args.AddEpilog(
      "examples:\n"
      "  mcmt-import --rosbag tag_detections.bag --cameras cameras.yaml --tag-size 0.16 --out session/\n"
      "  mcmt-import --csv det.csv --config rig.yaml --out session/\n"
      "  mcmt-mapper --config session/rig.yaml --log session/session.lcmlog --out session/map\n");
  int code = 0;
  if (!args.Parse(argc, argv, &code)) return code;
  if (rosbag.empty() == csv.empty()) {
    std::cerr << "mcmt-import: error: give exactly one of --rosbag or --csv\n";
    return 2;
  }
  mcmt::ImportSummary summary;
  if (!rosbag.empty()) {
    if (cameras.empty()) {
      std::cerr << "mcmt-import: error: --rosbag needs --cameras cameras.yaml\n";
      return 2;
    }
    if (args.Given("tag-size") && !(tag_size > 0)) {
      std::cerr << "mcmt-import: error: --tag-size: expected a positive length in metres\n";
      return 2;
    }
    summary = mcmt::ImportRosbag({rosbag, cameras, out, tag_size, tagslam, dictionary});
  } else {
    if (config.empty()) {
      std::cerr << "mcmt-import: error: --csv needs --config rig.yaml\n";
      return 2;
    }
    summary = mcmt::ImportCsv(csv, config, out);
  }
  std::cout << mcmt::FormatImportSummary(summary);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-import", [&] { return Run(argc, argv); });
}
