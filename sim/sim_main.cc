// mcmt-sim: writes a simulated session (rig.yaml, intrinsics, ground truth, images / video, or a log of
// detections) for the other mcmt processes and for mcmt-eval.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/cli.h"
#include "core/dictionary.h"
#include "core/progress.h"
#include "sim/sim.h"

namespace {

void ParseImageSize(const std::string& text, int* width, int* height) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w <= 0 ||
      h <= 0)
    throw std::invalid_argument("--image-size: expected WIDTHxHEIGHT such as 640x480, got '" + text + "'");
  if (w < 16 || h < 16 || w > 8192 || h > 8192)
    throw std::invalid_argument("--image-size: expected 16..8192 pixels per side, got '" + text + "'");
  *width = w;
  *height = h;
}

// The command line's values; the initialisers are the defaults --help shows.
struct SimArgs {
  std::string out, object = "four_sided", scene = "object", dictionary = "DICT_6X6_250",
                   image_size = "640x480", distortion = "none", imaging = "default";
  int cameras = 5, frames = 300, still_frames = 0, threads = 1, quiet_zone = 1, supersampling = 0,
      jpeg_quality = 0, add_camera = -1;
  long long seed = 1;
  double radius = 1.0, camera_height = -1.0, fps = 30.0, marker_size = -1.0, hfov = 60.0, noise = 2.0,
         blur = 0.0, intrinsics_spread = 0.0, max_tilt = 35.0, turns = 1.5, max_speed = 0.0;
  double surface_albedo = -1.0, surface_texture = 0.0, shading = 0.3, gradient = 0.3, vignetting = 0.0,
         defocus = 0.0, shot_noise = 0.0, gamma = 1.0, sharpen = 0.0;
  double corner_noise = 0.1, miss_rate = 0.0, false_rate = 0.0, drop_rate = 0.0;
  std::vector<std::string> move_camera, intrinsics_error, clock;
  bool motion_blur = false, video = false, detections_only = false, bgr = false, quiet = false,
       plain_bg = false;
};

// The session's place: output folder, object, cameras, frames, dictionary and lens.
void DeclareSceneOptions(mcmt::ArgParser* p, SimArgs* a) {
  using mcmt::AtLeast, mcmt::InRange, mcmt::OneOf;
  mcmt::ArgParser& args = *p;
  args.AddString("out", &a->out,
                 "output folder (created if needed; numbered frames of an earlier session in its camera "
                 "folders are removed)",
                 true);
  args.AddString("object", &a->object, "four_sided | box | pentagon | cube | board");
  args.AddString(
      "scene", &a->scene,
      "object: one object (--object) | bodies: a static floor board and two moving objects, tool "
      "and patient, that cross and occlude each other (with --detections-only; rig.yaml lists "
      "objects:, ground_truth_<body>.yaml per body; --intrinsics-error, --clock and --max-speed-m-s as "
      "for object, each moving body at that top speed)",
      false, OneOf({"object", "bodies"}));
  args.AddInt("cameras", &a->cameras, "number of cameras on the circle (named cam0 .. camN-1)",
              InRange(1, 64));
  args.AddDouble("radius", &a->radius, "circle radius, metres", InRange(0.1, 100));
  args.AddDouble("camera-height", &a->camera_height,
                 "camera height above the object's mean height, metres (-1: half the radius)");
  args.AddInt("frames", &a->frames, "number of frames", InRange(1, 10000000));
  args.AddDouble("fps", &a->fps, "frame rate (frame k has utime 1e12 + round(k * 1e6 / fps) us)",
                 InRange(0, 10000, true));
  args.AddInt64("seed", &a->seed, "random seed (same seed and options: same bytes)");
  args.AddDouble(
      "marker-size", &a->marker_size, "marker side, metres (-1: 0.04, pentagon 0.025)",
      {"must be -1 or in (0.001, 10)", [](const double& v) { return v == -1.0 || (v > 0.001 && v < 10); }});
  args.AddString("dictionary", &a->dictionary, "ArUco dictionary name or dictionary file");
  args.AddString("image-size", &a->image_size, "WIDTHxHEIGHT");
  args.AddDouble("hfov-deg", &a->hfov, "horizontal field of view of the pinhole part, degrees",
                 InRange(5, 170, true, true));
  args.AddString("distortion", &a->distortion, "mild lens distortion", false,
                 OneOf({"none", "radtan", "fisheye"}));
  args.AddDouble("intrinsics-spread", &a->intrinsics_spread,
                 "per-camera relative spread of focal length, principal point and distortion (0: identical)",
                 InRange(0, 0.2));
}

