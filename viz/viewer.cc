#include "viz/viewer.h"

#include <mrpt/gui/CDisplayWindow3D.h>
#include <mrpt/gui/keycodes.h>
#include <mrpt/opengl/CFBORender.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <thread>

#include "core/lcm_util.h"
#include "core/options.h"
#include "core/progress.h"

namespace mcmt::viz {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string FrameOverlay(const std::vector<TrajectoryRow>& rows, int index) {
  if (index < 0 || rows.empty()) return "no pose";
  const TrajectoryRow& r = rows[index];
  char text[200];
  std::snprintf(text, sizeof(text), "frame %d/%zu  seq %lld  t %.3f s  RMS %.3f px  cameras %d  markers %d",
                index + 1, rows.size(), static_cast<long long>(r.seq), 1e-6 * static_cast<double>(r.utime),
                r.rms_px, r.cameras, r.markers);
  return text;
}

// The name of the map's first moving body (FirstMovingObject), "" for a map without objects.
std::string MainBodyName(const RigMap& map) {
  return map.objects.empty() ? "" : map.objects[FirstMovingObject(map)].name;
}

}  // namespace

bool ViewerOptions::NeedsLiveLcm() const {
  if (!log_path.empty()) return false;
  if (!Headless()) return true;  // the live window always listens
  return map_path.empty() || max_poses > 0;
}

void ViewerOptions::Validate() const {
  scene.Validate();
  if (max_poses < 0)
    throw std::invalid_argument("--max-poses: expected >= 0, got " + std::to_string(max_poses));
  if (!(timeout_s > 0)) throw std::invalid_argument("--timeout: expected > 0 seconds");
  if (view != "rig" && view != "object" && view != "follow")
    throw std::invalid_argument("--view: expected rig, object or follow, got '" + view + "'");
  if (!(max_seconds >= 0)) throw std::invalid_argument("--max-seconds: expected >= 0");
  if (!(redraw_hz > 0 && redraw_hz <= 240)) throw std::invalid_argument("--redraw-hz: expected in (0, 240]");
  if (!initial_trajectory_path.empty() && initial_map_path.empty())
    throw std::invalid_argument("--initial-trajectory needs --initial-map");
}

const OptionTable<ViewerOptions>& VizOptionTable() {
  using O = ViewerOptions;
  using S = SceneOptions;
  using T = OptionTable<O>;
  static const T* table =
      &(*new T("viz"))
           .Add("width", T::Of(&O::scene, &S::width), "px", "window / image width", InRange(16, 16384))
           .Add("height", T::Of(&O::scene, &S::height), "px", "window / image height", InRange(16, 16384))
           .Add("rays", T::Of(&O::scene, &S::rays), "rays camera -> markers seen in the current frame")
           .Add("legend", T::Of(&O::scene, &S::legend), "the legend")
           .Add("residual_scale_px", T::Of(&O::scene, &S::residual_scale_px), "px",
                "residual colours: red at and above, green at and below a quarter (0: the largest RMS shown)",
                AtLeast(0))
           .Add("trail_max", T::Of(&O::scene, &S::trail_max), "poses", "newest poses kept in the trail",
                AtLeast(0))
           .Add("azimuth_deg", T::Of(&O::scene, &S::azimuth_deg), "deg", "automatic view direction")
           .Add("elevation_deg", T::Of(&O::scene, &S::elevation_deg), "deg", "automatic view elevation")
           .Add("fov_deg", T::Of(&O::scene, &S::fov_deg), "deg",
                "vertical field of view of the viewer's camera", InRange(1, 170, true, true))
           .Add("redraw_hz", &O::redraw_hz, "Hz", "live redraw rate", InRange(0, 240, true))
           .Add("follow", &O::follow, "the view follows the object");
  return *table;
}

void LoadVizSection(const YamlSection& s, ViewerOptions* o) { VizOptionTable().Load(s, o); }

std::string NoDisplayReason() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  if ((x && *x) || (w && *w)) return "";
  return "no display (DISPLAY and WAYLAND_DISPLAY are unset)";
}

void ParseSize(const std::string& text, int* width, int* height) {
  int w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 16384 || h > 16384)
    throw std::invalid_argument("--size: expected WIDTHxHEIGHT (16..16384), e.g. 1280x720, got '" + text +
                                "'");
  *width = w;
  *height = h;
}

