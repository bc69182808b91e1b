// mcmt_sim: synthetic rigs, objects, trajectories, an exact image renderer, ground-truth projections,
// simulated detections and ground_truth.yaml ("COLMAP's synthetic dataset generator" for mcmt).
//
// Conventions (same as the rest of mcmt):
// - Transforms are named a_from_b (p_a = a_from_b * p_b). The simulator's rig frame is a world frame:
//   origin at the centre of the camera circle, z up; cameras look at the origin. The simulator's object
//   frame is the object's body frame (its centre), not a marker frame. An estimator chooses its own
//   reference camera / marker; mcmt-eval aligns rigidly before comparing.
// - Pixel centres are at integer coordinates (OpenCV's convention): pixel (0, 0) covers [-0.5, 0.5]^2.
// - Marker corners in the marker frame in ArUco order (core/marker.h); z points out of the face. The
//   marker side s is the side of the black square including its one-cell black border (as ArUco);
//   a white quiet zone of `quiet_zone_cells` cells surrounds it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/camera.h"
#include "core/marker.h"
#include "core/se3.h"
#include "mcmt/detections_t.hpp"

namespace mcmt {
namespace sim {

// ---------------------------------------------------------------------------------------------
// Rig

struct SimCamera {
  std::string name;  // "cam0", "cam1", ...
  CameraModel model;
  Rigid3 rig_from_cam = Rigid3::Identity();
};

struct RigOptions {
  int num_cameras = 5;
  double radius = 1.0;          // circle radius, metres
  double camera_height = 0.5;   // height of the cameras above the circle's centre plane (z), metres
  double look_at_height = 0.0;  // cameras look at (0, 0, look_at_height)
  int width = 640;
  int height = 480;
  double hfov_deg = 60.0;                               // horizontal field of view (of the pinhole part)
  DistortionModel distortion = DistortionModel::kNone;  // radtan: k1 k2 p1 p2 k3; fisheye: k1..k4
  // Per-camera differences: relative spread of focal length and principal point offset (px), and of
  // the distortion coefficients, drawn with `seed`. 0: all cameras identical.
  double intrinsics_spread = 0.0;
  uint64_t seed = 1;
};

// Cameras evenly spaced on the circle (cam0 at angle 0, on +x), each looking at the look-at point,
// image x axis horizontal. Throws std::invalid_argument on bad options (naming the option).
std::vector<SimCamera> MakeRig(const RigOptions& options);
// The default distortion coefficients used for a model (mild, like a typical webcam / fisheye lens).
std::vector<double> DefaultDistortion(DistortionModel model);

// ---------------------------------------------------------------------------------------------
// Object: markers on an opaque body made of convex planar faces.

struct SimMarker {
  int id = 0;
  double size = 0.04;  // side, metres
  Rigid3 object_from_marker = Rigid3::Identity();
};

struct SimFace {  // one convex planar polygon of the opaque body, counter-clockwise seen from outside
  std::vector<Eigen::Vector3d> vertices;  // object frame
  double albedo = 0.55;                   // reflectance 0..1
};

struct SimObject {
  std::string name;  // "four_sided", "box", ...
  std::vector<SimMarker> markers;
  std::vector<SimFace> faces;
  double radius = 0.1;  // radius of a sphere around the object origin holding the whole body, metres
  const SimMarker* FindMarker(int id) const;
  MarkerSizes Sizes() const;  // default = the most common size, overrides for the others
};

enum class ObjectKind { kFourSided, kBox, kPentagon, kCube, kBoard };
const std::vector<std::string>& ObjectKindNames();       // "four_sided", "box", "pentagon", "cube", "board"
ObjectKind ObjectKindFromName(const std::string& name);  // throws std::invalid_argument listing names

struct ObjectOptions {
  ObjectKind kind = ObjectKind::kFourSided;
  double marker_size = 0.04;  // metres (pentagon: default 0.025 when marker_size <= 0)
  int first_id = 0;           // ids first_id, first_id + 1, ...
  uint64_t seed = 1;          // box: random placement
  // cube: a grid of markers on every face, face_columns x face_rows (ids row by row, face by face).
  int face_columns = 1;
  int face_rows = 1;
};
// four_sided: a square prism 1.75 marker sides wide and high (7 cm for 4 cm markers) with one marker on each
//             of its four sides, id 0..3.
// box:        a box of 4.5 x 3.5 x 2.5 marker sides (18x14x10 cm) with 8 markers at random places / in-plane
//             rotations on its faces (room for a one-cell quiet zone of a 6x6 dictionary).
// pentagon:   a pentagonal prism (radius 6 cm) with two small markers on each side (10 markers, 2.5 cm).
// cube:       a cube with a face_columns x face_rows grid of markers on each face (default one, 6 markers);
//             markers a quarter side apart, side = n markers + (n - 1) gaps + 2 cm, n = max(columns, rows).
// board:      a printed sheet on a thin board: a 3x3 grid of markers on its front face, white paper between
//             them (the board's albedo is the paper's, RenderOptions::white_level / 255).
SimObject MakeObject(const ObjectOptions& options);

// ---------------------------------------------------------------------------------------------
// Trajectory

struct SimFrame {
  int64_t seq = 0;
  int64_t utime = 0;
  Rigid3 rig_from_object = Rigid3::Identity();
};

// The first frame's utime (1e12 us, i.e. 1'000'000'000'000) and frame k's: kStartUtime + round(k * 1e6 /
// fps).
constexpr int64_t kStartUtime = 1000000000000LL;
int64_t FrameUtime(int64_t frame, double fps);

struct TrajectoryOptions {
  int frames = 300;
  double fps = 30.0;
  uint64_t seed = 1;
  // Extent of the motion around the look-at point: horizontal radius and vertical half-range, metres.
  // <= 0: chosen from the rig (a fraction of the circle radius, so the object stays in every view).
  double position_radius = -1.0;
  double vertical_range = -1.0;
  double look_at_height = 0.0;  // centre of the motion (z)
  double max_tilt_deg = 35.0;   // tilt of the object's z axis from vertical
  double turns = 1.5;           // full turns about the vertical over the sequence (every face is seen)
  // Still segments: `still_segments` segments of `still_frames` frames each where the object does not move.
  int still_frames = 0;
  int still_segments = 2;
  // Faster (or slower) motion: the motion's own time runs time_scale times as fast as the frames' (the
  // turns about the vertical stay `turns` over the sequence). max_speed_m_s > 0 replaces time_scale by the
  // one that makes the object centre's top speed this (TrajectoryMaxSpeed).
  double time_scale = 1.0;
  double max_speed_m_s = 0.0;
};

// A smooth random 6-DoF trajectory (sums of random sinusoids) inside the cameras' common view, turning
// about the vertical so every side faces every camera. Deterministic for a seed.
std::vector<SimFrame> MakeTrajectory(const TrajectoryOptions& options);
// The top speed of the object's centre (m/s) along MakeTrajectory(options) at options.time_scale (its
// max_speed_m_s ignored), sampled 20 times per frame interval.
double TrajectoryMaxSpeed(const TrajectoryOptions& options);
// The time_scale that gives the object's centre the top speed max_speed_m_s (bisection; throws
// std::invalid_argument naming --max-speed-m-s when it cannot be reached).
double TimeScaleForMaxSpeed(TrajectoryOptions options, double max_speed_m_s);

// ---------------------------------------------------------------------------------------------
// Ground-truth projections

struct MarkerView {
  int id = 0;
  MarkerCorners2d corners;        // distorted pixels, ArUco order (valid when all corners are in front)
  bool in_front = false;          // every corner has z > 0 in the camera frame
  bool in_image = false;          // all 4 corners inside the image (pixel centres 0..w-1, 0..h-1)
  bool front_facing = false;      // the face points towards the camera
  bool occluded = false;          // part of the marker (corners, edges, centre) is hidden by the body or
                                  // another marker
  bool fully_visible = false;     // in_front && in_image && front_facing && !occluded
  double view_angle_deg = 180.0;  // angle between the marker normal and the direction to the camera
  double size_px = 0.0;           // apparent side: sqrt of the projected quadrilateral's area, pixels
  double depth = 0.0;             // z of the marker centre in the camera frame, metres
  Rigid3 cam_from_marker = Rigid3::Identity();
};

// Every marker of the object, seen by one camera, with the object at rig_from_object.
std::vector<MarkerView> ProjectMarkers(const SimCamera& camera, const SimObject& object,
                                       const Rigid3& rig_from_object);

// ---------------------------------------------------------------------------------------------
// Rendering

struct RenderOptions {
  // 0 (default): exact anti-aliasing: every pixel gets the exact area-weighted mean of the scene over
  // its square footprint (box filter; the footprint mapped onto each planar patch by the local affine
  // map at the pixel centre, exact up to second-order perspective terms, < 1e-3 px of edge shift).
  // S >= 1: plain SxS point supersampling instead (for comparison).
  int supersampling = 0;
  double noise_sigma = 2.0;  // Gaussian noise, gray levels
  double blur_sigma = 0.0;   // Gaussian blur of the whole image (optics), pixels; 0: none
  // > 1: average this many poses over the exposure (needs the previous pose). The exposure ends at the
  // frame's pose (the ground truth), so a detector sees about the pose at mid-exposure, exposure_fraction / 2
  // frames earlier: compare with that pose when measuring corner accuracy under motion blur.
  int motion_blur_samples = 0;
  double exposure_fraction = 0.5;  // exposure as a fraction of the frame interval (motion blur)
  bool textured_background = true;
  double background_level = 128.0;  // gray level of the uniform background when not textured
  bool solid_markers = false;       // draw markers as plain black squares (tests of rendering exactness)
  double lighting_gradient = 0.3;   // relative brightness change across the image (0: uniform)
  double shading = 0.3;             // relative brightness change between faces by their normal (0: flat)
  double black_level = 25.0;        // gray level of the markers' black ink under full light
  double white_level = 225.0;       // gray level of the white paper under full light
  int quiet_zone_cells = 1;         // width of the white margin around each marker, in marker cells
  bool bgr = false;                 // 3-channel output (gray replicated with a slight tint)
  bool inverted = false;            // white-on-black markers
  uint64_t seed = 1;                // background texture and noise (noise also varies with frame and camera)

