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

std::string Num(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%g", v);
  return buffer;
}

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

void CheckRate(const char* name, double value, double max) {
  if (!(value >= 0 && value <= max))
    throw std::invalid_argument(std::string("--") + name + ": expected 0.." + Num(max) + ", got " +
                                Num(value));
}

int Main(int argc, char** argv) {
  using namespace mcmt;
  std::string out, object = "four_sided", dictionary = "DICT_6X6_250", image_size = "640x480",
                   distortion = "none";
  int cameras = 5, frames = 300, still_frames = 0, threads = 1, quiet_zone = 1, supersampling = 0;
  long long seed = 1;
  double radius = 1.0, camera_height = -1.0, fps = 30.0, marker_size = -1.0, hfov = 60.0, noise = 2.0,
         blur = 0.0;
  double corner_noise = 0.1, miss_rate = 0.0, false_rate = 0.0, drop_rate = 0.0, intrinsics_spread = 0.0;
  double max_tilt = 35.0, turns = 1.5;
  std::string imaging = "default", scene = "object";
  double surface_albedo = -1.0, surface_texture = 0.0, shading = 0.3, gradient = 0.3, vignetting = 0.0,
         defocus = 0.0, shot_noise = 0.0, gamma = 1.0, sharpen = 0.0;
  int jpeg_quality = 0;
  std::vector<std::string> move_camera, intrinsics_error, clock;
  int add_camera = -1;
  double max_speed = 0.0;
  bool motion_blur = false, video = false, detections_only = false, bgr = false, quiet = false,
       plain_bg = false;

  ArgParser args(
      "mcmt-sim",
      "Simulates a multi-camera marker session: cameras on a circle looking at its centre, an object "
      "covered with ArUco markers moving smoothly in their common view. Writes DIR/rig.yaml (ready for "
      "the other processes), DIR/camK.yml intrinsics, DIR/ground_truth.yaml and either rendered images "
      "(DIR/camK/000000.png ..., or DIR/camK.mp4 with --video) or, with --detections-only, "
      "DIR/detections.lcmlog.");
  args.AddString("out", &out,
                 "output folder (created if needed; numbered frames of an earlier session in its camera "
                 "folders are removed)",
                 true);
  args.AddString("object", &object, "four_sided | box | pentagon | cube | board");
  args.AddString(
      "scene", &scene,
      "object: one object (--object) | bodies: a static floor board and two moving objects, tool "
      "and patient, that cross and occlude each other (with --detections-only; rig.yaml lists "
      "objects:, ground_truth_<body>.yaml per body; --intrinsics-error, --clock and --max-speed-m-s as "
      "for object, each moving body at that top speed)");
  args.AddInt("cameras", &cameras, "number of cameras on the circle (named cam0 .. camN-1)");
  args.AddDouble("radius", &radius, "circle radius, metres");
  args.AddDouble("camera-height", &camera_height,
                 "camera height above the object's mean height, metres (-1: half the radius)");
  args.AddInt("frames", &frames, "number of frames");
  args.AddDouble("fps", &fps, "frame rate (frame k has utime 1e12 + round(k * 1e6 / fps) us)");
  args.AddInt64("seed", &seed, "random seed (same seed and options: same bytes)");
  args.AddDouble("marker-size", &marker_size, "marker side, metres (-1: 0.04, pentagon 0.025)");
  args.AddString("dictionary", &dictionary, "ArUco dictionary name or dictionary file");
  args.AddString("image-size", &image_size, "WIDTHxHEIGHT");
  args.AddDouble("hfov-deg", &hfov, "horizontal field of view of the pinhole part, degrees");
  args.AddString("distortion", &distortion, "none | radtan | fisheye (mild lens distortion)");
  args.AddDouble("intrinsics-spread", &intrinsics_spread,
                 "per-camera relative spread of focal length, principal point and distortion (0: identical)");
  args.AddDouble("noise", &noise, "image noise sigma, gray levels");
  args.AddDouble("blur", &blur, "Gaussian blur sigma, pixels (0: none)");
  args.AddFlag("motion-blur", &motion_blur, "average 5 poses over half a frame interval (5x slower)");
  args.AddInt("supersampling", &supersampling, "0: exact area anti-aliasing; S: SxS point samples per pixel");
  args.AddInt("quiet-zone", &quiet_zone, "white margin around each marker, in marker cells (0..2 typical)");
  args.AddFlag("plain-background", &plain_bg, "uniform gray background instead of a textured one");
  args.AddString("imaging", &imaging,
                 "default | random: a different imaging condition per camera drawn from --seed (margin, "
                 "surface, shading, gradient, vignetting, blur or defocus, noise, gamma, sharpening, JPEG; "
                 "the imaging options below are then ignored)");
  args.AddDouble("surface-albedo", &surface_albedo,
                 "reflectance 0..1 of the surface the markers are glued on (-1: the object's own)");
  args.AddDouble("surface-texture", &surface_texture,
                 "relative amplitude 0..1 of the surface's grain (0: plain)");
  args.AddDouble("shading", &shading, "relative brightness change between faces by their normal, 0..1");
  args.AddDouble("gradient", &gradient, "relative brightness change of the light across the image, 0..1");
  args.AddDouble("vignetting", &vignetting, "relative fall-off of the light at the image corners, 0..1");
  args.AddDouble("defocus", &defocus, "defocus blur: disc radius, pixels (0: none)");
  args.AddDouble("shot-noise", &shot_noise, "photon noise: variance added per linear gray level (0: none)");
  args.AddDouble("gamma", &gamma, "encoding gamma: written value 255 (v / 255)^(1 / gamma) (1: linear)");
  args.AddDouble("sharpen", &sharpen, "camera sharpening: unsharp mask amount, sigma 1 px (0: none)");
  args.AddInt("jpeg-quality", &jpeg_quality,
              "JPEG compression of every frame at this quality 1..100 (0: none)");
  args.AddFlag("bgr", &bgr, "write 3-channel images");
  args.AddFlag("video", &video, "write DIR/camK.mp4 instead of PNG folders");
  args.AddInt("still-frames", &still_frames, "length of each of two still segments, frames (0: none)");
  args.AddDouble("max-tilt-deg", &max_tilt, "largest tilt of the object from upright, degrees");
  args.AddDouble("turns", &turns, "turns of the object about the vertical over the sequence");
  args.AddDouble("max-speed-m-s", &max_speed,
                 "faster (or slower) motion: the object's centre reaches this top speed, m/s (the motion's "
                 "time scaled; 0: the default motion)");
  args.AddInt("threads", &threads, "cameras rendered in parallel");
  args.AddFlag(
      "detections-only", &detections_only,
      "skip rendering; write DIR/detections.lcmlog (detections_t on MCMT_DETECTIONS_CAMK, event time = "
      "message utime)");
  args.AddDouble("corner-noise-px", &corner_noise, "detections-only: Gaussian corner noise sigma, pixels");
  args.AddDouble("miss-rate", &miss_rate, "detections-only: probability a visible marker is not detected");
  args.AddDouble("false-rate", &false_rate,
                 "detections-only: mean number of false detections (ids not on the object) per camera frame");
  args.AddDouble("drop-rate", &drop_rate, "detections-only: probability a camera frame is not published");
  args.AddList("move-camera", &move_camera,
               "CAM,FRAME,ROT_DEG,TRANS_MM: the camera is bumped at FRAME: turned by ROT_DEG degrees about "
               "its y axis and shifted by TRANS_MM millimetres along its x axis (FRAME 0: moved before the "
               "session, a session for mcmt-mapper --map; repeatable; ground_truth.yaml moves:)");
  args.AddInt("add-camera", &add_camera,
              "FRAME: one more camera (cam<N>, on the circle halfway between cam0 and cam1) that publishes "
              "from FRAME on (-1: none; ground_truth.yaml late_cameras:)");
  args.AddList("intrinsics-error", &intrinsics_error,
               "CAM,FOCAL_PCT,CX_PX,CY_PX[,K1]: the rig is given wrong intrinsics for CAM (camK.yml and the "
               "detections' camera model: focal length off by FOCAL_PCT %, principal point by CX_PX, CY_PX "
               "pixels, k1 by K1); images, corners and ground_truth.yaml stay true (repeatable)");
  args.AddList("clock", &clock,
               "CAM,OFFSET_MS[,DRIFT_PPM]: CAM's clock reads the true time + OFFSET_MS + DRIFT_PPM * 1e-6 * "
               "(time since the first frame): its detections' utime, or with images CAM_timestamps.csv "
               "(rig.yaml timestamps:); ground_truth.yaml clocks: (repeatable)");
  args.AddFlag("quiet", &quiet, "no progress or summary output");
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
  int exit_code = 0;
  if (!args.Parse(argc, argv, &exit_code)) return exit_code;

  sim::DatasetOptions o;
  o.out_dir = out;
  o.dictionary = dictionary;
  try {
    o.object.kind = sim::ObjectKindFromName(object);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("--object: ") + e.what());
  }
  try {
    LoadDictionary(dictionary);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("--dictionary: ") + e.what());
  }
  if (marker_size != -1.0 && !(marker_size > 0.001 && marker_size < 10))
    throw std::invalid_argument("--marker-size: expected 0.001..10 m, got " + Num(marker_size));
  o.object.marker_size = marker_size;
  o.object.seed = static_cast<uint64_t>(seed);
  if (cameras < 1 || cameras > 64)
    throw std::invalid_argument("--cameras: expected 1..64, got " + std::to_string(cameras));
  if (!(radius >= 0.1 && radius <= 100))
    throw std::invalid_argument("--radius: expected 0.1..100 m, got " + Num(radius));
  o.rig.num_cameras = cameras;
  o.rig.radius = radius;
  o.rig.camera_height = camera_height != -1.0 ? camera_height : 0.5 * radius;
  ParseImageSize(image_size, &o.rig.width, &o.rig.height);
  if (!(hfov > 5 && hfov < 170)) throw std::invalid_argument("--hfov-deg: expected 5..170, got " + Num(hfov));
  o.rig.hfov_deg = hfov;
  try {
    o.rig.distortion = DistortionModelFromName(distortion);
  } catch (const std::exception&) {
    throw std::invalid_argument("--distortion: expected none, radtan or fisheye, got '" + distortion + "'");
  }
  if (!(intrinsics_spread >= 0 && intrinsics_spread <= 0.2))
    throw std::invalid_argument("--intrinsics-spread: expected 0..0.2");
  o.rig.intrinsics_spread = intrinsics_spread;
  o.rig.seed = static_cast<uint64_t>(seed);
  if (frames < 1 || frames > 10000000)
    throw std::invalid_argument("--frames: expected >= 1, got " + std::to_string(frames));
  if (!(fps > 0 && fps <= 10000)) throw std::invalid_argument("--fps: expected 0..10000, got " + Num(fps));
  if (still_frames < 0) throw std::invalid_argument("--still-frames: expected >= 0");
  o.trajectory.frames = frames;
  o.trajectory.fps = fps;
  o.trajectory.seed = static_cast<uint64_t>(seed);
  o.trajectory.still_frames = still_frames;
  o.trajectory.position_radius = 0.15 * radius;
  o.trajectory.vertical_range = 0.08 * radius;
  if (!(max_tilt >= 0 && max_tilt <= 90)) throw std::invalid_argument("--max-tilt-deg: expected 0..90");
  o.trajectory.max_tilt_deg = max_tilt;
  o.trajectory.turns = turns;
  if (max_speed != 0.0) {  // checked here (one line naming the option); each body's motion its own scale
    o.trajectory.time_scale = sim::TimeScaleForMaxSpeed(o.trajectory, max_speed);
    o.trajectory.max_speed_m_s = max_speed;
  }
  if (!(noise >= 0 && noise <= 100)) throw std::invalid_argument("--noise: expected 0..100 gray levels");
  if (!(blur >= 0 && blur <= 50)) throw std::invalid_argument("--blur: expected 0..50 px");
  if (supersampling < 0 || supersampling > 16) throw std::invalid_argument("--supersampling: expected 0..16");
  if (quiet_zone < 0 || quiet_zone > 10) throw std::invalid_argument("--quiet-zone: expected 0..10 cells");
  o.render.noise_sigma = noise;
  o.render.blur_sigma = blur;
  o.render.motion_blur_samples = motion_blur ? 5 : 0;
  o.render.supersampling = supersampling;
  o.render.quiet_zone_cells = quiet_zone;
  o.render.textured_background = !plain_bg;
  o.render.bgr = bgr;
  o.render.seed = static_cast<uint64_t>(seed);
  if (!(surface_albedo == -1.0 || (surface_albedo >= 0 && surface_albedo <= 1)))
    throw std::invalid_argument("--surface-albedo: expected 0..1 or -1, got " + Num(surface_albedo));
  CheckRate("surface-texture", surface_texture, 1.0);
  CheckRate("shading", shading, 1.0);
  CheckRate("gradient", gradient, 1.0);
  CheckRate("vignetting", vignetting, 1.0);
  CheckRate("defocus", defocus, 50.0);
  CheckRate("shot-noise", shot_noise, 10.0);
  CheckRate("sharpen", sharpen, 5.0);
  if (!(gamma >= 0.2 && gamma <= 5))
    throw std::invalid_argument("--gamma: expected 0.2..5, got " + Num(gamma));
  if (jpeg_quality < 0 || jpeg_quality > 100)
    throw std::invalid_argument("--jpeg-quality: expected 0..100, got " + std::to_string(jpeg_quality));
  o.render.surface_albedo = surface_albedo;
  o.render.surface_texture = surface_texture;
  o.render.shading = shading;
  o.render.lighting_gradient = gradient;
  o.render.vignetting = vignetting;
  o.render.defocus_radius = defocus;
  o.render.shot_noise = shot_noise;
  o.render.gamma = gamma;
  o.render.sharpen = sharpen;
  o.render.jpeg_quality = jpeg_quality;
  std::vector<std::string> imaging_summary;
  if (imaging == "random")
    o.render = sim::RandomImaging(o.render, cameras, static_cast<uint64_t>(seed), &imaging_summary);
  else if (imaging != "default")
    throw std::invalid_argument("--imaging: expected default or random, got '" + imaging + "'");
  if (!(corner_noise >= 0 && corner_noise <= 100))
    throw std::invalid_argument("--corner-noise-px: expected 0..100");
  CheckRate("miss-rate", miss_rate, 1.0);
  CheckRate("drop-rate", drop_rate, 1.0);
  CheckRate("false-rate", false_rate, 100.0);
  o.detections.corner_noise_px = corner_noise;
  o.detections.miss_rate = miss_rate;
  o.detections.false_rate = false_rate;
  o.detections.drop_rate = drop_rate;
  o.detections_only = detections_only;
  for (const std::string& m : move_camera) o.moves.push_back(sim::ParseCameraMove(m));
  for (const std::string& e : intrinsics_error) {
    const auto parsed = sim::ParseIntrinsicsError(e);
    if (!o.intrinsics_errors.emplace(parsed).second)
      throw std::invalid_argument("--intrinsics-error: camera '" + parsed.first + "' given twice");
  }
  for (const std::string& c : clock) {
    const auto parsed = sim::ParseCameraClock(c);
    if (!o.clocks.emplace(parsed).second)
      throw std::invalid_argument("--clock: camera '" + parsed.first + "' given twice");
  }
  const int named = cameras + (add_camera >= 0 ? 1 : 0);  // cam0 .. cam<named - 1>
  auto check_name = [&](const std::string& option, const std::string& name) {
    for (int k = 0; k < named; ++k)
      if (name == "cam" + std::to_string(k)) return;
    throw std::invalid_argument(option + ": no camera named '" + name + "' (cam0 .. cam" +
                                std::to_string(named - 1) + ")");
  };
  for (const auto& entry : o.intrinsics_errors) check_name("--intrinsics-error", entry.first);
  for (const auto& entry : o.clocks) check_name("--clock", entry.first);
  if (add_camera < -1) throw std::invalid_argument("--add-camera: expected a frame >= 0 (-1: none)");
  o.add_camera_frame = add_camera;
  if (video && detections_only)
    throw std::invalid_argument("--video and --detections-only exclude each other");
  o.video = video;
  if (threads < 1 || threads > 64) throw std::invalid_argument("--threads: expected 1..64");
  o.threads = threads;
  o.quiet = quiet;
  {
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec || !std::filesystem::is_directory(out))
      throw std::runtime_error("--out: cannot create folder '" + out + "'" + (ec ? ": " + ec.message() : ""));
  }

  std::mutex progress_mutex;  // images: a bar on a terminal, a line every 5 s otherwise
  std::unique_ptr<Progress> progress;
  if (!quiet && !detections_only) progress = std::make_unique<Progress>("mcmt-sim", 0, "images");
  if (progress)
    o.progress = [&](int64_t done, int64_t total) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      progress->SetTotal(total);
      progress->Update(done);
    };
  if (scene != "object" && scene != "bodies")
    throw std::invalid_argument("--scene: expected object or bodies, got '" + scene + "'");
  const sim::DatasetSummary s = scene == "bodies" ? sim::GenerateBodiesDataset(o) : sim::GenerateDataset(o);
  if (progress) progress->Finish();
  if (!quiet)
    for (size_t k = 0; k < imaging_summary.size(); ++k)
      std::printf("mcmt-sim: cam%zu imaging: %s\n", k, imaging_summary[k].c_str());
  if (!quiet) {
    std::printf(
        "mcmt-sim: %s, %zu cameras, %zu markers, %zu frames -> %s (%s, %.2f s)\n", s.truth.object.c_str(),
        s.truth.cameras.size(), s.truth.markers.size(), s.truth.frames.size(), out.c_str(),
        detections_only ? (std::to_string(s.messages_written) + " detection messages").c_str()
                        : (std::to_string(s.images_written) + (video ? " video frames" : " images")).c_str(),
        s.seconds);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-sim", [&]() { return Main(argc, argv); });
}
