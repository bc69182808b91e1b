// The MRPT scene of a rig map and the object's track: camera frustums, textured markers on the
// object, its trail, rays to the detected markers, residual colours with a legend, and, with an
// initial map, the mapper's initial and refined solutions side by side.
#pragma once

#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CText.h>

#include <Eigen/Core>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/files.h"
#include "core/se3.h"
#include "viz/view_camera.h"

namespace mrpt::opengl {
class CFBORender;
}

namespace mcmt::viz {

// The viewports' background colour, as 8-bit B, G, R.
cv::Vec3b BackgroundBgr();

// Residual colour on an absolute scale, the same for every map and snapshot: green at and below
// scale/4, yellow half-way, red at and above scale (the default scale, 2 px: green <= 0.5 px, red >= 2 px).
// RGB in [0, 1].
Eigen::Vector3d ResidualColor(double rms_px, double scale_px);
// A camera the tracker reports suspect (orange), excluded (red) or not judged (violet: never judged since
// the map, e.g. never within the sync window of two others) (camera_health_t::STATE_*;
// MCMT_TRACKER_STATUS) is drawn in this colour, whatever its residual; false for ok (and unknown states).
bool CameraStateColor(int state, Eigen::Vector3d* rgb);
// What follows a flagged camera's name: " (suspect)", " (excluded)", " (not judged)"; "" otherwise.
std::string CameraStateSuffix(int state);
constexpr double kDefaultResidualScalePx = 2.0;

// MRPT frustums look along their +X (Y left, Z up); OpenCV cameras along +Z (X right, Y down).
// cam_from_frustum maps the frustum's axes onto the camera's: X_f -> +Z_c, Y_f -> -X_c, Z_f -> -Y_c.
Rigid3 CamFromFrustum();

// Display frame: world +Z is the cameras' mean "up" (-Y of each camera), world +Y the reference
// camera's viewing direction made horizontal, origin at the rig origin. Returns world_from_rig.
Rigid3 WorldFromRig(const RigMap& map);

struct SceneOptions {
  int width = 1280;  // rendered image / window size, pixels
  int height = 720;
  bool rays = true;  // rays camera -> markers detected in the current frame
  bool legend = true;
  bool grid = true;  // ground grid
  // Residual colour scale (red at and above, green at and below a quarter of it), px; 0: the largest
  // per-camera/marker RMS of the maps shown (colours then change from map to map).
  double residual_scale_px = kDefaultResidualScalePx;
  int trail_max = 20000;        // newest poses kept in the trail
  double azimuth_deg = -120.0;  // automatic view direction (see ViewCamera)
  double elevation_deg = 30.0;
  double fov_deg = 45.0;   // vertical field of view of the viewer's camera
  std::string dictionary;  // marker bitmaps; empty: the map's dictionary
  void Validate() const;   // throws std::invalid_argument naming the option
};

// A map with several bodies (version 2, more than one object) draws every body: each in its own colour
// (BodyColor: an outline around each of its markers, its trail and its name label), static bodies once at
// their rig_from_object, moving bodies at their pose of the current frame. `trajectory` is the first moving
// body's (the map's `markers`, FirstMovingObject), which sets the current frame; the other moving bodies'
// poses are in `bodies` by name, each shown at its newest row not after the current frame's utime (and
// hidden when that row is more than kBodyPoseMaxAgeUs older).
struct PanelInput {
  std::string title;  // "initial", "refined", ...
  RigMap map;
  std::vector<TrajectoryRow> trajectory;
  std::map<std::string, std::vector<TrajectoryRow>> bodies =
      {};  // (= {}: PanelInput{title, map, rows} is fine)
};

// The colour of body k of a map with several bodies (map.objects order), RGB in [0, 1]: magenta, blue,
// pink, violet, brown, then again; none of them a residual colour (green .. red), the trail's orange of a
// single object, the rays' cyan, the neutral light blue or the markers' black and white.
Eigen::Vector3d BodyColor(size_t k);
constexpr int64_t kBodyPoseMaxAgeUs = 500000;

class VizScene {
 public:
  explicit VizScene(SceneOptions options);
  ~VizScene();

  // (Re)builds the scene. With two panels, the first is drawn on the left half and the second on
  // the right half (before/after); the display frame and the view come from the last panel.
  void SetPanels(std::vector<PanelInput> panels);
  bool HasMap() const { return !panels_.empty(); }
  int num_panels() const { return static_cast<int>(panels_.size()); }

  // Live: appends a pose to the last panel's trajectory and makes it the current frame.
  void AddPose(const TrajectoryRow& row);
  // Live: appends a pose of another moving body (by name; a body not in the map is ignored) to the last
  // panel and shows it there (newest = true), or keeps the body at the current frame's row.
  void AddBodyPose(const std::string& body, const TrajectoryRow& row, bool newest = true);
  // The rig_from_object a body is drawn at in a panel (moving: its row shown; static: its pose).
  std::optional<Rigid3> BodyPose(int panel, const std::string& body) const;
  // Current frame: index into the last panel's trajectory (-1: the newest). Other panels show the
  // row with the same seq (or none).
  void SetCurrentFrame(int index);
  int current_frame() const { return current_; }
  const std::vector<TrajectoryRow>& trajectory() const;
  // The current rig_from_object of a panel, if there is one.
  std::optional<Rigid3> CurrentPose(int panel) const;