// The imaging: noise, blur, margin, surface, light, encoding, and what is written.
void DeclareImagingOptions(mcmt::ArgParser* p, SimArgs* a) {
  using mcmt::AtLeast, mcmt::InRange, mcmt::OneOf;
  mcmt::ArgParser& args = *p;
  args.AddDouble("noise", &a->noise, "image noise sigma, gray levels", InRange(0, 100));
  args.AddDouble("blur", &a->blur, "Gaussian blur sigma, pixels (0: none)", InRange(0, 50));
  args.AddFlag("motion-blur", &a->motion_blur, "average 5 poses over half a frame interval (5x slower)");
  args.AddInt("supersampling", &a->supersampling,
              "0: exact area anti-aliasing; S: SxS point samples per pixel", InRange(0, 16));
  args.AddInt("quiet-zone", &a->quiet_zone, "white margin around each marker, in marker cells (0..2 typical)",
              InRange(0, 10));
  args.AddFlag("plain-background", &a->plain_bg, "uniform gray background instead of a textured one");
  args.AddString("imaging", &a->imaging,
                 "default | random: a different imaging condition per camera drawn from --seed (margin, "
                 "surface, shading, gradient, vignetting, blur or defocus, noise, gamma, sharpening, JPEG; "
                 "the imaging options below are then ignored)",
                 false, OneOf({"default", "random"}));
  args.AddDouble(
      "surface-albedo", &a->surface_albedo,
      "reflectance 0..1 of the surface the markers are glued on (-1: the object's own)",
      {"must be -1 or in [0, 1]", [](const double& v) { return v == -1.0 || (v >= 0 && v <= 1); }});
  args.AddDouble("surface-texture", &a->surface_texture,
                 "relative amplitude 0..1 of the surface's grain (0: plain)", InRange(0, 1));
  args.AddDouble("shading", &a->shading, "relative brightness change between faces by their normal, 0..1",
                 InRange(0, 1));
  args.AddDouble("gradient", &a->gradient, "relative brightness change of the light across the image, 0..1",
                 InRange(0, 1));
  args.AddDouble("vignetting", &a->vignetting, "relative fall-off of the light at the image corners, 0..1",
                 InRange(0, 1));
  args.AddDouble("defocus", &a->defocus, "defocus blur: disc radius, pixels (0: none)", InRange(0, 50));
  args.AddDouble("shot-noise", &a->shot_noise, "photon noise: variance added per linear gray level (0: none)",
                 InRange(0, 10));
  args.AddDouble("gamma", &a->gamma, "encoding gamma: written value 255 (v / 255)^(1 / gamma) (1: linear)",
                 InRange(0.2, 5));
  args.AddDouble("sharpen", &a->sharpen, "camera sharpening: unsharp mask amount, sigma 1 px (0: none)",
                 InRange(0, 5));
  args.AddInt("jpeg-quality", &a->jpeg_quality,
              "JPEG compression of every frame at this quality 1..100 (0: none)", InRange(0, 100));
  args.AddFlag("bgr", &a->bgr, "write 3-channel images");
  args.AddFlag("video", &a->video, "write DIR/camK.mp4 instead of PNG folders");
}

