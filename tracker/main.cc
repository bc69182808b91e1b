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

// The command line, as given.
struct Cli {
  std::string config, map_path, log_path, out_path, lcm_url, channel;
  bool quiet = false;
  double deadline_ms = 15.0, max_wait_ms = 100.0;
};

void DeclareOptions(mcmt::ArgParser* args, Cli* c) {
  args->AddString("config", &c->config, "rig YAML (cameras, markers, optional tracker: section)", true);
  args->AddString("map", &c->map_path,
                  "map.yaml from mcmt-mapper; without it: wait for MCMT_MAP; live, newer maps on MCMT_MAP "
                  "replace either (mcmt-mapper --maintain)");
  args->AddString("log", &c->log_path, "process this LCM log as fast as possible instead of live traffic");
  args->AddString(
      "out", &c->out_path,
      "write the trajectory (trajectory.csv format) here on exit, atomically; with several bodies one "
      "file per pose stream, OUT's name + _NAME (poses_tool.csv, poses_tool_in_patient.csv); while "
      "running, every pose is appended to OUT.partial at once (what survives a crash), removed at a "
      "clean exit");
  args->AddString(
      "lcm-url", &c->lcm_url,
      "LCM URL (default: lcm.url of the rig YAML, else LCM's default); with --log: publish poses there, "
      "as fast as the log is read (slow receivers over udpm may drop some)");
  args->AddString("channel", &c->channel,
                  "output channel (default: tracker.channel, else MCMT_POSE); with several bodies the "
                  "prefix of their channels");
  args->AddDouble("deadline-ms", &c->deadline_ms,
                  "frame deadline: wait this long after a frame's first detection for the other cameras "
                  "(overrides tracker.deadline_ms; raise it when cameras' messages lag each other)");
  args->AddDouble("max-wait-ms", &c->max_wait_ms,
                  "live: longest wait for a camera whose messages lag (measured per camera) after a frame's "
                  "first detection (overrides tracker.max_wait_ms; 0: only the deadline)");
  args->AddFlag("quiet", &c->quiet, "no status lines (warnings are still printed)");
  args->AddEpilog(
      "\nexamples:\n"
      "  mcmt-tracker --config rig.yaml --map out/map.yaml\n"
      "  mcmt-tracker --config rig.yaml --map out/map.yaml --log session.lcmlog --out poses.csv\n"
      "  mcmt-tracker --config rig.yaml --lcm-url 'udpm://239.255.76.67:7667?ttl=1'   # waits for "
      "MCMT_MAP\n");
  args->SetConfigHelp("### tracker\n\n" + mcmt::TrackerOptionTable().Markdown() + "\n### sync\n\n" +
                      mcmt::SyncOptionTable().Markdown());
}

// The rig YAML's tracker: section with the command line's overrides, checked.
mcmt::TrackerNodeOptions OptionsOf(const mcmt::RigConfig& rig, const Cli& c, const mcmt::ArgParser& args) {
  mcmt::TrackerNodeOptions options;
  options.tracker = mcmt::TrackerOptions::FromConfig(rig);
  if (args.Given("channel")) options.tracker.channel = c.channel;
  if (args.Given("deadline-ms")) options.tracker.deadline_ms = c.deadline_ms;
  if (args.Given("max-wait-ms")) options.tracker.max_wait_ms = c.max_wait_ms;
  options.tracker.Validate();
  options.log_mode = !c.log_path.empty();
  options.keep_trajectory = !c.out_path.empty();
  if (!c.out_path.empty()) options.partial_path = c.out_path + ".partial";
  options.quiet = c.quiet;
  return options;
}

// A log is read by core's reader (nothing arrives on the memq input; poses go out only with --lcm-url);
// live, both ways on --lcm-url or the rig's lcm.url.
void OpenLcms(const Cli& c, const mcmt::RigConfig& rig, const mcmt::ArgParser& args,
              std::unique_ptr<lcm::LCM>* input, std::unique_ptr<lcm::LCM>* output) {
  if (c.log_path.empty()) {
    *input = mcmt::OpenLcm(args.Given("lcm-url") ? c.lcm_url : rig.lcm_url);
    return;
  }
  if (!std::ifstream(c.log_path, std::ios::binary))
    throw std::runtime_error(c.log_path + ": cannot open the log");
  *input = mcmt::OpenLcm("memq://");
  if (args.Given("lcm-url")) *output = mcmt::OpenLcm(c.lcm_url);
}

// One file per pose stream: OUT for a single object, else OUT's name + _NAME (poses_tool.csv); the
// partial files go only once every final file is written.
void WriteTrajectories(const Cli& c, const mcmt::TrackerNodeOptions& options, const mcmt::TrackerNode& node) {
  if (node.streams().empty()) mcmt::WriteTrajectory(c.out_path, {}, true);  // no map came
  for (const mcmt::PoseStream& s : node.streams()) {
    const std::string path = s.single ? c.out_path : mcmt::BodyPath(c.out_path, s.name);
    mcmt::WriteTrajectory(path, s.trajectory, true);
    if (!c.quiet)
      std::cerr << "mcmt-tracker: wrote " << s.trajectory.size() << " poses to " << path << std::endl;
  }
  std::remove(options.partial_path.c_str());
  for (const mcmt::PoseStream& s : node.streams())
    if (!s.single) std::remove((mcmt::BodyPath(c.out_path, s.name) + ".partial").c_str());
}

int Main(int argc, char** argv) {
  Cli c;
  mcmt::ArgParser args(
      "mcmt-tracker",
      "Tracks the object with a known map: one object_pose_t per frame on MCMT_POSE (rig_from_object,\n"
      "covariance, RMS error, cameras and markers used, status, latency). With several bodies (a map\n"
      "with objects:), one per moving body on MCMT_POSE_<NAME>, and the relative poses of\n"
      "tracker.relative on MCMT_POSE_<OF>_IN_<IN>.");
  DeclareOptions(&args, &c);
  int exit_code = 0;
  if (!args.Parse(argc, argv, &exit_code)) return exit_code;

  const mcmt::RigConfig rig = mcmt::LoadRigConfig(c.config);
  mcmt::TrackerNodeOptions options = OptionsOf(rig, c, args);
  std::optional<mcmt::RigMap> map;
  if (!c.map_path.empty()) map = mcmt::ReadMap(c.map_path);
  // The map's own uncertainty (mcmt-mapper writes it into map.yaml; older maps have none): the poses'
  // covariances then hold the map's error too (tracker.map_uncertainty).
  if (!c.map_path.empty()) options.map_covariance = mcmt::ReadMapCovariance(c.map_path);
  if (map) mcmt::CheckMapMatchesRig(*map, rig, c.map_path);

  std::unique_ptr<lcm::LCM> input, output;
  OpenLcms(c, rig, args, &input, &output);
  const mcmt::StopToken stop = mcmt::StopOnSignals();
  mcmt::TrackerNode node(*input, rig, options, map, output.get());
  if (!c.quiet)  // subscribed from here on (tests wait for this line)
    std::cerr << "mcmt-tracker: ready, " << (map ? "" : "waiting for MCMT_MAP, ") << "poses on "
              << (node.streams().empty() ? options.tracker.channel : StreamChannels(node.streams()))
              << (options.log_mode && !output ? " (not published: --log without --lcm-url)" : "")
              << std::endl;
  mcmt::LogReadReport report;
  if (options.log_mode)
    report = node.RunLog(c.log_path, stop);
  else
    node.Run(stop);
  if (!c.out_path.empty()) WriteTrajectories(c, options, node);
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