  // The tracker's camera states (camera_health_t::STATE_* by name), used by the next SetPanels: suspect
  // cameras orange, excluded ones red, not judged ones violet, "(suspect)" / "(excluded)" /
  // "(not judged)" after the name.
  void SetCameraStates(const std::map<std::string, int>& states) { camera_states_ = states; }
  const std::map<std::string, int>& camera_states() const { return camera_states_; }

  // Marker ids each camera detected in the current frame (rays).
  void SetDetections(const std::map<std::string, std::vector<int>>& ids_by_camera);
  void SetRaysVisible(bool visible);
  bool rays_visible() const { return options_.rays; }
  // Text lines drawn at the top left of the image (over the last panel).
  void SetOverlay(const std::vector<std::string>& lines);

  // Views: automatic framing of the rig and the object's trail, following the object, or a view
  // given by the caller (the live window's mouse).
  void AutoView();
  void FollowObject();
  // Close-up: frames the object's markers at the current frame (the view direction kept).
  void FrameObject();
  const ViewCamera& view(int panel) const { return views_.at(panel); }
  void SetView(const ViewCamera& view);  // same orbit for every panel (viewport kept)
  void Resize(int width, int height);

  // Where a rig-frame point lands in the rendered image of panel `panel` (top-left origin,
  // continuous coordinates: the pixel with index (c, r) covers [c, c+1) x [r, r+1)).
  bool ProjectRigPoint(int panel, const Eigen::Vector3d& p_rig, Eigen::Vector2d* pixel) const;
  const Rigid3& world_from_rig() const { return world_from_rig_; }
  double residual_scale_px() const { return residual_scale_; }
  bool has_residuals() const { return has_residuals_; }  // any per-camera/marker RMS in the maps

  mrpt::opengl::COpenGLScene::Ptr scene() const { return scene_; }
  // Copies the panel views into the scene's viewports (call before rendering).
  void ApplyViews();
  // The live window's legend: a viewport of its own (offscreen renders draw it on the image).
  void EnableLegendViewport();
  // Renders offscreen (an EGL context: no display needed) into a BGR image.
  cv::Mat Render(mrpt::opengl::CFBORender* render);

 private:
  struct Panel {
    PanelInput input;
    std::string viewport;
    mrpt::opengl::CSetOfObjects::Ptr root;    // pose world_from_rig: children in the rig frame
    mrpt::opengl::CSetOfObjects::Ptr object;  // pose world_from_rig * rig_from_object
    mrpt::opengl::CSetOfLines::Ptr trail;     // rig frame
    mrpt::opengl::CSetOfLines::Ptr rays;      // rig frame
    int current = -1;                         // row shown, -1: none
    int trail_first = 0, trail_last = -1;     // rows drawn in the trail
    mrpt::opengl::CText::Ptr label;           // several bodies: the name, above the body (world frame)
    double reach = 0.0;                       // the farthest marker corner from the body's origin
    struct Body {                             // the other bodies of a map with several
      std::string name;
      bool is_static = false;
      Rigid3 rig_from_object = Rigid3::Identity();  // static bodies
      size_t object_index = 0;                      // into the map's objects
      mrpt::opengl::CText::Ptr label;
      double reach = 0.0;
      mrpt::opengl::CSetOfObjects::Ptr object;  // pose world_from_rig * rig_from_object
      mrpt::opengl::CSetOfLines::Ptr trail;     // rig frame
      int current = -1;
      int trail_first = 0, trail_last = -1;
    };
    std::vector<Body> bodies;
  };
  void UpdateBodyFrame(Panel* panel, Panel::Body* body, int row);
  // Where a body's name is drawn: above its farthest marker (world +z), in the world frame.
  Eigen::Vector3d LabelPoint(const Rigid3& rig_from_object, double reach) const;
  mrpt::opengl::CText::Ptr MakeLabel(const std::string& name, const Eigen::Vector3d& rgb) const;
  void BuildPanel(Panel* panel);
  void BuildLegend();
  void DrawLegend(cv::Mat* bgr) const;
  void UpdatePanelFrame(Panel* panel, int row);
  void UpdateRays(Panel* panel);
  void UpdateViewports();
  std::vector<Eigen::Vector3d> FramingPoints() const;
  std::string DictionaryName() const;

  SceneOptions options_;
  mrpt::opengl::COpenGLScene::Ptr scene_;
  std::vector<Panel> panels_;
  std::vector<ViewCamera> views_;
  std::map<std::string, int> camera_states_;
  Rigid3 world_from_rig_ = Rigid3::Identity();
  double residual_scale_ = 1.0;
  bool has_residuals_ = false;
  double frustum_length_ = 0.1;
  double floor_z_ = 0.0;
  int current_ = -1;
  bool legend_viewport_ = false;
  std::map<std::string, std::vector<int>> detections_;
  std::vector<std::string> overlay_;
};

}  // namespace mcmt::viz
