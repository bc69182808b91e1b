// mcmt-viz: shows the rig, the object and its track (MRPT), live or headless.
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "core/cli.h"
#include "core/config.h"
#include "core/lcm_util.h"
#include "core/options.h"
#include "viz/viewer.h"

namespace {

// The command line, as given.
struct Cli {
  mcmt::viz::ViewerOptions o;
  std::string config, size = "1280x720", lcm_url;
  bool no_rays = false, no_legend = false, no_grid = false;
};

void DeclareOptions(mcmt::ArgParser* args, Cli* c) {
  args->AddString("map", &c->o.map_path, "map.yaml from mcmt-mapper (default: MCMT_MAP from the log or LCM)");
  args->AddString("initial-map", &c->o.initial_map_path,
                  "the mapper's initial solution (OUTDIR/map_initial.yaml): before/after side by side");
  args->AddString(
      "trajectory", &c->o.trajectory_path,
      "trajectory.csv, or for a map with several bodies the mapper's OUTDIR (its trajectory_<body>.csv) or "
      "the tracker's --out PATH (PATH_<body>.csv) "
      "(default: MCMT_POSE and every MCMT_POSE_<BODY> from the log or LCM)");
  args->AddString(
      "initial-trajectory", &c->o.initial_trajectory_path,
      "trajectory of the initial solution (default: trajectory_initial.csv beside --initial-map)");
  args->AddString("log", &c->o.log_path,
                  "LCM log to read (MCMT_MAP, MCMT_POSE, MCMT_POSE_<BODY>, MCMT_DETECTIONS_*)");
  args->AddString("lcm-url", &c->lcm_url,
                  "LCM URL for live traffic (default: lcm.url of --config, or LCM's default)");
  args->AddString("config", &c->config, "rig YAML: its optional viz: section and lcm.url");
  args->AddString("snapshot", &c->o.snapshot_path, "render offscreen to this PNG (no display needed)");
  args->AddString("size", &c->size, "image / window size WIDTHxHEIGHT");
  args->AddString("save-scene", &c->o.save_scene_path, "save the scene for MRPT's SceneViewer3D (.3Dscene)");
  args->AddString("video", &c->o.video_dir,
                  "render one PNG per trajectory frame into DIR (frame_000000.png ...)");
  args->AddString("view", &c->o.view,
                  "headless view: rig (frame the rig and the trail), object (close-up of the object), "
                  "follow (rig view centred on the object)");
  args->AddInt("frame", &c->o.frame, "trajectory row to show (negative: from the end; -1 = last)");
  args->AddString("dictionary", &c->o.scene.dictionary,
                  "marker dictionary for the bitmaps (default: the map's)");
  args->AddFlag("no-rays", &c->no_rays, "do not draw rays from the cameras to the detected markers");
  args->AddFlag("no-legend", &c->no_legend, "do not draw the residual colour legend");
  args->AddFlag("no-grid", &c->no_grid, "do not draw the ground grid");
  args->AddDouble("residual-scale", &c->o.scene.residual_scale_px,
                  "residual (px) drawn red, green at and below a quarter of it (an absolute scale: a map "
                  "keeps its colours); 0: the largest per-camera/marker RMS shown");
  args->AddInt("max-poses", &c->o.max_poses,
               "live headless: render after this many poses (and a map) arrived");
  args->AddDouble("timeout", &c->o.timeout_s, "live headless: seconds to wait for the map and poses");
  args->AddDouble("redraw-hz", &c->o.redraw_hz, "live window: redraws per second at most");
  args->AddDouble("max-seconds", &c->o.max_seconds,
                  "live window: close it after this many seconds (0: never)");
  args->AddFlag("follow", &c->o.follow, "live window: start following the object (key f toggles)");
  args->AddEpilog(
      "Live window keys: f follow the object, r reset the view, t toggle rays, left/right (or , .) step "
      "through the frames, n back to the newest, q quit; the mouse orbits, pans and zooms.\n"
      "Examples:\n"
      "  mcmt-viz --map out/map.yaml --trajectory out/trajectory.csv --snapshot view.png\n"
      "  mcmt-viz --map out/map.yaml --trajectory out/ --snapshot bodies.png   (several bodies: each in "
      "its "
      "colour, with its trail and name)\n"
      "  mcmt-viz --map out/map.yaml --initial-map out/map_initial.yaml --trajectory out/trajectory.csv "
      "--snapshot before_after.png\n"
      "  mcmt-viz --log session.lcmlog --video frames/   (then: ffmpeg -framerate 30 -i "
      "frames/frame_%06d.png session.mp4)\n"
      "  mcmt-viz --lcm-url udpm://239.255.76.67:7667?ttl=0          (live window)\n");
  args->SetConfigHelp("### viz\n\n" + mcmt::viz::VizOptionTable().Markdown());
}

// The rig YAML's viz: section (and its dictionary and lcm.url) under the options the command line gave.
void ApplyConfig(const mcmt::ArgParser& args, Cli* c) {
  mcmt::viz::ViewerOptions& o = c->o;
  const mcmt::RigConfig rig = mcmt::LoadRigConfig(c->config);
  mcmt::viz::ViewerOptions from_yaml = o;
  mcmt::viz::LoadVizSection(rig.viz, &from_yaml);
  if (!args.Given("size")) {
    o.scene.width = from_yaml.scene.width;
    o.scene.height = from_yaml.scene.height;
  }
  if (!args.Given("residual-scale")) o.scene.residual_scale_px = from_yaml.scene.residual_scale_px;
  if (!args.Given("redraw-hz")) o.redraw_hz = from_yaml.redraw_hz;
  if (!args.Given("follow")) o.follow = from_yaml.follow;
  if (!args.Given("no-rays")) o.scene.rays = from_yaml.scene.rays;
  if (!args.Given("no-legend")) o.scene.legend = from_yaml.scene.legend;
  o.scene.trail_max = from_yaml.scene.trail_max;
  o.scene.azimuth_deg = from_yaml.scene.azimuth_deg;
  o.scene.elevation_deg = from_yaml.scene.elevation_deg;
  o.scene.fov_deg = from_yaml.scene.fov_deg;
  if (o.scene.dictionary.empty() && !args.Given("map")) o.scene.dictionary = rig.markers.dictionary;
  if (c->lcm_url.empty()) c->lcm_url = rig.lcm_url;
}

// A log is read by core's reader (nothing arrives on the memq handle); live traffic only when needed.
std::unique_ptr<lcm::LCM> OpenLcmFor(const Cli& c, bool* is_log) {
  *is_log = false;
  if (!c.o.log_path.empty()) {
    if (!std::filesystem::is_regular_file(c.o.log_path))
      throw std::runtime_error(c.o.log_path + ": no such log file");
    *is_log = true;
    return mcmt::OpenLcm("memq://");
  }
  if (c.o.NeedsLiveLcm()) return mcmt::OpenLcm(c.lcm_url);
  return nullptr;
}

int Run(int argc, char** argv) {
  Cli c;
  mcmt::ArgParser args("mcmt-viz",
                       "3D view of the rig (camera frustums), the object (its textured markers) and its "
                       "trail, from files, a log or live LCM; a live MRPT window or headless PNG/.3Dscene "
                       "output.");
  DeclareOptions(&args, &c);
  int exit_code = 0;
  if (!args.Parse(argc, argv, &exit_code)) return exit_code;
  // Defaults from the rig YAML, then the command line again on top.
  if (!c.config.empty()) ApplyConfig(args, &c);
  if (args.Given("size")) {
    try {
      mcmt::viz::ParseSize(c.size, &c.o.scene.width, &c.o.scene.height);
    } catch (const std::invalid_argument& e) {  // a usage error, as the parser reports them
      std::cerr << "mcmt-viz: error: " << e.what() << "\n";
      return 2;
    }
  }
  if (c.no_rays) c.o.scene.rays = false;
  if (c.no_legend) c.o.scene.legend = false;
  if (c.no_grid) c.o.scene.grid = false;
  c.o.Validate();

  bool is_log = false;
  std::unique_ptr<lcm::LCM> lcm = OpenLcmFor(c, &is_log);
  mcmt::viz::Viewer viewer(c.o, lcm.get(), is_log);
  return viewer.Run();
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-viz", [&] { return Run(argc, argv); });
}
