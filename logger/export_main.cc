// mcmt-export: logs -> detections CSV, poses CSV/TUM, summary; maps -> Kalibr, ROS, OpenCV, PLY, OBJ;
// detections CSV -> log.
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "core/cli.h"
#include "core/config.h"
#include "core/files.h"
#include "logger/export.h"

int main(int argc, char** argv) {
  // "--summary LOG" (the spelling) is "--summary --log LOG".
  std::vector<std::string> words(argv, argv + argc);
  for (size_t i = 1; i + 1 < words.size(); ++i) {
    if (words[i] == "--summary" && words[i + 1].rfind("--", 0) != 0) {
      words.insert(words.begin() + static_cast<long>(i) + 1, "--log");
      break;
    }
  }
  std::vector<char*> new_argv;
  for (std::string& w : words) new_argv.push_back(&w[0]);
  argc = static_cast<int>(new_argv.size());
  argv = new_argv.data();

  return mcmt::RunMain("mcmt-export", [&]() {
    std::string log, det_csv, poses_csv, tum, map_path, kalibr, ros_dir, opencv, ply, obj, csv_to_log, out,
        config;
    std::string rig_frame = "mcmt_rig", object_frame = "mcmt_object";
    bool summary = false;
    mcmt::ArgParser args("mcmt-export",
                         "Exports mcmt logs and maps to other formats, and detections CSV to a log.");
    args.AddString("log", &log, "LCM log to read (a split recording: NAME.lcmlog reads NAME.00.lcmlog, ...)");
    args.AddString("detections", &det_csv,
                   "from --log: detections CSV (utime,seq,camera,id,x0,y0,...,x3,y3)");
    args.AddString("poses", &poses_csv, "from --log: poses CSV (trajectory.csv format) of MCMT_POSE");
    args.AddString("tum", &tum, "from --log: poses in TUM format (timestamp tx ty tz qx qy qz qw)");
    args.AddFlag("summary", &summary,
                 "from --log: print channels, counts, rates, span, cameras, ids, seq gaps");
    args.AddString("map", &map_path, "map.yaml to read, or a log: its last rig_map_t on MCMT_MAP");
    args.AddString("kalibr", &kalibr, "from --map: Kalibr camchain YAML");
    args.AddString("ros-dir", &ros_dir,
                   "from --map: folder of camera_info YAML per camera + static_transforms.yaml/.txt");
    args.AddString("ros-rig-frame", &rig_frame, "--ros-dir: name of the rig frame");
    args.AddString("ros-object-frame", &object_frame, "--ros-dir: name of the object frame");
    args.AddString("opencv", &opencv, "from --map: OpenCV FileStorage YAML");
    args.AddString("ply", &ply, "from --map: the object's marker squares as PLY");
    args.AddString("obj", &obj, "from --map: the object's marker squares as Wavefront OBJ");
    args.AddString("detections-to-log", &csv_to_log,
                   "detections CSV to turn back into a log (needs --out, --config)");
    args.AddString("out", &out, "--detections-to-log: log to create (never overwritten)");
    args.AddString("config", &config, "--detections-to-log: rig YAML giving camera models and dictionary");
    args.AddEpilog(
        "examples:\n"
        "  mcmt-export --summary session.lcmlog\n"
        "  mcmt-export --log session.lcmlog --detections det.csv --poses poses.csv --tum poses.tum\n"
        "  mcmt-export --map out/map.yaml --kalibr camchain.yaml --ros-dir ros/ --opencv map.yml --ply "
        "object.ply\n"
        "  mcmt-export --detections-to-log det.csv --out det.lcmlog --config rig.yaml\n");
    int code = 0;
    if (!args.Parse(argc, argv, &code)) return code;

    const bool log_action = summary || !det_csv.empty() || !poses_csv.empty() || !tum.empty();
    const bool map_action =
        !kalibr.empty() || !ros_dir.empty() || !opencv.empty() || !ply.empty() || !obj.empty();
    if (!log.empty() && !log_action)
      throw std::invalid_argument("--log: say what to export (--summary, --detections, --poses, --tum)");
    if (!map_path.empty() && !map_action)
      throw std::invalid_argument("--map: say what to export (--kalibr, --ros-dir, --opencv, --ply, --obj)");
    if (!log_action && !map_action && csv_to_log.empty())
      throw std::invalid_argument(
          "nothing to do: give --summary, --detections, --poses, --tum (with --log), "
          "--kalibr, --ros-dir, --opencv, --ply, --obj (with --map) or --detections-to-log");
    if (log_action && log.empty())
      throw std::invalid_argument("--summary/--detections/--poses/--tum need --log");
    if (map_action && map_path.empty())
      throw std::invalid_argument("--kalibr/--ros-dir/--opencv/--ply/--obj need --map");
    if (!csv_to_log.empty() && (out.empty() || config.empty()))
      throw std::invalid_argument("--detections-to-log needs --out LOG and --config rig.yaml");

    if (summary) std::cout << mcmt::FormatSummary(mcmt::SummarizeLog(log)) << std::flush;
    if (!det_csv.empty() || !poses_csv.empty() || !tum.empty()) {
      mcmt::LogExportRequest request;
      request.detections_csv = det_csv;
      request.poses_csv = poses_csv;
      request.tum = tum;
      mcmt::LogExportResult r = mcmt::ExportFromLog(log, request);
      if (!det_csv.empty())
        std::cerr << "mcmt-export: " << det_csv << ": " << r.detection_rows << " markers from "
                  << r.detection_messages << " detections_t\n";
      if (!poses_csv.empty() || !tum.empty())
        std::cerr << "mcmt-export: " << r.pose_rows << " poses (" << r.poses_skipped << " lost skipped)\n";
    }
    if (map_action) {
      mcmt::RigMap map = mcmt::ReadMapOrLog(map_path);
      if (!kalibr.empty()) mcmt::WriteFileAtomic(kalibr, mcmt::KalibrCamchain(map));
      if (!ros_dir.empty()) mcmt::WriteRosDir(map, ros_dir, rig_frame, object_frame);
      if (!opencv.empty()) mcmt::WriteFileAtomic(opencv, mcmt::OpenCvMapYaml(map));
      if (!ply.empty()) mcmt::WriteFileAtomic(ply, mcmt::MarkersPly(map));
      if (!obj.empty()) mcmt::WriteFileAtomic(obj, mcmt::MarkersObj(map));
    }
    if (!csv_to_log.empty()) {
      mcmt::RigConfig rig = mcmt::LoadRigConfig(config);
      mcmt::CsvToLogResult r = mcmt::DetectionsCsvToLog(csv_to_log, rig, out);
      std::cerr << "mcmt-export: " << out << ": " << r.messages << " detections_t from " << r.rows
                << " rows\n";
    }
    return 0;
  });
}
