// mcmt-mapper: the paper's initialisation and bundle adjustment over detections from live LCM or a log.
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <iostream>

#include "core/cli.h"
#include "core/config.h"
#include "core/lcm_util.h"
#include "core/options.h"
#include "mapper/maintain.h"
#include "mapper/mapper.h"
#include "mapper/node.h"
#include "mapper/out_folder.h"

namespace {

// --maintain: live, from the map given with --map (mapper/maintain.h).
int Maintain(const mcmt::RigConfig& rig, const mcmt::MapperOptions& options, const std::string& map_path,
             const std::string& log, const std::string& out, const std::string& lcm_url,
             const std::string& pose_channel) {
  if (map_path.empty()) throw std::runtime_error("--maintain: needs --map (the map in use)");
  if (!log.empty()) throw std::runtime_error("--maintain: live only (no --log)");
  const mcmt::RigMap map = mcmt::ReadMap(map_path);
  std::unique_ptr<lcm::LCM> lcm = mcmt::OpenLcm(lcm_url);
  mcmt::MaintainNodeOptions node_options;
  node_options.pose_channel = pose_channel;
  node_options.outdir = out;
  const mcmt::StopToken stop = mcmt::StopOnSignals();
  mcmt::MaintainNode node(*lcm, lcm.get(), rig, options, map, node_options, std::cerr);
  node.Run(stop);
  int published = 0;
  for (const mcmt::MaintainEvent& e : node.events()) published += e.published;
  std::cerr << "maintain: stopped after " << published << " new maps" << std::endl;
  return 0;
}

int Run(int argc, char** argv) {
  std::string config, log, out, lcm_url, reference_camera, old_map, pose_channel = mcmt::kPoseChannel;
  bool refine_layout = false, maintain = false;
  int frames = 0;
  double seconds = 0.0;
  bool allow_partial = false, publish = false, no_refine = false, force = false;
  int threads = -1;
  mcmt::ArgParser args("mcmt-mapper",
                       "Maps a rig from marker detections: camera poses, marker layout, object trajectory "
                       "(graph initialisation + bundle adjustment).");
  args.AddString("config", &config, "rig YAML", true);
  args.AddString("log", &log, "read detections from this LCM log (at full speed) instead of live LCM");
  args.AddString("out", &out,
                 "output folder: map.yaml, trajectory.csv, report.json, map_initial.yaml, "
                 "trajectory_initial.csv (required; with --maintain optional: map.yaml rewritten at each "
                 "new map)");
  args.AddString("lcm-url", &lcm_url, "LCM URL (default: lcm.url of the rig YAML, else LCM's default)");
  args.AddInt("frames", &frames, "stop collecting after this many frames (0: no limit)", mcmt::AtLeast(0));
  args.AddDouble("seconds", &seconds,
                 "stop collecting after this many seconds (log: of message time; 0: no limit)",
                 mcmt::AtLeast(0));
  args.AddFlag("allow-partial", &allow_partial,
               "map the connected cameras and markers, leaving out the others; write a map no camera "
               "supports (mapper.unsupported_rms_ratio) with a warning");
  args.AddFlag("publish", &publish,
               "with --log: also publish status and the map on --lcm-url (live: always)");
  args.AddString("reference-camera", &reference_camera,
                 "reference camera (default: mapper.reference_camera, "
                 "else the best connected)");
  args.AddInt("threads", &threads, "solver threads (-1: mapper.threads of the rig YAML, 0: all cores)",
              mcmt::AtLeast(-1));
  args.AddFlag("no-refine", &no_refine, "initialisation only (no bundle adjustment)");
  args.AddFlag("force", &force, "overwrite the results of another session in --out");
  args.AddString(
      "map", &old_map,
      "offline update: start from this map.yaml, re-estimate the cameras that moved, add the rig's "
      "cameras it lacks (report.json moved_cameras, added_cameras)");
  args.AddFlag("refine-layout", &refine_layout,
               "with --map: refine the marker layout too (default: held fixed)");
  args.AddFlag("maintain", &maintain,
               "with --map, live: keep the map true while trackers run: re-estimate a camera the tracker "
               "reports suspect or excluded (MCMT_TRACKER_STATUS) from frames of object poses seen by the "
               "others, add a rig camera that publishes and is not in the map, publish each new map on "
               "MCMT_MAP (mapper.maintain_frames, maintain_added_frames)");
  args.AddString("pose-channel", &pose_channel, "with --maintain: the tracker's object_pose_t channel");
  args.AddEpilog(
      "Live: collects MCMT_DETECTIONS_* with a progress line until SIGINT/SIGTERM/SIGUSR1, a "
      "mapper_command_t\n"
      "\"solve\" on MCMT_MAPPER_COMMAND, or the --frames/--seconds limit; then solves, writes OUTDIR and "
      "publishes\n"
      "rig_map2_t on MCMT_MAP (status on MCMT_MAPPER_STATUS).\n"
      "examples:\n"
      "  mcmt-mapper --config rig.yaml --log session.lcmlog --out map/\n"
      "  mcmt-mapper --config rig.yaml --out map/ --seconds 60\n"
      "  mcmt-mapper --config rig.yaml --map OLD/map.yaml --log new.lcmlog --out NEW/   # offline update\n"
      "  mcmt-mapper --config rig.yaml --map map.yaml --maintain                        # live upkeep\n");
  args.SetConfigHelp("### mapper\n\n" + mcmt::MapperOptionTable().Markdown() + "\n### sync\n\n" +
                     mcmt::SyncOptionTable().Markdown());
  int code = 0;
  if (!args.Parse(argc, argv, &code)) return code;

  const mcmt::RigConfig rig = mcmt::LoadRigConfig(config);
  mcmt::MapperOptions options = mcmt::MapperOptions::FromConfig(rig);
  if (allow_partial) options.allow_partial = true;
  if (!reference_camera.empty()) {
    if (!rig.FindCamera(reference_camera))
      throw std::runtime_error("--reference-camera: no camera named '" + reference_camera + "' in " + config);
    options.reference_camera = reference_camera;
  }
  if (threads >= 0) options.threads = threads;
  if (no_refine) options.refine = false;
  if (!args.Given("lcm-url")) lcm_url = rig.lcm_url;
  if (maintain) return Maintain(rig, options, old_map, log, out, lcm_url, pose_channel);
  if (out.empty()) throw std::runtime_error("--out is required (the output folder)");
  if (args.Given("pose-channel")) throw std::runtime_error("--pose-channel: only with --maintain");

  mcmt::Mapper mapper(options);
  if (!old_map.empty()) {
    mcmt::RigMap base = mcmt::ReadMap(old_map);
    if (!out.empty() && std::filesystem::exists(old_map) && std::filesystem::exists(out + "/map.yaml") &&
        std::filesystem::equivalent(old_map, out + "/map.yaml"))
      throw std::runtime_error("--out: " + out +
                               " holds the old map given with --map; write the update elsewhere");
    mapper.SetBaseMap(base, refine_layout);
  } else if (refine_layout) {
    throw std::runtime_error("--refine-layout: only with --map (an offline update)");
  }
  mcmt::MapperNodeOptions node_options;
  node_options.outdir = out;
  node_options.session = mcmt::MapperSession(log);
  node_options.force = force;
  for (const mcmt::CameraConfig& c : rig.cameras)
    node_options.rig_image_sizes[c.name] = {c.model.width, c.model.height};
  node_options.max_frames = frames;
  node_options.max_seconds = seconds;
  node_options.stop = mcmt::StopOnSignals({SIGINT, SIGTERM, SIGUSR1});
  std::unique_ptr<lcm::LCM> input, output;
  if (!log.empty()) {
    if (access(log.c_str(), R_OK) != 0) throw std::runtime_error("cannot read log " + log);
    std::error_code ec;
    if (std::filesystem::file_size(log, ec) == 0 && !ec)
      throw std::runtime_error("no detections_t messages on MCMT_DETECTIONS_* in " + log + " (empty log)");
    node_options.log_path = log;
    node_options.publish = publish;
    input = mcmt::OpenLcm("memq://");  // nothing arrives on it: the log is read by core's reader
    if (publish) output = mcmt::OpenLcm(lcm_url);
  } else {
    input = mcmt::OpenLcm(lcm_url);
  }
  lcm::LCM* out_lcm = output ? output.get() : (log.empty() ? input.get() : nullptr);
  mcmt::MapperNode node(*input, out_lcm, mapper, node_options, std::cerr);

  const std::string reason = node.Collect();
  mcmt::DefaultSignals();  // a second Ctrl-C during the solve ends the process
  std::cerr << "collected " << mapper.NumMessages() << " detections messages (" << reason << ")\n";
  if (mapper.NumMessages() == 0)
    throw std::runtime_error(log.empty() ? "no detections received on MCMT_DETECTIONS_*"
                                         : "no detections_t messages on MCMT_DETECTIONS_* in " + log);
  node.SolveWriteAndPublish();
  if (node.log_report().damaged()) {
    std::cerr << "mcmt-mapper: " << node.log_report().Summary() << " (exit status " << mcmt::kExitDamagedLog
              << ")\n";
    return mcmt::kExitDamagedLog;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-mapper", [&] { return Run(argc, argv); });
}
