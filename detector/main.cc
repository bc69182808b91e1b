// mcmt-detector: one camera's frames -> marker detections on LCM channel MCMT_DETECTIONS_<CAMERA>.
#include <cstdlib>
#include <iostream>
#include <lcm/lcm-cpp.hpp>

#include "core/cli.h"
#include "core/config.h"
#include "core/lcm_util.h"
#include "core/options.h"
#include "detector/node.h"

int main(int argc, char** argv) {
  // FFmpeg's own log lines would break the one-line error contract; errors are reported by us.
  setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0);
  return mcmt::RunMain("mcmt-detector", [&]() {
    std::string config, lcm_url, source, rate = "max";
    std::string camera;
    bool loop = false, images = false, quiet = false;
    int max_frames = -1;
    long long start_utime = mcmt::kDefaultStartUtime;
    long long start_wall_utime = 0;
    double fps = 0.0, max_lag_ms = 0.0;
    mcmt::ArgParser args("mcmt-detector",
                         "Detects the rig's markers in one camera's frames (image folder, video file or live "
                         "device) and publishes them as mcmt.detections_t on MCMT_DETECTIONS_<CAMERA>.");
    args.AddString("config", &config, "rig YAML", true);
    args.AddString("camera", &camera, "camera name in the rig YAML", true);
    args.AddString("lcm-url", &lcm_url, "LCM URL (default: lcm.url of the rig YAML, else LCM's default)");
    args.AddString("source", &source,
                   "overrides the camera's source: image folder, video file, V4L2 index or path, GStreamer "
                   "pipeline");
    args.AddString("rate", &rate, "max (as fast as possible) or realtime (recordings at their frame rate)");
    args.AddFlag("loop", &loop, "recordings: start again at the end");
    args.AddInt("max-frames", &max_frames, "stop after N frames (-1: no limit)", mcmt::AtLeast(-1));
    args.AddFlag("images", &images, "also publish rate-limited JPEG images on MCMT_IMAGE_<CAMERA>");
    args.AddInt64("start-utime", &start_utime,
                  "utime (us) of frame 0 of recordings without a timestamps file (frame k: + k * 1e6 / fps)");
    args.AddInt64(
        "start-wall-utime", &start_wall_utime,
        "with --rate realtime: wall clock (us since the epoch) at which to publish the first frame; "
        "give several detectors the same value to publish each frame together");
    args.AddDouble("fps", &fps,
                   "frame rate of recordings (0: detector.fps of the rig, the video's own, or 30)",
                   mcmt::InRange(0, 1e6));
    args.AddDouble("max-lag-ms", &max_lag_ms,
                   "with --rate realtime: drop frames already this late, as a live camera would (0: none; "
                   "default: detector.max_lag_ms of the rig)",
                   mcmt::InRange(0, 1e9));
    args.AddFlag("quiet", &quiet, "no status lines");
    args.AddEpilog(
        "Examples:\n"
        "  mcmt-detector --config rig.yaml --camera cam0\n"
        "  mcmt-detector --config rig.yaml --camera cam1 --source /dev/video2 --lcm-url "
        "'udpm://239.255.76.67:7667?ttl=1'\n"
        "  mcmt-detector --config out/sim/rig.yaml --camera cam0 --rate realtime --loop --images\n"
        "Settings come from the rig YAML's markers: and detector: sections (see docs). Exits 0 at the end of "
        "a\n"
        "recording after publishing every frame; SIGINT/SIGTERM stop it cleanly.");
    args.SetConfigHelp("### detector\n\n" + mcmt::DetectorOptionTable().Markdown() + "\n" +
                       mcmt::DetectorNodeOptionTable().Markdown());
    int exit_code = 0;
    if (!args.Parse(argc, argv, &exit_code)) return exit_code;

    const mcmt::RigConfig rig = mcmt::LoadRigConfig(config);
    mcmt::DetectorNodeOptions options;
    options.LoadFromConfig(rig);
    options.camera = camera;
    options.source = source;
    options.rate = rate;
    options.loop = loop;
    options.max_frames = max_frames;
    if (args.Given("images")) options.images = images;
    options.start_utime = start_utime;
    options.start_wall_utime = start_wall_utime;
    if (args.Given("fps") && fps > 0) options.fps = fps;
    if (args.Given("max-lag-ms")) options.max_lag_ms = max_lag_ms;
    options.quiet = quiet;
    if (lcm_url.empty()) lcm_url = rig.lcm_url;

    std::unique_ptr<lcm::LCM> lcm = mcmt::OpenLcm(lcm_url);
    mcmt::DetectorNode node(rig, options, *lcm);
    node.Run(mcmt::StopOnSignals());
    return 0;
  });
}