void WritePng(const std::string& path, const cv::Mat& bgr) {
  std::vector<uchar> buffer;
  if (!cv::imencode(".png", bgr, buffer)) throw std::runtime_error(path + ": cannot encode PNG");
  WriteFileAtomic(path, std::string(buffer.begin(), buffer.end()));
}

Viewer::Viewer(ViewerOptions options, lcm::LCM* lcm, bool is_log)
    : options_(std::move(options)), lcm_(lcm), is_log_(is_log) {
  options_.Validate();
  if (!options_.map_path.empty()) {
    file_map_ = ReadMap(options_.map_path);
    have_file_map_ = true;
  }
  if (!options_.initial_map_path.empty()) {
    file_initial_map_ = ReadMap(options_.initial_map_path);
    have_initial_ = true;
    std::string traj = options_.initial_trajectory_path;
    if (traj.empty()) {
      const fs::path beside = fs::path(options_.initial_map_path).parent_path() / "trajectory_initial.csv";
      if (fs::exists(beside)) traj = beside.string();
    }
    if (!traj.empty()) file_initial_trajectory_ = ReadTrajectory(traj);
  }
  if (!options_.trajectory_path.empty()) {
    const bool per_body =
        fs::is_directory(options_.trajectory_path) ||
        (!fs::exists(options_.trajectory_path) && have_file_map_ && !file_map_.objects.empty());
    if (per_body) {  // the mapper's OUTDIR, or the tracker's --out PATH (PATH_<body>.csv): every moving
                     // body's
      for (const auto& [body, path] : BodyTrajectoryFiles(options_.trajectory_path, file_map_)) {
        if (body.empty())
          file_trajectory_ = ReadTrajectory(path);
        else
          file_body_trajectories_[body] = ReadTrajectory(path);
      }
    } else {
      file_trajectory_ = ReadTrajectory(options_.trajectory_path);
    }
    have_file_trajectory_ = true;
  }
}

const PoseStream& Viewer::MainStream(const LcmCollector& collector, const RigMap& map) {
  if (!map.objects.empty()) {
    const auto it = collector.body_poses().find(map.objects[FirstMovingObject(map)].name);
    if (it != collector.body_poses().end()) return it->second;
  }
  return collector.pose_stream();
}

std::string Viewer::NoPosesInLog() const {
  return options_.log_path +
         " has no MCMT_POSE (mcmt-tracker was not running while it was recorded), so the object is not "
         "drawn: "
         "add --trajectory OUTDIR/trajectory.csv (the mapper's; several bodies: --trajectory OUTDIR)";
}

std::vector<PanelInput> Viewer::Panels(const LcmCollector* collector) const {
  PanelInput refined;
  refined.title = have_initial_ ? "refined" : "map";
  if (have_file_map_)
    refined.map = file_map_;
  else if (collector && collector->has_map())
    refined.map = collector->map();
  else
    return {};
  const bool several = refined.map.objects.size() > 1;
  const std::string main_body = MainBodyName(refined.map);
  if (have_file_trajectory_) {
    refined.trajectory = file_trajectory_;
    for (const auto& [body, rows] : file_body_trajectories_) {
      if (body == main_body)
        refined.trajectory = rows;
      else
        refined.bodies[body] = rows;
    }
  } else if (collector) {
    refined.trajectory = MainStream(*collector, refined.map).rows;
    for (const auto& [body, stream] : collector->body_poses())
      if (several && body != main_body) refined.bodies[body] = stream.rows;
  }
  std::vector<PanelInput> panels;
  if (have_initial_) {
    PanelInput initial;
    initial.title = "initial";
    initial.map = file_initial_map_;
    initial.trajectory = file_initial_trajectory_;
    panels.push_back(std::move(initial));
  }
  panels.push_back(std::move(refined));
  return panels;
}

