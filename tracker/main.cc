// mcmt-tracker: publishes the object's pose (object_pose_t on MCMT_POSE) from the detections of the
// mapped cameras, live or from a log.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "core/cli.h"
#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/options.h"
#include "tracker/tracker.h"

namespace {

std::string StreamChannels(const std::vector<mcmt::PoseStream>& streams) {
  std::string out;
  for (size_t k = 0; k < streams.size(); ++k) out += (k ? ", " : "") + streams[k].channel;
  return out;
}

int Main(int argc, char** argv) {
  std::string config, map_path, log_path, out_path, lcm_url, channel;
  bool quiet = false;
  double deadline_ms = 15.0, max_wait_ms = 100.0;
  mcmt::ArgParser args(
      "mcmt-tracker",
      "Tracks the object with a known map: one object_pose_t per frame on MCMT_POSE (rig_from_object,\n"
      "covariance, RMS error, cameras and markers used, status, latency). With several bodies (a map\n"
      "with objects:), one per moving body on MCMT_POSE_<NAME>, and the relative poses of\n"
      "tracker.relative on MCMT_POSE_<OF>_IN_<IN>.");
  args.AddString("config", &config, "rig YAML (cameras, markers, optional tracker: section)", true);
  args.AddString("map", &map_path,
                 "map.yaml from mcmt-mapper; without it: wait for MCMT_MAP; live, newer maps on MCMT_MAP "
                 "replace either (mcmt-mapper --maintain)");
  args.AddString("log", &log_path, "process this LCM log as fast as possible instead of live traffic");
  args.AddString(
      "out", &out_path,
      "write the trajectory (trajectory.csv format) here on exit, atomically; with several bodies one "
      "file per pose stream, OUT's name + _NAME (poses_tool.csv, poses_tool_in_patient.csv); while "
      "running, every pose is appended to OUT.partial at once (what survives a crash), removed at a "
      "clean exit");
  args.AddString(
      "lcm-url", &lcm_url,
      "LCM URL (default: lcm.url of the rig YAML, else LCM's default); with --log: publish poses there, "
      "as fast as the log is read (slow receivers over udpm may drop some)");
  args.AddString("channel", &channel,
                 "output channel (default: tracker.channel, else MCMT_POSE); with several bodies the "
                 "prefix of their channels");
  args.AddDouble("deadline-ms", &deadline_ms,
                 "frame deadline: wait this long after a frame's first detection for the other cameras "
                 "(overrides tracker.deadline_ms; raise it when cameras' messages lag each other)");
  args.AddDouble("max-wait-ms", &max_wait_ms,
                 "live: longest wait for a camera whose messages lag (measured per camera) after a frame's "
                 "first detection (overrides tracker.max_wait_ms; 0: only the deadline)");
  args.AddFlag("quiet", &quiet, "no status lines (warnings are still printed)");
  args.AddEpilog(
      "\nexamples:\n"
      "  mcmt-tracker --config rig.yaml --map out/map.yaml\n"
      "  mcmt-tracker --config rig.yaml --map out/map.yaml --log session.lcmlog --out poses.csv\n"
      "  mcmt-tracker --config rig.yaml --lcm-url 'udpm://239.255.76.67:7667?ttl=1'   # waits for "
      "MCMT_MAP\n");
  args.SetConfigHelp("### tracker\n\n" + mcmt::TrackerOptionTable().Markdown() + "\n### sync\n\n" +
                     mcmt::SyncOptionTable().Markdown());
  int exit_code = 0;
  if (!args.Parse(argc, argv, &exit_code)) return exit_code;

  const mcmt::RigConfig rig = mcmt::LoadRigConfig(config);
  mcmt::TrackerNodeOptions options;
  options.tracker = mcmt::TrackerOptions::FromConfig(rig);
  if (args.Given("channel")) options.tracker.channel = channel;
  if (args.Given("deadline-ms")) options.tracker.deadline_ms = deadline_ms;
  if (args.Given("max-wait-ms")) options.tracker.max_wait_ms = max_wait_ms;
  options.tracker.Validate();
  options.log_mode = !log_path.empty();
  options.keep_trajectory = !out_path.empty();
  if (!out_path.empty()) options.partial_path = out_path + ".partial";
  options.quiet = quiet;

  std::optional<mcmt::RigMap> map;
  if (!map_path.empty()) map = mcmt::ReadMap(map_path);
  if (map) mcmt::CheckMapMatchesRig(*map, rig, map_path);

  const std::string live_url = args.Given("lcm-url") ? lcm_url : rig.lcm_url;
  std::unique_ptr<lcm::LCM> input, output;
  if (options.log_mode) {
    if (!std::ifstream(log_path, std::ios::binary))
      throw std::runtime_error(log_path + ": cannot open the log");
    input = mcmt::OpenLcm("memq://");  // nothing arrives on it: the log is read by core's reader
    if (args.Given("lcm-url")) output = mcmt::OpenLcm(lcm_url);
  } else {
    input = mcmt::OpenLcm(live_url);
  }
  const mcmt::StopToken stop = mcmt::StopOnSignals();
  mcmt::TrackerNode node(*input, rig, options, map, output.get());
  if (!quiet)  // subscribed from here on (tests wait for this line)
    std::cerr << "mcmt-tracker: ready, " << (map ? "" : "waiting for MCMT_MAP, ") << "poses on "
              << (node.streams().empty() ? options.tracker.channel : StreamChannels(node.streams()))
              << (options.log_mode && !output ? " (not published: --log without --lcm-url)" : "")
              << std::endl;
  mcmt::LogReadReport report;
  if (options.log_mode)
    report = node.RunLog(log_path, stop);
  else
    node.Run(stop);
  if (!out_path.empty()) {
    // One file per pose stream: OUT for a single object, else OUT's name + _NAME (poses_tool.csv); the
    // partial files go only once every final file is written.
    if (node.streams().empty()) mcmt::WriteTrajectory(out_path, {});  // no map came
    for (const mcmt::PoseStream& s : node.streams()) {
      const std::string path = s.single ? out_path : mcmt::BodyPath(out_path, s.name);
      mcmt::WriteTrajectory(path, s.trajectory);
      if (!quiet)
        std::cerr << "mcmt-tracker: wrote " << s.trajectory.size() << " poses to " << path << std::endl;
    }
    std::remove(options.partial_path.c_str());
    for (const mcmt::PoseStream& s : node.streams())
      if (!s.single) std::remove((mcmt::BodyPath(out_path, s.name) + ".partial").c_str());
  }
  if (report.damaged()) {
    std::cerr << "mcmt-tracker: " << report.Summary() << " (exit status " << mcmt::kExitDamagedLog << ")"
              << std::endl;
    return mcmt::kExitDamagedLog;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-tracker", [&] { return Main(argc, argv); });
}
