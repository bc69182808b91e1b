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

// The command line, as given.
struct Cli {
  std::string config, log, out, lcm_url, reference_camera, old_map, pose_channel = mcmt::kPoseChannel;
  bool refine_layout = false, maintain = false;
  int frames = 0;
  double seconds = 0.0, marker_size_sigma_percent = 0.0;
  bool allow_partial = false, publish = false, no_refine = false, force = false;
  int threads = -1;
};

void DeclareOptions(mcmt::ArgParser* args, Cli* c) {
  args->AddString("config", &c->config, "rig YAML", true);
  args->AddString("log", &c->log, "read detections from this LCM log (at full speed) instead of live LCM");
  args->AddString("out", &c->out,
                  "output folder: map.yaml, trajectory.csv, report.json, map_initial.yaml, "
                  "trajectory_initial.csv (required; with --maintain optional: map.yaml rewritten at each "
                  "new map)");
  args->AddString("lcm-url", &c->lcm_url, "LCM URL (default: lcm.url of the rig YAML, else LCM's default)");
  args->AddInt("frames", &c->frames, "stop collecting after this many frames (0: no limit)",
               mcmt::AtLeast(0));
  args->AddDouble("seconds", &c->seconds,
                  "stop collecting after this many seconds (log: of message time; 0: no limit)",
                  mcmt::AtLeast(0));
  args->AddFlag("allow-partial", &c->allow_partial,
                "map the connected cameras and markers, leaving out the others; write a map no camera "
                "supports (mapper.unsupported_rms_ratio) with a warning");
  args->AddFlag("publish", &c->publish,
                "with --log: also publish status and the map on --lcm-url (live: always)");
  args->AddString("reference-camera", &c->reference_camera,
                  "reference camera (default: mapper.reference_camera, "
                  "else the best connected)");
  args->AddInt("threads", &c->threads, "solver threads (-1: mapper.threads of the rig YAML, 0: all cores)",
               mcmt::AtLeast(-1));
  args->AddDouble(
      "marker-size-sigma-percent", &c->marker_size_sigma_percent,
      "the printed marker size's relative 1-sigma in %, instead of mapper.marker_size_sigma_percent",
      mcmt::InRange(0, 10, false, true));
  args->AddFlag("no-refine", &c->no_refine, "initialisation only (no bundle adjustment)");
  args->AddFlag("force", &c->force, "overwrite the results of another session in --out");
  args->AddString(
      "map", &c->old_map,
      "offline update: start from this map.yaml, re-estimate the cameras that moved, add the rig's "
      "cameras it lacks (report.json moved_cameras, added_cameras)");
  args->AddFlag("refine-layout", &c->refine_layout,
                "with --map: refine the marker layout too (default: held fixed)");
  args->AddFlag("maintain", &c->maintain,
                "with --map, live: keep the map true while trackers run: re-estimate a camera the tracker "
                "reports suspect or excluded (MCMT_TRACKER_STATUS) from frames of object poses seen by the "
                "others, add a rig camera that publishes and is not in the map, publish each new map on "
                "MCMT_MAP (mapper.maintain_frames, maintain_added_frames)");
  args->AddString("pose-channel", &c->pose_channel, "with --maintain: the tracker's object_pose_t channel");
  args->AddEpilog(
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
  args->SetConfigHelp("### mapper\n\n" + mcmt::MapperOptionTable().Markdown() + "\n### sync\n\n" +
                      mcmt::SyncOptionTable().Markdown());
}

// The rig YAML's mapper: section with the command line's overrides.
mcmt::MapperOptions OptionsOf(const mcmt::RigConfig& rig, const Cli& c, bool size_sigma_given) {
  mcmt::MapperOptions options = mcmt::MapperOptions::FromConfig(rig);
  if (c.allow_partial) options.allow_partial = true;
  if (!c.reference_camera.empty()) {
    if (!rig.FindCamera(c.reference_camera))
      throw std::runtime_error("--reference-camera: no camera named '" + c.reference_camera + "' in " +
                               c.config);
    options.reference_camera = c.reference_camera;
  }
  if (c.threads >= 0) options.threads = c.threads;
  if (c.no_refine) options.refine = false;
  if (size_sigma_given) options.marker_size_sigma_percent = c.marker_size_sigma_percent;
  return options;
}

// --map: the offline update's starting map (not the map --out would overwrite).
void SetBaseMap(const Cli& c, mcmt::Mapper* mapper) {
  if (c.old_map.empty()) {
    if (c.refine_layout) throw std::runtime_error("--refine-layout: only with --map (an offline update)");
    return;
  }
  mcmt::RigMap base = mcmt::ReadMap(c.old_map);
  if (std::filesystem::exists(c.old_map) && std::filesystem::exists(c.out + "/map.yaml") &&
      std::filesystem::equivalent(c.old_map, c.out + "/map.yaml"))
    throw std::runtime_error("--out: " + c.out +
                             " holds the old map given with --map; write the update elsewhere");
  mapper->SetBaseMap(base, c.refine_layout);
}

mcmt::MapperNodeOptions NodeOptionsOf(const mcmt::RigConfig& rig, const Cli& c) {
  mcmt::MapperNodeOptions node_options;
  node_options.outdir = c.out;
  node_options.session = mcmt::MapperSession(c.log);
  node_options.force = c.force;
  for (const mcmt::CameraConfig& cam : rig.cameras)
    node_options.rig_image_sizes[cam.name] = {cam.model.width, cam.model.height};
  node_options.max_frames = c.frames;
  node_options.max_seconds = c.seconds;
  node_options.stop = mcmt::StopOnSignals({SIGINT, SIGTERM, SIGUSR1});
  if (!c.log.empty()) {
    node_options.log_path = c.log;
    node_options.publish = c.publish;
  }
  return node_options;
}

// A log (checked readable and not empty) is read by core's reader: nothing arrives on the memq input, and
// the output is --lcm-url only with --publish. Live: both on --lcm-url.
void OpenLcms(const Cli& c, std::unique_ptr<lcm::LCM>* input, std::unique_ptr<lcm::LCM>* output) {
  if (c.log.empty()) {
    *input = mcmt::OpenLcm(c.lcm_url);
    return;
  }
  if (access(c.log.c_str(), R_OK) != 0) throw std::runtime_error("cannot read log " + c.log);
  std::error_code ec;
  if (std::filesystem::file_size(c.log, ec) == 0 && !ec)
    throw std::runtime_error("no detections_t messages on MCMT_DETECTIONS_* in " + c.log + " (empty log)");
  *input = mcmt::OpenLcm("memq://");
  if (c.publish) *output = mcmt::OpenLcm(c.lcm_url);
}

int Run(int argc, char** argv) {
  Cli c;
  mcmt::ArgParser args("mcmt-mapper",
                       "Maps a rig from marker detections: camera poses, marker layout, object trajectory "
                       "(graph initialisation + bundle adjustment).");
  DeclareOptions(&args, &c);
  int code = 0;
  if (!args.Parse(argc, argv, &code)) return code;

  const mcmt::RigConfig rig = mcmt::LoadRigConfig(c.config);
  const mcmt::MapperOptions options = OptionsOf(rig, c, args.Given("marker-size-sigma-percent"));
  if (!args.Given("lcm-url")) c.lcm_url = rig.lcm_url;
  if (c.maintain) return Maintain(rig, options, c.old_map, c.log, c.out, c.lcm_url, c.pose_channel);
  if (c.out.empty()) throw std::runtime_error("--out is required (the output folder)");
  if (args.Given("pose-channel")) throw std::runtime_error("--pose-channel: only with --maintain");

  mcmt::Mapper mapper(options);
  SetBaseMap(c, &mapper);
  const mcmt::MapperNodeOptions node_options = NodeOptionsOf(rig, c);
  std::unique_ptr<lcm::LCM> input, output;
  OpenLcms(c, &input, &output);
  lcm::LCM* out_lcm = output ? output.get() : (c.log.empty() ? input.get() : nullptr);
  mcmt::MapperNode node(*input, out_lcm, mapper, node_options, std::cerr);

  const std::string reason = node.Collect();
  mcmt::DefaultSignals();  // a second Ctrl-C during the solve ends the process
  std::cerr << "collected " << mapper.NumMessages() << " detections messages (" << reason << ")\n";
  if (mapper.NumMessages() == 0)
    throw std::runtime_error(c.log.empty() ? "no detections received on MCMT_DETECTIONS_*"
                                           : "no detections_t messages on MCMT_DETECTIONS_* in " + c.log);
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