int Viewer::Run() {
  std::unique_ptr<LcmCollector> collector;
  // Live: bounded memory (the trail shows at most trail_max poses anyway).
  const size_t keep_poses =
      is_log_ ? 0 : std::max<size_t>(10000, 2 * static_cast<size_t>(options_.scene.trail_max));
  if (lcm_) collector = std::make_unique<LcmCollector>(*lcm_, is_log_ ? 0 : 300, keep_poses);
  if (collector && is_log_) {
    log_damaged_ = collector->ReadLog(options_.log_path).damaged();
    if (!have_file_map_ && !collector->has_map())
      throw std::runtime_error(options_.log_path + ": no MCMT_MAP message in the log (give --map map.yaml)");
    if (!have_file_trajectory_ && collector->all_poses() == 0) {
      if (!options_.video_dir.empty()) throw std::runtime_error("--video: " + NoPosesInLog());
      std::cerr << "mcmt-viz: note: " << NoPosesInLog() << "\n";
    }
  }
  if (!lcm_ && !have_file_map_) throw std::runtime_error("nothing to show: give --map, --log or --lcm-url");
  const int code = options_.Headless() ? RunHeadless(collector.get()) : RunWindow(collector.get());
  return code == 0 && log_damaged_ ? kExitDamagedLog : code;
}

int Viewer::RunHeadless(LcmCollector* collector) {
  if (collector && !is_log_) {
    // Live: wait for a map and enough poses.
    const auto deadline = Clock::now() + std::chrono::duration<double>(options_.timeout_s);
    auto ready = [&] {
      return (have_file_map_ || collector->has_map()) && collector->all_poses() >= options_.max_poses;
    };
    // Subscribed from here on (tests wait for this line).
    std::string wanted = have_file_map_ ? "" : "MCMT_MAP";
    if (options_.max_poses > 0)
      wanted += (wanted.empty() ? "" : " and ") + std::to_string(options_.max_poses) + " poses";
    std::cerr << "mcmt-viz: listening for " << wanted << " (at most " << options_.timeout_s << " s)"
              << std::endl;
    while (!ready() && Clock::now() < deadline) lcm_->handleTimeout(20);
    if (!ready()) {
      char text[200];
      std::snprintf(text, sizeof(text), "timed out after %.1f s waiting for %s (got %s and %lld poses)",
                    options_.timeout_s, options_.max_poses > 0 ? "a map and --max-poses poses" : "a map",
                    (have_file_map_ || collector->has_map()) ? "a map" : "no MCMT_MAP",
                    static_cast<long long>(collector->all_poses()));
      throw std::runtime_error(text);
    }
  }
  VizScene scene(options_.scene);
  if (collector) scene.SetCameraStates(collector->camera_states());  // the tracker's newest
  scene.SetPanels(Panels(collector));
  const auto& rows = scene.trajectory();
  auto detections_at = [&](int index) {
    if (!collector || index < 0) return std::map<std::string, std::vector<int>>();
    return collector->DetectionsAt(rows[index].utime);
  };

  if (!rows.empty() || options_.frame != -1) {
    const int n = static_cast<int>(rows.size());
    const int index = options_.frame >= 0 ? options_.frame : n + options_.frame;
    if (index < 0 || index >= n)
      throw std::invalid_argument("--frame " + std::to_string(options_.frame) + ": the trajectory has " +
                                  std::to_string(n) + " frames");
    scene.SetCurrentFrame(index);
    scene.SetDetections(detections_at(index));
  }
  auto apply_view = [&] {
    if (options_.view == "object") scene.FrameObject();
    if (options_.view == "follow") scene.FollowObject();
  };
  apply_view();
  scene.SetOverlay({FrameOverlay(rows, scene.current_frame())});

  if (!options_.save_scene_path.empty()) {
    scene.ApplyViews();
    const std::string tmp = options_.save_scene_path + ".tmp." + std::to_string(::getpid());
    if (!scene.scene()->saveToFile(tmp)) {
      std::remove(tmp.c_str());
      throw std::runtime_error(options_.save_scene_path + ": cannot write the scene");
    }
    if (std::rename(tmp.c_str(), options_.save_scene_path.c_str()) != 0) {
      std::remove(tmp.c_str());
      throw std::runtime_error(options_.save_scene_path + ": cannot rename the written scene into place");
    }
    std::cout << "mcmt-viz: wrote " << options_.save_scene_path << "\n";
  }
  if (options_.snapshot_path.empty() && options_.video_dir.empty()) return 0;

  mrpt::opengl::CFBORender render(static_cast<unsigned>(options_.scene.width),
                                  static_cast<unsigned>(options_.scene.height));
  if (!options_.snapshot_path.empty()) {
    WritePng(options_.snapshot_path, scene.Render(&render));
    std::cout << "mcmt-viz: wrote " << options_.snapshot_path << " (" << options_.scene.width << "x"
              << options_.scene.height << ")\n";
  }
  if (!options_.video_dir.empty()) {
    if (rows.empty())
      throw std::runtime_error("--video: no trajectory to render (give --trajectory or a log with poses)");
    std::error_code ec;
    fs::create_directories(options_.video_dir, ec);
    if (ec) throw std::runtime_error(options_.video_dir + ": cannot create the folder: " + ec.message());
    const int n = static_cast<int>(rows.size());
    Progress progress("mcmt-viz --video", n);
    for (int i = 0; i < n; ++i) {
      scene.SetCurrentFrame(i);
      scene.SetDetections(detections_at(i));
      scene.SetOverlay({FrameOverlay(rows, i)});
      apply_view();
      char name[32];
      std::snprintf(name, sizeof(name), "frame_%06d.png", i);
      WritePng((fs::path(options_.video_dir) / name).string(), scene.Render(&render));
      progress.Update(i + 1);
    }
    progress.Finish();
    std::cout << "mcmt-viz: wrote " << n << " frames to " << options_.video_dir << "\n";
  }
  return 0;
}