  // The surface the prints are glued on (the body's faces): reflectance (< 0: each face's own albedo),
  // the relative amplitude of a wood-like grain (0: plain) and its period (metres), and a colour tint
  // (B, G, R factors of the reflectance; the gray image is their Rec. 601 mean).
  double surface_albedo = -1.0;
  double surface_texture = 0.0;
  double surface_texture_period = 0.012;
  double surface_tint[3] = {1.0, 1.0, 1.0};
  // The camera pipeline, after the scene's image in linear light (exact area coverage per pixel):
  // optics blur (blur_sigma, then a defocus disc of this radius, px), vignetting (relative fall-off of
  // the light at the image corners, r^2 law), sensor noise (noise_sigma: read noise in linear gray
  // levels; shot_noise: variance added per linear gray level), gamma encoding 255 (v / 255)^(1 / gamma),
  // sharpening (unsharp mask of this amount, sigma 1 px, on encoded values), 8-bit quantisation and JPEG
  // compression at jpeg_quality (0: none).
  double defocus_radius = 0.0;
  double vignetting = 0.0;
  double shot_noise = 0.0;
  double gamma = 1.0;
  double sharpen = 0.0;
  int jpeg_quality = 0;
  // Per-camera imaging (index = camera index): where present it replaces these options for that camera
  // (RandomImaging fills it).
  std::vector<RenderOptions> cameras;
  const RenderOptions& ForCamera(int index) const {
    return index >= 0 && index < static_cast<int>(cameras.size()) ? cameras[index] : *this;
  }
};

// `--imaging random`: a different imaging condition per camera drawn from `seed`, over `base`: per
// session the print's margin (0-2 cells), the surface (reflectance 0.05-0.9, at least 0.3 without a
// margin; tint, grain) and the faces' shading; per camera the light gradient, vignetting, Gaussian or defocus
// blur, noise, gamma, sharpening and JPEG quality. Deterministic for a seed. `summary` (optional) gets one
// line per camera.
RenderOptions RandomImaging(const RenderOptions& base, int cameras, uint64_t seed,
                            std::vector<std::string>* summary = nullptr);
// One line describing a camera's imaging (units included).
std::string DescribeImaging(const RenderOptions& o);

// Renders marker images of one dictionary. Thread-compatible (const methods are thread-safe).
class Renderer {
 public:
  // dictionary: a name or file as core/dictionary.h LoadDictionary accepts. Throws on unknown names
  // or marker ids out of the dictionary.
  Renderer(const SimObject& object, const std::string& dictionary, const RenderOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // One camera's 8-bit image (CV_8UC1, or CV_8UC3 when options.bgr) of the object at rig_from_object.
  // camera_index and frame seed the noise. previous_rig_from_object (optional) is the pose one frame
  // earlier, used for motion blur.
  cv::Mat Render(const SimCamera& camera, int camera_index, int64_t frame, const Rigid3& rig_from_object,
                 const Rigid3* previous_rig_from_object = nullptr) const;

  // The noise-free, blur-free image as float gray levels (0..255), for tests of rendering exactness.
  cv::Mat RenderIdeal(const SimCamera& camera, int camera_index, const Rigid3& rig_from_object) const;

  const RenderOptions& options() const { return options_; }

 private:
  struct Impl;
  RenderOptions options_;
  std::unique_ptr<Impl> impl_;
};

// Low-level helper (exposed for tests): the exact area of the intersection of a convex polygon with
// the axis-aligned rectangle [x0, x1] x [y0, y1].
double ConvexPolygonRectArea(const std::vector<Eigen::Vector2d>& polygon, double x0, double y0, double x1,
                             double y1);

// Low-level helper (exposed for tests): the cells first..last of a row (or column) of `grid` cells that
// the interval [from, to], in cells from the grid's edge, overlaps: first = max(0, floor(from)),
// last = min(grid - 1, floor(to)); none (first > last) when the interval misses the grid. An interval
// ending 2^31 or more cells away, or not a number (a pixel's footprint at the horizon), gives none: such
// a footprint is not rendered (the conversion to int was undefined there; x86 skipped it).
struct CellSpan {
  int first = 0, last = -1;
};
CellSpan CellsOverlapping(double from, double to, int grid);

// ---------------------------------------------------------------------------------------------
// What a session tells its user that is not the truth (sim/perturb.cc, issue 18): intrinsics written to
// the rig (camK.yml, and the camera_model of the detections) that differ from the true ones the images and
// corners are made with, and camera clocks that are off and drift.

// Error of a camera's written intrinsics against the truth.
struct IntrinsicsError {
  double focal_rel = 0.0;           // fx, fy *= 1 + focal_rel
  double cx_px = 0.0, cy_px = 0.0;  // added to the principal point
  double k1 = 0.0;                  // added to the first distortion coefficient (radtan or fisheye k1)
};
// The written model: `truth` with the error applied (k1 ignored without distortion coefficients).
CameraModel PerturbedModel(const CameraModel& truth, const IntrinsicsError& error);
// "CAM,FOCAL_PCT,CX_PX,CY_PX[,K1]" (e.g. "cam1,3,8,-6,0.03"); throws std::invalid_argument naming
// --intrinsics-error.
std::pair<std::string, IntrinsicsError> ParseIntrinsicsError(const std::string& text);

// A camera's clock against the true time (the frames' utimes in ground_truth.yaml): at true time t it
// reads t + offset + drift * (t - kStartUtime).
struct CameraClock {
  double offset_ms = 0.0;
  double drift_ppm = 0.0;  // 1 ppm: 1 us more per second
};
// "CAM,OFFSET_MS[,DRIFT_PPM]" (e.g. "cam2,12" or "cam2,-8,200"); throws std::invalid_argument naming
// --clock.
std::pair<std::string, CameraClock> ParseCameraClock(const std::string& text);
// The clock's reading (us, rounded) at true time `utime`.
int64_t ClockUtime(const CameraClock& clock, int64_t utime);

// ---------------------------------------------------------------------------------------------
// Ground truth file (ground_truth.yaml)

// A camera that moves during the session (a bumped tripod): from `frame` on it sits at rig_from_cam_after
// = rig_from_cam * [rotation by rotation_deg about the camera's y axis (a pan), translation_mm along its x
// axis].
struct CameraMove {
  std::string camera;
  int64_t frame = 0;  // first frame at the new pose
  double rotation_deg = 0.0;
  double translation_mm = 0.0;
  Rigid3 rig_from_cam_after = Rigid3::Identity();
};

// A camera that only publishes from `frame` on (one added to a running rig).
struct LateCamera {
  std::string camera;
  int64_t frame = 0;
};

struct GroundTruth {
  std::string object;  // object kind name
  std::string dictionary = "DICT_6X6_250";
  double marker_size = 0.04;           // default side
  std::map<int, double> marker_sizes;  // every id's side
  double fps = 30.0;
  std::vector<SimCamera> cameras;  // name, model, rig_from_cam
  std::vector<SimMarker> markers;  // id, size, object_from_marker
  std::vector<SimFrame> frames;    // seq, utime, rig_from_object
  std::vector<CameraMove> moves;   // cameras[].rig_from_cam is the pose before a move (sim/bump.cc)
  std::vector<LateCamera> late_cameras;
  std::map<std::string, CameraClock> clocks;  // cameras whose clock is not the true time
  const SimCamera* FindCamera(const std::string& name) const;
  const SimMarker* FindMarker(int id) const;
};

// Poses written as {translation: [x, y, z], rotation_wxyz: [w, x, y, z]} with %.17g, written atomically.
// Layout:
//   version: 1
//   object: four_sided
//   dictionary: DICT_6X6_250
//   marker_size: 0.04
//   fps: 30
//   rig_frame: world
//   cameras:   {cam0: {rig_from_cam: POSE, width: 640, height: 480, fx: .., fy: .., cx: .., cy: ..,
//                      distortion_model: none, distortion: []}, ...}
//   markers:   {0: {size: 0.04, object_from_marker: POSE}, ...}
//   frames:    - {seq: 0, utime: 1000000000000, rig_from_object: POSE}
//   moves:     - {camera: cam2, frame: 150, rotation_deg: 0.5, translation_mm: 3, rig_from_cam_after: POSE}
//   late_cameras: - {camera: cam5, frame: 300}
//   clocks:    {cam1: {offset_ms: -20, drift_ppm: 0}}
// (the last three only when there are moves / late cameras / clocks that are off).
void WriteGroundTruth(const std::string& path, const GroundTruth& truth);
// Throws std::runtime_error naming the file and key.
GroundTruth ReadGroundTruth(const std::string& path);

// ---------------------------------------------------------------------------------------------
// Simulated detections (detections-only mode)

struct DetectionSimOptions {
  double corner_noise_px = 0.1;  // Gaussian sigma per corner coordinate
  double miss_rate = 0.0;        // probability that a visible marker is not reported
  double false_rate = 0.0;       // expected false detections per camera frame (Poisson), ids not on object
  double drop_rate = 0.0;        // probability that a whole camera frame is not published
  double max_view_angle_deg = 80.0;  // markers seen more obliquely are not detected
  double min_size_px = 8.0;          // smaller markers are not detected
  std::string dictionary = "DICT_6X6_250";
  int dictionary_size = 250;  // false ids are drawn from [0, dictionary_size) minus the object's ids
};

// One camera's detections_t for one frame (nullopt-like: returns false when the frame is dropped).
// rng drives noise, misses and false detections (use one per camera for determinism independent of order).
bool SimulateDetections(const SimCamera& camera, const SimObject& object, const SimFrame& frame,
                        const DetectionSimOptions& options, std::mt19937_64& rng, detections_t* out);

// ---------------------------------------------------------------------------------------------
// A whole dataset (what mcmt-sim does), usable from tests and benchmarks without the process.

// ---------------------------------------------------------------------------------------------
// Cameras that move or start late (sim/bump.cc)

struct CameraMoveOptions {
  std::string camera;
  int64_t frame = 0;
  double rotation_deg = 0.0;
  double translation_mm = 0.0;
};

// "CAM,FRAME,ROT_DEG,TRANS_MM" (e.g. "cam2,150,0.5,3"); throws std::invalid_argument naming the option.
CameraMoveOptions ParseCameraMove(const std::string& text);

// The moved pose of CameraMove (rotation about the camera's y axis, translation along its x axis).
Rigid3 MovedRigFromCam(const Rigid3& rig_from_cam, double rotation_deg, double translation_mm);

// An extra camera for a rig of `rig.num_cameras` cameras: named cam<N>, on the circle halfway between cam0
// and cam1, looking at the look-at point (the first N cameras are unchanged).
SimCamera MakeExtraCamera(const RigOptions& rig);

// The camera as it is at frame `seq` (its moved pose from the move's frame on).
SimCamera CameraAtFrame(const SimCamera& camera, const GroundTruth& truth, int64_t seq);
// Whether the camera publishes at frame `seq` (late cameras only from their frame on).
bool CameraActive(const std::string& camera, const GroundTruth& truth, int64_t seq);
// The truth with every camera at its pose at the end of the session (what a map should hold).
GroundTruth TruthAtEnd(const GroundTruth& truth);

struct DatasetOptions {
  std::string out_dir;
  ObjectOptions object;
  RigOptions rig;
  TrajectoryOptions trajectory;
  RenderOptions render;
  DetectionSimOptions detections;
  std::vector<CameraMoveOptions> moves;  // cameras bumped during the session
  // Per camera name: the error of the intrinsics written to the rig (camK.yml and the detections'
  // camera_model; the images, corners and ground truth stay true), and a clock that is off (detections'
  // utime; with images, camK_timestamps.csv named in rig.yaml). Both recorded in ground_truth.yaml only as
  // far as the clocks go (the true intrinsics are there).
  std::map<std::string, IntrinsicsError> intrinsics_errors;
  std::map<std::string, CameraClock> clocks;
  int64_t add_camera_frame = -1;  // >= 0: one extra camera (MakeExtraCamera) from this frame on
  std::string dictionary = "DICT_6X6_250";
  bool detections_only = false;
  bool video = false;  // per-camera MP4 instead of PNG folders
  bool quiet = true;   // no progress on stderr
  // Called after each image with (images written, images in all), from the rendering threads.
  std::function<void(int64_t, int64_t)> progress;
  int threads = 1;  // cameras rendered in parallel (results do not depend on it)
};

struct DatasetSummary {
  GroundTruth truth;
  int64_t images_written = 0;
  int64_t messages_written = 0;  // detections-only
  double seconds = 0.0;
};

// A detections-only session as `mcmt-sim --detections-only --out dir --frames N --seed S` sets it up
// with its other options at their defaults (5 cameras at 1.0 m, the motion's extent from the radius).
DatasetOptions DetectionsOnlySession(const std::string& dir, int frames, uint64_t seed);

// The extra camera and the moves of `options` added to the truth (its cameras and frames filled); throws
// std::invalid_argument naming the option.
void AddCameraChanges(const DatasetOptions& options, GroundTruth* truth);

// Writes out_dir/rig.yaml, out_dir/camK.yml, out_dir/ground_truth.yaml and either images
// (out_dir/camK/000000.png ... or out_dir/camK.mp4) or out_dir/detections.lcmlog.
DatasetSummary GenerateDataset(const DatasetOptions& options);

// ---------------------------------------------------------------------------------------------
// Scenes with several rigid bodies (sim/scene_bodies.cc)

struct SceneBody {
  std::string name;  // as in the rig's objects: list
  bool is_static = false;
  SimObject object;
  std::vector<SimFrame> frames;  // rig_from_object per frame (constant for a static body)
};

// `bodies`: a static floor board (8 markers of 8 cm, ids 20-27, on a ring of radius 0.25 * radius at
// z = -0.25 * radius) and two moving objects, "tool" (four_sided, ids 0-3) and "patient" (cube, ids
// 10-15), on independent trajectories (seeds `seed` and `seed + 1`) pushed apart along x by
// +-0.09 * radius * cos(2 pi s), s = frame / (frames - 1): they swap sides twice, crossing (and occluding
// each other) at s = 1/4 and 3/4. `with_static`: false leaves the floor out.
std::vector<SceneBody> MakeBodiesScene(const DatasetOptions& options, bool with_static = true);

// A body that does not move: `object` at rig_from_object in every frame of `like` (same seqs and utimes),
// is_static set (a floor, a marker fixed in the room).
SceneBody StaticBody(const std::string& name, const SimObject& object, const Rigid3& rig_from_object,
                     const std::vector<SimFrame>& like);

// The scene's bodies at frame k as one object in the rig frame (markers and faces of all bodies): a
// marker of one body hidden by another body is occluded.
SimObject SceneAt(const std::vector<SceneBody>& bodies, size_t k);

// mcmt-sim --scene bodies (detections only): DIR/rig.yaml (objects: tool, patient, floor static and the
// rig frame), DIR/rig_moving.yaml (the same without the floor: its ids ignored), camK.yml,
// DIR/ground_truth_<body>.yaml per body (its markers in its own frame, rig_from_object per frame),
// DIR/ground_truth.yaml (= the tool's) and DIR/detections.lcmlog. `moves` and `add_camera_frame` as for
// one object (each body's ground truth lists the moves and late cameras).
DatasetSummary GenerateBodiesDataset(const DatasetOptions& options);

// ---------------------------------------------------------------------------------------------
// Detections-only sessions in memory (sim/session.cc): a rig, bodies moving in front of it and every
// camera's detections, for tests and benchmarks that want them without files. The same simulation as a
// detections-only dataset: a session from SessionOptions holds the messages GenerateDataset would log for
// the same rig, object, trajectory and detection options.

struct Session {
  std::vector<SimCamera> cameras;
  std::vector<SceneBody> bodies;  // bodies[0]: the object; every body has one pose per frame
  std::string dictionary = "DICT_6X6_250";
  double fps = 30.0;
  std::vector<std::vector<detections_t>> views;  // per frame: the cameras' published messages, camera order