// The motion, rendering threads, detections-only sessions and what goes wrong in them.
void DeclareSessionOptions(mcmt::ArgParser* p, SimArgs* a) {
  using mcmt::AtLeast, mcmt::InRange, mcmt::OneOf;
  mcmt::ArgParser& args = *p;
  args.AddInt("still-frames", &a->still_frames, "length of each of two still segments, frames (0: none)",
              AtLeast(0));
  args.AddDouble("max-tilt-deg", &a->max_tilt, "largest tilt of the object from upright, degrees",
                 InRange(0, 90));
  args.AddDouble("turns", &a->turns, "turns of the object about the vertical over the sequence");
  args.AddDouble("max-speed-m-s", &a->max_speed,
                 "faster (or slower) motion: the object's centre reaches this top speed, m/s (the motion's "
                 "time scaled; 0: the default motion)");
  args.AddInt("threads", &a->threads, "cameras rendered in parallel", InRange(1, 64));
  args.AddFlag(
      "detections-only", &a->detections_only,
      "skip rendering; write DIR/detections.lcmlog (detections_t on MCMT_DETECTIONS_CAMK, event time = "
      "message utime)");
  args.AddDouble("corner-noise-px", &a->corner_noise, "detections-only: Gaussian corner noise sigma, pixels",
                 InRange(0, 100));
  args.AddDouble("miss-rate", &a->miss_rate, "detections-only: probability a visible marker is not detected",
                 InRange(0, 1));
  args.AddDouble("false-rate", &a->false_rate,
                 "detections-only: mean number of false detections (ids not on the object) per camera frame",
                 InRange(0, 100));
  args.AddDouble("drop-rate", &a->drop_rate, "detections-only: probability a camera frame is not published",
                 InRange(0, 1));
  args.AddList("move-camera", &a->move_camera,
               "CAM,FRAME,ROT_DEG,TRANS_MM: the camera is bumped at FRAME: turned by ROT_DEG degrees about "
               "its y axis and shifted by TRANS_MM millimetres along its x axis (FRAME 0: moved before the "
               "session, a session for mcmt-mapper --map; repeatable; ground_truth.yaml moves:)");
  args.AddInt("add-camera", &a->add_camera,
              "FRAME: one more camera (cam<N>, on the circle halfway between cam0 and cam1) that publishes "
              "from FRAME on (-1: none; ground_truth.yaml late_cameras:)",
              AtLeast(-1));
  args.AddList("intrinsics-error", &a->intrinsics_error,
               "CAM,FOCAL_PCT,CX_PX,CY_PX[,K1]: the rig is given wrong intrinsics for CAM (camK.yml and the "
               "detections' camera model: focal length off by FOCAL_PCT %, principal point by CX_PX, CY_PX "
               "pixels, k1 by K1); images, corners and ground_truth.yaml stay true (repeatable)");
  args.AddList("clock", &a->clock,
               "CAM,OFFSET_MS[,DRIFT_PPM]: CAM's clock reads the true time + OFFSET_MS + DRIFT_PPM * 1e-6 * "
               "(time since the first frame): its detections' utime, or with images CAM_timestamps.csv "
               "(rig.yaml timestamps:); ground_truth.yaml clocks: (repeatable)");
  args.AddFlag("quiet", &a->quiet, "no progress or summary output");
  args.AddEpilog(
      "\nA marker is detected (detections-only) when all 4 corners are in the image, it faces the camera "
      "within "
      "80 degrees of head-on, is not occluded and spans at least 8 px.\n"
      "Frames: the rig frame of ground_truth.yaml is a world frame (origin at the circle's centre, z up), "
      "the "
      "object frame the object's body frame; mcmt-eval aligns estimates rigidly.\n"
      "examples:\n"
      "  mcmt-sim --out /tmp/s --object four_sided --cameras 5 --frames 300\n"
      "  mcmt-sim --out /tmp/d --detections-only --frames 10000 --cameras 8 --corner-noise-px 0.2\n"
      "  mcmt-sim --out /tmp/q --detections-only --intrinsics-error cam1,3,8,-6,0.03 --clock cam2,12,100 "
      "--max-speed-m-s 1\n");
}