namespace {

constexpr char kHeadlessHint[] =
    "render headless instead with --snapshot out.png, --save-scene out.3Dscene or --video DIR";

// The live MRPT window, or null after a one-line reason on stderr (no display, or it would not open).
mrpt::gui::CDisplayWindow3D::Ptr OpenWindow(int width, int height) {
  const std::string reason = NoDisplayReason();
  if (!reason.empty()) {
    std::cerr << "mcmt-viz: " << reason << ": the live window cannot open; " << kHeadlessHint << "\n";
    return nullptr;
  }
  mrpt::gui::CDisplayWindow3D::Ptr win;
  try {
    win = mrpt::gui::CDisplayWindow3D::Create("mcmt-viz", width, height);
  } catch (const std::exception& e) {
    std::cerr << "mcmt-viz: cannot open the live window (" << e.what()
              << "); render headless instead with --snapshot, --save-scene or --video\n";
    return nullptr;
  }
  if (!win || !win->isOpen()) {
    std::cerr << "mcmt-viz: cannot open the live window on display '"
              << (std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "") << "'; " << kHeadlessHint << "\n";
    return nullptr;
  }
  return win;
}

}  // namespace

// The live window and what it shows, between turns of Viewer::RunWindow's loop.
struct Viewer::LiveWindow {
  LiveWindow(mrpt::gui::CDisplayWindow3D::Ptr w, const SceneOptions& options)
      : win(std::move(w)), scene(options) {}

  // Runs `change` on the scene with the window's scene lock held (the window thread renders it).
  template <class Change>
  void Locked(Change change) {
    mrpt::opengl::COpenGLScene::Ptr& ptr = win->get3DSceneAndLock();
    change(ptr);
    win->unlockAccess3DScene();
  }
  const ViewCamera& MainView() const {
    return scene.view(scene.num_panels() > 0 ? scene.num_panels() - 1 : 0);
  }
  // The main view to the window's camera.
  void PushView(const ViewCamera& v) {
    win->setCameraPointingToPoint(static_cast<float>(v.pointing.x()), static_cast<float>(v.pointing.y()),
                                  static_cast<float>(v.pointing.z()));
    win->setCameraAzimuthDeg(static_cast<float>(v.azimuth_deg));
    win->setCameraElevationDeg(static_cast<float>(v.elevation_deg));
    win->setCameraZoom(static_cast<float>(v.distance));
    win->setFOV(static_cast<float>(v.fov_deg));
  }
  // The window's camera (the mouse may have moved it) to the main view.
  void PullView() {
    ViewCamera v = MainView();
    float x, y, z;
    win->getCameraPointingToPoint(x, y, z);
    v.pointing = Eigen::Vector3d(x, y, z);
    v.azimuth_deg = win->getCameraAzimuthDeg();
    v.elevation_deg = win->getCameraElevationDeg();
    v.distance = win->getCameraZoom();
    scene.SetView(v);
  }
  // Repaints when something changed: the scene, the view (mouse), or once a second (overlay).
  void RepaintIfChanged() {
    const ViewCamera& v = MainView();
    const bool view_changed = (v.pointing - last_view.pointing).norm() > 0 ||
                              v.azimuth_deg != last_view.azimuth_deg ||
                              v.elevation_deg != last_view.elevation_deg || v.distance != last_view.distance;
    if (!dirty && !view_changed && Clock::now() - last_repaint < std::chrono::seconds(1)) return;
    last_view = v;
    Locked([&](auto&) { scene.ApplyViews(); });  // keeps the side-by-side panels on the main view
    win->forceRepaint();
    ++repaints;
    last_repaint = Clock::now();
    dirty = false;
  }