  const SimObject& object() const { return bodies.at(0).object; }
  const std::vector<SimFrame>& frames() const { return bodies.at(0).frames; }
  // A body's ground truth (the cameras, its markers and poses), for Evaluate and MapFromGroundTruth.
  GroundTruth Truth(size_t body = 0) const;
  // Every message, frame by frame (what a log of the session holds, in its order).
  std::vector<detections_t> Messages() const;
};

struct SessionOptions {
  RigOptions rig;
  ObjectOptions object;
  TrajectoryOptions trajectory;  // its seed also seeds the detections (as GenerateDataset)
  DetectionSimOptions detections;
  // Camera k's messages are stamped k * camera_stagger_us after the frame (cameras not triggered together).
  int64_t camera_stagger_us = 0;
  // More bodies beside the object (bodies[1], ...; e.g. StaticBody: a marker fixed in the room), each with
  // one pose per frame of the trajectory; their markers are detected and hide, and are hidden by, the others.
  std::vector<SceneBody> extra_bodies;
};

// The rig, the object and its trajectory made from the options (MakeRig, MakeObject, MakeTrajectory), and
// the extra bodies.
Session SimulateSession(const SessionOptions& options);
// Given cameras and bodies (the same number of frames each; frame times and seqs are bodies[0]'s): the
// detections of every body's markers, a body hiding markers of the others. Throws std::invalid_argument
// when there is no body or the bodies' frames differ in number.
Session SimulateSession(const std::vector<SimCamera>& cameras, const std::vector<SceneBody>& bodies,
                        const DetectionSimOptions& options, uint64_t seed, int64_t camera_stagger_us = 0);

// DIR/rig.yaml and DIR/camK.yml for the session's cameras (markers: the dictionary and the object's sizes;
// cameras: name and intrinsics), `extra` appended verbatim (sync:, mapper: ...). Returns the rig's path.
std::string WriteSessionRig(const std::string& dir, const Session& session, const std::string& extra = "");

// Writes `messages` in their order as an LCM log (detections_t on MCMT_DETECTIONS_<CAMERA>), atomically; an
// event's time is its message's utime plus `arrival_delay_us(message)` when given (a detector that takes
// longer). Returns the events written; throws std::runtime_error naming the file.
int64_t WriteMessagesLog(const std::string& path, const std::vector<detections_t>& messages,
                         const std::function<int64_t(const detections_t&)>& arrival_delay_us = nullptr);

}  // namespace sim
}  // namespace mcmt