// Every option once: its name, value, help (with its unit) and check, in --help's order.
void DeclareOptions(mcmt::ArgParser* p, SimArgs* a) {
  DeclareSceneOptions(p, a);
  DeclareImagingOptions(p, a);
  DeclareSessionOptions(p, a);
}

// The object, rig and motion: names read, the radius's proportions applied.
void SceneFrom(const SimArgs& a, mcmt::sim::DatasetOptions* o) {
  using namespace mcmt;
  o->out_dir = a.out;
  o->dictionary = a.dictionary;
  try {
    o->object.kind = sim::ObjectKindFromName(a.object);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("--object: ") + e.what());
  }
  try {
    LoadDictionary(a.dictionary);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("--dictionary: ") + e.what());
  }
  o->object.marker_size = a.marker_size;
  o->object.seed = static_cast<uint64_t>(a.seed);
  o->rig.num_cameras = a.cameras;
  o->rig.radius = a.radius;
  o->rig.camera_height = a.camera_height != -1.0 ? a.camera_height : 0.5 * a.radius;
  ParseImageSize(a.image_size, &o->rig.width, &o->rig.height);
  o->rig.hfov_deg = a.hfov;
  o->rig.distortion = DistortionModelFromName(a.distortion);
  o->rig.intrinsics_spread = a.intrinsics_spread;
  o->rig.seed = static_cast<uint64_t>(a.seed);
  o->trajectory.frames = a.frames;
  o->trajectory.fps = a.fps;
  o->trajectory.seed = static_cast<uint64_t>(a.seed);
  o->trajectory.still_frames = a.still_frames;
  o->trajectory.position_radius = 0.15 * a.radius;
  o->trajectory.vertical_range = 0.08 * a.radius;
  o->trajectory.max_tilt_deg = a.max_tilt;
  o->trajectory.turns = a.turns;
  if (a.max_speed != 0.0) {  // checked here (one line naming the option); each body's motion its own scale
    o->trajectory.time_scale = sim::TimeScaleForMaxSpeed(o->trajectory, a.max_speed);
    o->trajectory.max_speed_m_s = a.max_speed;
  }
}

// The imaging: the options as given, or (imaging random) a condition per camera drawn from the seed, one
// line per camera in `imaging_summary`.
mcmt::sim::RenderOptions ImagingFrom(const SimArgs& a, std::vector<std::string>* imaging_summary) {
  mcmt::sim::RenderOptions r;
  r.noise_sigma = a.noise;
  r.blur_sigma = a.blur;
  r.motion_blur_samples = a.motion_blur ? 5 : 0;
  r.supersampling = a.supersampling;
  r.quiet_zone_cells = a.quiet_zone;
  r.textured_background = !a.plain_bg;
  r.bgr = a.bgr;
  r.seed = static_cast<uint64_t>(a.seed);
  r.surface_albedo = a.surface_albedo;
  r.surface_texture = a.surface_texture;
  r.shading = a.shading;
  r.lighting_gradient = a.gradient;
  r.vignetting = a.vignetting;
  r.defocus_radius = a.defocus;
  r.shot_noise = a.shot_noise;
  r.gamma = a.gamma;
  r.sharpen = a.sharpen;
  r.jpeg_quality = a.jpeg_quality;
  if (a.imaging == "random")
    r = mcmt::sim::RandomImaging(r, a.cameras, static_cast<uint64_t>(a.seed), imaging_summary);
  return r;
}