  mrpt::gui::CDisplayWindow3D::Ptr win;
  VizScene scene;
  bool follow = false;
  bool browsing = false;  // stepping through frames with the arrow keys
  bool dirty = true;      // the scene changed since the last repaint
  bool reset = false;     // this turn: the view goes back to the automatic one
  int map_count = -1;     // the collector's map_count() shown
  // Poses received (the collector's absolute index per stream: "" the first moving body's) already in
  // the scene.
  std::map<std::string, int64_t> poses_shown;
  ViewCamera last_view;
  Clock::time_point last_repaint = Clock::now();
  int64_t repaints = 0;
};

const RigMap& Viewer::SceneMap(const LcmCollector& collector) const {
  return have_file_map_ ? file_map_ : collector.map();
}

bool Viewer::HandleKey(LiveWindow& w, int key) const {
  if (key == 'q' || key == 'Q' || key == 27) return false;
  if (key == 'f' || key == 'F') w.follow = !w.follow;
  if (key == 'r' || key == 'R') w.reset = true;
  if (key == 't' || key == 'T') w.Locked([&](auto&) { w.scene.SetRaysVisible(!w.scene.rays_visible()); });
  // Step through the trajectory (then the newest live pose is no longer followed until 'n').
  const int n = static_cast<int>(w.scene.trajectory().size());
  if (n > 0 && (key == ',' || key == mrpt::gui::MRPTK_LEFT || key == '.' || key == mrpt::gui::MRPTK_RIGHT)) {
    const int step = (key == ',' || key == mrpt::gui::MRPTK_LEFT) ? -1 : 1;
    w.browsing = true;
    w.Locked([&](auto&) { w.scene.SetCurrentFrame(std::clamp(w.scene.current_frame() + step, 0, n - 1)); });
  }
  if (key == 'n' || key == 'N') {
    w.browsing = false;
    w.Locked([&](auto&) { w.scene.SetCurrentFrame(-1); });
  }
  w.dirty = true;
  return true;
}

void Viewer::MarkAllPosesShown(LiveWindow& w, const LcmCollector& collector) const {
  w.poses_shown.clear();
  w.poses_shown[""] = MainStream(collector, SceneMap(collector)).total();
  for (const auto& [body, stream] : collector.body_poses()) w.poses_shown[body] = stream.total();
}

void Viewer::ShowNewPoses(LiveWindow& w, const LcmCollector& collector) const {
  const RigMap& map = SceneMap(collector);
  const PoseStream& main = MainStream(collector, map);
  int64_t& main_shown = w.poses_shown[""];
  main_shown = std::max(main_shown, main.dropped);  // older ones dropped
  for (; main_shown < main.total(); ++main_shown) {
    const int shown = w.scene.current_frame();
    w.scene.AddPose(main.rows[static_cast<size_t>(main_shown - main.dropped)]);
    if (w.browsing) w.scene.SetCurrentFrame(shown);
    w.dirty = true;
  }
  const std::string main_body = MainBodyName(map);
  for (const auto& [body, stream] : collector.body_poses()) {
    if (body == main_body) continue;
    int64_t& body_shown = w.poses_shown[body];
    body_shown = std::max(body_shown, stream.dropped);
    for (; body_shown < stream.total(); ++body_shown) {
      w.scene.AddBodyPose(body, stream.rows[static_cast<size_t>(body_shown - stream.dropped)], !w.browsing);
      w.dirty = true;
    }
  }
}

