// mcmt-export: logs -> detections CSV, poses CSV/TUM, summary; trajectory CSV -> poses CSV/TUM; maps ->
// every format of core/map_export.h's table; detections CSV -> log. Writes every output it can; an output
// that cannot be written (e.g. a camera model its format cannot express) is refused with a one-line reason,
// the others are still written, and the exit code is 1.
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "core/cli.h"
#include "core/config.h"
#include "core/files.h"
#include "core/map_export.h"
#include "logger/export.h"

namespace {

struct Request {
  std::string log, trajectory, det_csv, poses_csv, tum, map_path, csv_to_log, out, config;
  bool summary = false;
  mcmt::MapExportOptions map_options;
  std::vector<std::string> map_paths;  // one per mcmt::MapExportFormats() row, "" when not asked
};

// "--kalibr, --ros-dir, ..." from the format table.
std::string MapOptionNames(const std::string& separator) {
  std::string names;
  for (const mcmt::MapExportFormat& f : mcmt::MapExportFormats())
    names += (names.empty() ? "--" : separator + "--") + f.option;
  return names;
}

// Runs one output's writer. On failure prints "mcmt-export: error: WHAT: not written: REASON" (one line)
// and returns false; the other outputs go on.
bool Attempt(const std::string& what, const std::function<void()>& write) {
  try {
    write();
    return true;
  } catch (const std::exception& e) {
    std::string reason = e.what();
    for (char& c : reason)
      if (c == '\n') c = ' ';
    std::cerr << "mcmt-export: error: " << what << ": not written: " << reason << std::endl;
    return false;
  }
}

void CheckRequest(const Request& r) {
  bool map_action = false;
  for (const std::string& p : r.map_paths) map_action = map_action || !p.empty();
  const bool pose_action = !r.poses_csv.empty() || !r.tum.empty();
  const bool log_action = r.summary || !r.det_csv.empty() || pose_action;
  const std::string map_names = MapOptionNames(", ");
  if (!r.log.empty() && !log_action)
    throw std::invalid_argument("--log: say what to export (--summary, --detections, --poses, --tum)");
  if (!r.trajectory.empty() && !pose_action)
    throw std::invalid_argument("--trajectory: say what to export (--poses, --tum)");
  if (!r.map_path.empty() && !map_action)
    throw std::invalid_argument("--map: say what to export (" + map_names + ")");
  if (!log_action && !map_action && r.csv_to_log.empty())
    throw std::invalid_argument(
        "nothing to do: give --summary, --detections, --poses, --tum (with --log), "
        "--poses, --tum (with --trajectory), " +
        map_names + " (with --map) or --detections-to-log");
  if (!r.trajectory.empty() && !r.log.empty())
    throw std::invalid_argument("give --log or --trajectory, not both");
  if (!r.trajectory.empty() && (r.summary || !r.det_csv.empty()))
    throw std::invalid_argument("--summary/--detections need --log (a trajectory CSV holds poses only)");
  if ((r.summary || !r.det_csv.empty()) && r.log.empty())
    throw std::invalid_argument("--summary/--detections need --log");
  if (pose_action && r.log.empty() && r.trajectory.empty())
    throw std::invalid_argument("--poses/--tum need --log or --trajectory");
  if (map_action && r.map_path.empty()) throw std::invalid_argument(MapOptionNames("/") + " need --map");
  if (!r.csv_to_log.empty() && (r.out.empty() || r.config.empty()))
    throw std::invalid_argument("--detections-to-log needs --out LOG and --config rig.yaml");
}

// --detections, --poses, --tum from the log or the trajectory CSV; notes why a file came out empty.
bool ExportPosesAndDetections(const Request& r) {
  if (r.det_csv.empty() && r.poses_csv.empty() && r.tum.empty()) return true;
  mcmt::LogExportRequest request;
  request.detections_csv = r.det_csv;
  request.poses_csv = r.poses_csv;
  request.tum = r.tum;
  const bool from_trajectory = !r.trajectory.empty();
  const std::string source = from_trajectory ? r.trajectory : r.log;
  mcmt::LogExportResult result;
  const std::string what = r.det_csv.empty()                        ? "--poses/--tum"
                           : (r.poses_csv.empty() && r.tum.empty()) ? "--detections"
                                                                    : "--detections/--poses/--tum";
  if (!Attempt(what + " from " + source, [&] {
        result = from_trajectory ? mcmt::ExportFromTrajectory(source, request)
                                 : mcmt::ExportFromLog(source, request);
      }))
    return false;
  if (!r.det_csv.empty()) {
    std::cerr << "mcmt-export: " << r.det_csv << ": " << result.detection_rows << " markers from "
              << result.detection_messages << " detections_t\n";
    const std::string why = mcmt::WhyDetectionsEmpty(source, result);
    if (!why.empty()) std::cerr << "mcmt-export: " << r.det_csv << " is empty: " << why << "\n";
  }
  if (!r.poses_csv.empty() || !r.tum.empty()) {
    for (const mcmt::PoseExport& s : result.streams) {
      if (s.body.empty()) continue;
      std::cerr << "mcmt-export: body " << s.body << " (" << s.source << "): " << s.rows << " poses";
      if (!from_trajectory) std::cerr << " (" << s.skipped << " lost skipped)";
      std::cerr << " -> " << s.poses_csv << (s.poses_csv.empty() || s.tum.empty() ? "" : ", ") << s.tum
                << "\n";
    }
    std::cerr << "mcmt-export: " << result.pose_rows << " poses";
    if (!from_trajectory) std::cerr << " (" << result.poses_skipped << " lost skipped)";
    std::cerr << "\n";
    const std::string why = mcmt::WhyPosesEmpty(source, from_trajectory, result, request.pose_channel);
    if (!why.empty())
      std::cerr << "mcmt-export: " << (r.poses_csv.empty() ? r.tum : r.poses_csv) << " is empty: " << why
                << "\n";
  }
  return true;
}

// Every asked map format, each on its own: one refused does not stop the others.
bool ExportMap(const Request& r) {
  if (r.map_path.empty()) return true;
  mcmt::RigMap map;
  if (!Attempt("--map " + r.map_path, [&] { map = mcmt::ReadMapOrLog(r.map_path); })) return false;
  bool ok = true;
  const std::vector<mcmt::MapExportFormat>& formats = mcmt::MapExportFormats();
  for (size_t i = 0; i < formats.size(); ++i) {
    if (r.map_paths[i].empty()) continue;
    ok = Attempt("--" + formats[i].option + " " + r.map_paths[i],
                 [&] { formats[i].write(map, r.map_paths[i], r.map_options); }) &&
         ok;
  }
  return ok;
}

void AddOptions(mcmt::ArgParser* args, Request* r) {
  args->AddString("log", &r->log,
                  "LCM log to read (a split recording: NAME.lcmlog reads NAME.00.lcmlog, ...)");
  args->AddString(
      "trajectory", &r->trajectory,
      "trajectory.csv or poses.csv to read instead of --log, for --poses and --tum; or the mapper's "
      "OUTDIR (several bodies: its trajectory_<body>.csv, one output file per body)");
  args->AddString("detections", &r->det_csv,
                  "from --log: detections CSV (utime,seq,camera,id,x0,y0,...,x3,y3)");
  args->AddString(
      "poses", &r->poses_csv,
      "from --log (MCMT_POSE) or --trajectory: poses CSV (trajectory.csv format); poses of several "
      "bodies (MCMT_POSE_<BODY>) go to PATH_<body>.csv, one file per body");
  args->AddString("tum", &r->tum,
                  "from --log or --trajectory: poses in TUM format (timestamp tx ty tz qx qy qz qw); several "
                  "bodies: PATH_<body>.tum per body");
  args->AddFlag("summary", &r->summary,
                "from --log: print channels, counts, rates, span, cameras, ids, seq gaps");
  args->AddString("map", &r->map_path,
                  "map.yaml to read, or a log: its last map on MCMT_MAP (rig_map2_t or rig_map_t)");
  const std::vector<mcmt::MapExportFormat>& formats = mcmt::MapExportFormats();
  r->map_paths.resize(formats.size());
  for (size_t i = 0; i < formats.size(); ++i)
    args->AddString(formats[i].option, &r->map_paths[i], "from --map: " + formats[i].help);
  args->AddString("ros-rig-frame", &r->map_options.rig_frame, "--ros-dir: name of the rig frame");
  args->AddString("ros-object-frame", &r->map_options.object_frame, "--ros-dir: name of the object frame");
  args->AddString("detections-to-log", &r->csv_to_log,
                  "detections CSV to turn back into a log (needs --out, --config)");
  args->AddString("out", &r->out, "--detections-to-log: log to create (never overwritten)");
  args->AddString("config", &r->config, "--detections-to-log: rig YAML giving camera models and dictionary");
  args->AddEpilog(
      "Every output that can be written is written; one that cannot (e.g. --kalibr for a camera whose model\n"
      "Kalibr cannot express) is refused with its reason, and the exit code is then 1.\n"
      "examples:\n"
      "  mcmt-export --summary session.lcmlog\n"
      "  mcmt-export --log session.lcmlog --detections det.csv --poses poses.csv --tum poses.tum\n"
      "  mcmt-export --trajectory map/trajectory.csv --tum trajectory.tum\n"
      "  mcmt-export --trajectory map/ --tum poses.tum --ply layout.ply --map map/map.yaml   (several "
      "bodies: "
      "poses_<body>.tum, layout_<body>.ply)\n"
      "  mcmt-export --map out/map.yaml --kalibr camchain.yaml --ros-dir ros/ --opencv map.yml --ply "
      "object.ply\n"
      "  mcmt-export --detections-to-log det.csv --out det.lcmlog --config rig.yaml\n");
}

int Run(int argc, char** argv) {
  Request r;
  mcmt::ArgParser args(
      "mcmt-export",
      "Exports mcmt logs, trajectories and maps to other formats, and detections CSV to a log.");
  AddOptions(&args, &r);
  int code = 0;
  if (!args.Parse(argc, argv, &code)) return code;
  if (!r.log.empty() && r.trajectory.empty() && !r.summary && r.det_csv.empty() &&
      mcmt::IsTrajectoryCsv(r.log)) {
    std::cerr << "mcmt-export: " << r.log << " is a trajectory CSV: read as --trajectory\n";
    std::swap(r.log, r.trajectory);
  }
  CheckRequest(r);
  bool ok = true;
  if (r.summary)
    ok = Attempt("--summary",
                 [&] { std::cout << mcmt::FormatSummary(mcmt::SummarizeLog(r.log)) << std::flush; }) &&
         ok;
  ok = ExportPosesAndDetections(r) && ok;
  ok = ExportMap(r) && ok;
  if (!r.csv_to_log.empty())
    ok = Attempt("--detections-to-log " + r.csv_to_log,
                 [&] {
                   const mcmt::CsvToLogResult c =
                       mcmt::DetectionsCsvToLog(r.csv_to_log, mcmt::LoadRigConfig(r.config), r.out);
                   std::cerr << "mcmt-export: " << r.out << ": " << c.messages << " detections_t from "
                             << c.rows << " rows\n";
                 }) &&
         ok;
  return ok ? 0 : 1;
}

}  // namespace

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
  return mcmt::RunMain("mcmt-export",
                       [&] { return Run(static_cast<int>(new_argv.size()), new_argv.data()); });
}
