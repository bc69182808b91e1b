// mcmt-viz: gathers a map, trajectories and detections from files, a log or live LCM, then either
// renders headless (PNG snapshot, .3Dscene, one PNG per frame) or opens the live MRPT window.
#pragma once

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/options.h"
#include "viz/collector.h"
#include "viz/scene.h"

namespace mcmt::viz {

struct ViewerOptions {
  std::string map_path;                 // map.yaml (refined)
  std::string initial_map_path;         // map_initial.yaml: before/after side by side
  std::string trajectory_path;          // trajectory.csv of the refined map, or the mapper's OUTDIR (bodies)
  std::string initial_trajectory_path;  // default: trajectory_initial.csv beside the initial map
  std::string log_path;                 // LCM log read by core's reader
  std::string snapshot_path;            // PNG
  std::string save_scene_path;          // MRPT .3Dscene (SceneViewer3D)
  std::string video_dir;                // one PNG per trajectory frame: frame_000000.png ...
  int frame = -1;                       // trajectory row shown (negative: from the end, -1 = last)
  int max_poses = 0;                    // live headless: wait for this many poses (and a map)
  double timeout_s = 30.0;              // live headless: give up after this long
  double redraw_hz = 30.0;              // live window: redraws per second at most
  bool follow = false;                  // live window: start following the object
  double max_seconds = 0.0;             // live window: close after this long (0: never)
  std::string view = "rig";             // headless view: rig (all), object (close-up), follow
  SceneOptions scene;

  bool Headless() const { return !snapshot_path.empty() || !save_scene_path.empty() || !video_dir.empty(); }
  // Whether the run needs LCM traffic (a log, or live messages).
  bool NeedsLiveLcm() const;
  void Validate() const;  // throws std::invalid_argument naming the option
};

// Reads the optional "viz:" section of a rig YAML into the options (keys declared in VizOptionTable).
void LoadVizSection(const YamlSection& section, ViewerOptions* options);  // throws OptionError
const mcmt::OptionTable<ViewerOptions>& VizOptionTable();  // every viz: key (loading, checks, docs)

// Why the live window cannot open here, or empty when a display is available.
std::string NoDisplayReason();

// "1280x720" -> width, height; throws std::invalid_argument.
void ParseSize(const std::string& text, int* width, int* height);

// Encodes as PNG and writes atomically (temporary file + rename).
void WritePng(const std::string& path, const cv::Mat& bgr);

class Viewer {
 public:
  // lcm: a log (file:// provider, is_log) or live traffic; may be null when neither is needed.
  Viewer(ViewerOptions options, lcm::LCM* lcm, bool is_log);
  int Run();

 private:
  std::vector<PanelInput> Panels(const LcmCollector* collector) const;
  // The stream of the map's first moving body (MCMT_POSE_<BODY> of a map with several bodies, when it
  // has poses), else MCMT_POSE's.
  static const PoseStream& MainStream(const LcmCollector& collector, const RigMap& map);
  std::string NoPosesInLog() const;  // why a log shows no object, and what to add
  int RunHeadless(LcmCollector* collector);
  int RunWindow(LcmCollector* collector);
  // The live window's loop turn, in steps (viewer.cc).
  struct LiveWindow;
  const RigMap& SceneMap(const LcmCollector& collector) const;  // --map's, else the collector's
  void WaitForRedraw(std::chrono::steady_clock::time_point next_redraw, LcmCollector* collector);
  bool HandleKey(LiveWindow& w, int key) const;  // false: quit
  // A new map or camera states, new poses, the current frame's detections and the overlay.
  void SyncWithCollector(LiveWindow& w, const LcmCollector& collector) const;
  void MarkAllPosesShown(LiveWindow& w, const LcmCollector& collector) const;
  void ShowNewPoses(LiveWindow& w, const LcmCollector& collector) const;
  void UpdateView(LiveWindow& w) const;  // reset, the mouse's view, following

  ViewerOptions options_;
  lcm::LCM* lcm_;
  bool is_log_;
  bool log_damaged_ = false;  // the log was damaged: exit status kExitDamagedLog
  RigMap file_map_, file_initial_map_;
  bool have_file_map_ = false, have_initial_ = false;
  std::vector<TrajectoryRow> file_trajectory_, file_initial_trajectory_;
  bool have_file_trajectory_ = false;
  // --trajectory OUTDIR of a map with several bodies: trajectory_<body>.csv by body (file_trajectory_ is
  // then the first moving body's, chosen when the map is known).
  std::map<std::string, std::vector<TrajectoryRow>> file_body_trajectories_;
};

}  // namespace mcmt::viz