void Viewer::SyncWithCollector(LiveWindow& w, const LcmCollector& collector) const {
  w.Locked([&](mrpt::opengl::COpenGLScene::Ptr& ptr) {
    VizScene& scene = w.scene;
    const bool new_map = collector.map_count() != w.map_count && (collector.has_map() || have_file_map_);
    if (new_map || (w.map_count < 0 && have_file_map_)) {
      w.map_count = collector.map_count();
      scene.SetCameraStates(collector.camera_states());
      scene.SetPanels(Panels(&collector));
      ptr = scene.scene();
      MarkAllPosesShown(w, collector);
      w.reset = true;
      w.dirty = true;
    } else if (scene.HasMap() && collector.camera_states() != scene.camera_states()) {
      // A camera turned suspect, excluded or ok again (MCMT_TRACKER_STATUS): redrawn, the view kept.
      const ViewCamera view = w.MainView();
      const int shown = scene.current_frame();
      scene.SetCameraStates(collector.camera_states());
      scene.SetPanels(Panels(&collector));
      scene.SetView(view);
      scene.SetCurrentFrame(w.browsing ? shown : -1);
      ptr = scene.scene();
      MarkAllPosesShown(w, collector);
      w.dirty = true;
    }
    if (scene.HasMap() && !have_file_trajectory_) ShowNewPoses(w, collector);
    if (w.dirty && scene.HasMap() && scene.current_frame() >= 0)
      scene.SetDetections(collector.DetectionsAt(scene.trajectory()[scene.current_frame()].utime));
    const PoseStats& st = collector.stats();
    char line[200];
    std::snprintf(
        line, sizeof(line), "poses %lld (lost %lld)  rate %.1f Hz  latency %.1f ms  RMS %.3f px%s%s",
        static_cast<long long>(st.poses), static_cast<long long>(st.lost), collector.RateHz(NowUtime()),
        st.latency_ms, st.rms_px, w.follow ? "  [follow]" : "", scene.rays_visible() ? "  [rays]" : "");
    scene.SetOverlay({scene.HasMap() ? line : "waiting for MCMT_MAP (or give --map map.yaml) ...",
                      FrameOverlay(scene.trajectory(), scene.current_frame())});
  });
}

void Viewer::UpdateView(LiveWindow& w) const {
  if (w.reset) {
    w.Locked([&](auto&) { w.scene.AutoView(); });
    w.PushView(w.MainView());
    w.dirty = true;
  } else {
    w.PullView();  // the mouse may have moved the main view
  }
  if (w.follow && w.dirty) {
    w.scene.FollowObject();
    w.PushView(w.MainView());
  }
}

void Viewer::WaitForRedraw(Clock::time_point next_redraw, LcmCollector* collector) {
  // LCM until the next redraw is due (redraws bounded however fast poses arrive).
  while (Clock::now() < next_redraw) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(next_redraw - Clock::now());
    if (collector && !is_log_)
      lcm_->handleTimeout(std::max<int>(1, static_cast<int>(left.count())));
    else
      std::this_thread::sleep_for(left);
  }
}

int Viewer::RunWindow(LcmCollector* collector) {
  mrpt::gui::CDisplayWindow3D::Ptr win = OpenWindow(options_.scene.width, options_.scene.height);
  if (!win) return 1;
  LiveWindow w(win, options_.scene);
  w.scene.EnableLegendViewport();
  w.follow = options_.follow;
  w.Locked([&](mrpt::opengl::COpenGLScene::Ptr& ptr) { ptr = w.scene.scene(); });
  if (!collector) {  // files only: one static scene
    w.Locked([&](mrpt::opengl::COpenGLScene::Ptr& ptr) {
      w.scene.SetPanels(Panels(nullptr));
      ptr = w.scene.scene();
    });
    w.PushView(w.MainView());
  }
  std::cout
      << "mcmt-viz: keys: f follow the object, r reset the view, t toggle rays, left/right (or , .) step "
         "frames, n newest frame, q quit"
      << std::endl;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / options_.redraw_hz));
  const auto start = Clock::now();
  auto next_redraw = start;
  while (win->isOpen()) {
    if (options_.max_seconds > 0 &&
        Clock::now() - start > std::chrono::duration<double>(options_.max_seconds))
      break;
    WaitForRedraw(next_redraw, collector);
    next_redraw = Clock::now() + period;
    w.reset = false;
    if (win->keyHit() && !HandleKey(w, win->getPushedKey())) break;
    if (collector) SyncWithCollector(w, *collector);
    if (!w.scene.HasMap()) {
      if (w.dirty) win->forceRepaint();
      w.dirty = false;
      continue;
    }
    UpdateView(w);
    w.RepaintIfChanged();
  }
  std::printf("mcmt-viz: window closed after %.1f s: %zu poses shown, %lld repaints\n",
              std::chrono::duration<double>(Clock::now() - start).count(), w.scene.trajectory().size(),
              static_cast<long long>(w.repaints));
  return 0;
}

}  // namespace mcmt::viz