// What goes wrong in the session: detections' noise and losses, moved, late, mis-calibrated cameras and
// their clocks (camera names checked against the rig's).
void FaultsFrom(const SimArgs& a, mcmt::sim::DatasetOptions* o) {
  using namespace mcmt;
  o->detections.corner_noise_px = a.corner_noise;
  o->detections.miss_rate = a.miss_rate;
  o->detections.false_rate = a.false_rate;
  o->detections.drop_rate = a.drop_rate;
  for (const std::string& m : a.move_camera) o->moves.push_back(sim::ParseCameraMove(m));
  for (const std::string& e : a.intrinsics_error) {
    const auto parsed = sim::ParseIntrinsicsError(e);
    if (!o->intrinsics_errors.emplace(parsed).second)
      throw std::invalid_argument("--intrinsics-error: camera '" + parsed.first + "' given twice");
  }
  for (const std::string& c : a.clock) {
    const auto parsed = sim::ParseCameraClock(c);
    if (!o->clocks.emplace(parsed).second)
      throw std::invalid_argument("--clock: camera '" + parsed.first + "' given twice");
  }
  const int named = a.cameras + (a.add_camera >= 0 ? 1 : 0);  // cam0 .. cam<named - 1>
  auto check_name = [&](const std::string& option, const std::string& name) {
    for (int k = 0; k < named; ++k)
      if (name == "cam" + std::to_string(k)) return;
    throw std::invalid_argument(option + ": no camera named '" + name + "' (cam0 .. cam" +
                                std::to_string(named - 1) + ")");
  };
  for (const auto& entry : o->intrinsics_errors) check_name("--intrinsics-error", entry.first);
  for (const auto& entry : o->clocks) check_name("--clock", entry.first);
  o->add_camera_frame = a.add_camera;
}

void CreateFolder(const std::string& out) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec || !std::filesystem::is_directory(out))
    throw std::runtime_error("--out: cannot create folder '" + out + "'" + (ec ? ": " + ec.message() : ""));
}

int Main(int argc, char** argv) {
  using namespace mcmt;
  SimArgs a;
  ArgParser args(
      "mcmt-sim",
      "Simulates a multi-camera marker session: cameras on a circle looking at its centre, an object "
      "covered with ArUco markers moving smoothly in their common view. Writes DIR/rig.yaml (ready for "
      "the other processes), DIR/camK.yml intrinsics, DIR/ground_truth.yaml and either rendered images "
      "(DIR/camK/000000.png ..., or DIR/camK.mp4 with --video) or, with --detections-only, "
      "DIR/detections.lcmlog.");
  DeclareOptions(&args, &a);
  int exit_code = 0;
  if (!args.Parse(argc, argv, &exit_code)) return exit_code;

  sim::DatasetOptions o;
  SceneFrom(a, &o);
  std::vector<std::string> imaging_summary;
  o.render = ImagingFrom(a, &imaging_summary);
  FaultsFrom(a, &o);
  if (a.video && a.detections_only)
    throw std::invalid_argument("--video and --detections-only exclude each other");
  o.detections_only = a.detections_only;
  o.video = a.video;
  o.threads = a.threads;
  o.quiet = a.quiet;
  CreateFolder(a.out);

  std::mutex progress_mutex;  // images: a bar on a terminal, a line every 5 s otherwise
  std::unique_ptr<Progress> progress;
  if (!a.quiet && !a.detections_only) progress = std::make_unique<Progress>("mcmt-sim", 0, "images");
  if (progress)
    o.progress = [&](int64_t done, int64_t total) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      progress->SetTotal(total);
      progress->Update(done);
    };
  const sim::DatasetSummary s = a.scene == "bodies" ? sim::GenerateBodiesDataset(o) : sim::GenerateDataset(o);
  if (progress) progress->Finish();
  if (a.quiet) return 0;
  for (size_t k = 0; k < imaging_summary.size(); ++k)
    std::printf("mcmt-sim: cam%zu imaging: %s\n", k, imaging_summary[k].c_str());
  std::printf("mcmt-sim: %s, %zu cameras, %zu markers, %zu frames -> %s (%s, %.2f s)\n",
              s.truth.object.c_str(), s.truth.cameras.size(), s.truth.markers.size(), s.truth.frames.size(),
              a.out.c_str(),
              a.detections_only
                  ? (std::to_string(s.messages_written) + " detection messages").c_str()
                  : (std::to_string(s.images_written) + (a.video ? " video frames" : " images")).c_str(),
              s.seconds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-sim", [&]() { return Main(argc, argv); });
}
