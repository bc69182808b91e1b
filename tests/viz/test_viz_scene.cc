// Unit tests of the viewer's scene: colours, frames, the viewer camera's projection against what
// MRPT actually renders offscreen (EGL, no display), frustum direction and marker texture orientation.
#include <gtest/gtest.h>
#include <mrpt/opengl/CFBORender.h>

#include <memory>
#include <opencv2/imgproc.hpp>

#include "core/dictionary.h"
#include "core/lcm_util.h"
#include "core/marker.h"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/tracker_status_t.hpp"
#include "tests/viz/viz_test_util.h"
#include "viz/collector.h"
#include "viz/scene.h"
#include "viz/viewer.h"

namespace mcmt::viz {
namespace {

using testing::MakeTestRig;
using testing::NotBackgroundNear;

// One offscreen renderer for the whole test binary (creating EGL contexts is slow).
mrpt::opengl::CFBORender& Renderer(int w, int h) {
  static std::map<std::pair<int, int>, std::unique_ptr<mrpt::opengl::CFBORender>> renderers;
  auto& r = renderers[{w, h}];
  if (!r) r = std::make_unique<mrpt::opengl::CFBORender>(w, h);
  return *r;
}

// Keeps a rendered image for a look when MCMT_VIZ_DUMP names a folder.
void Dump(const cv::Mat& img, const std::string& name) {
  if (const char* dir = std::getenv("MCMT_VIZ_DUMP")) cv::imwrite(std::string(dir) + "/" + name, img);
}

// w x h, no grid and no legend: only the rig and the object.
SceneOptions BareOptions(int w, int h) {
  SceneOptions o;
  o.width = w;
  o.height = h;
  o.grid = false;
  o.legend = false;
  return o;
}

// The colour of the background: a render of a scene with nothing in it.
cv::Vec3b Background(int w, int h) {
  SceneOptions o;
  o.width = w;
  o.height = h;
  o.legend = false;
  VizScene empty(o);
  cv::Mat img = empty.Render(&Renderer(w, h));
  return img.at<cv::Vec3b>(h / 2, w / 2);
}

TEST(VizColors, ResidualColourGoesFromGreenToRed) {
  // Scale 2 px: green at and below 0.5 px, yellow half-way (1.25 px), red at and above 2 px.
  const Eigen::Vector3d low = ResidualColor(0.5, 2.0), mid = ResidualColor(1.25, 2.0),
                        high = ResidualColor(2.0, 2.0);
  EXPECT_EQ(ResidualColor(0.0, 2.0), low);
  EXPECT_LT(low.x(), 0.05);
  EXPECT_GT(low.y(), 0.8);
  EXPECT_GT(mid.x(), 0.9);
  EXPECT_GT(mid.y(), 0.8);  // yellow
  EXPECT_GT(high.x(), 0.9);
  EXPECT_LT(high.y(), 0.05);
  EXPECT_EQ(ResidualColor(5.0, 2.0), high);  // saturates
  double prev_red = -1;
  for (double v = 0; v <= 2.0; v += 0.1) {
    const Eigen::Vector3d c = ResidualColor(v, 2.0);
    EXPECT_GE(c.x(), prev_red);
    prev_red = c.x();
  }
}

// The worst camera was red whatever its value, so a map changed colour with what it was shown beside.
TEST(VizColors, AMapKeepsItsColoursOnTheAbsoluteScale) {
  const auto rig = MakeTestRig(3, 8);
  RigMap good = rig.map, bad = rig.map;
  for (size_t i = 0; i < good.cameras.size(); ++i) good.cameras[i].rms_px = 0.1 + 0.1 * i;  // <= 0.3 px
  for (auto& c : bad.cameras) c.rms_px += 3.0;
  SceneOptions o;
  o.width = 320;
  o.height = 180;
  VizScene alone(o), beside(o);
  alone.SetPanels({PanelInput{"map", good, rig.trajectory}});
  beside.SetPanels({PanelInput{"initial", bad, rig.trajectory}, PanelInput{"refined", good, rig.trajectory}});
  EXPECT_EQ(alone.residual_scale_px(), kDefaultResidualScalePx);
  EXPECT_EQ(beside.residual_scale_px(), kDefaultResidualScalePx);
  // Every camera of the good map is green (its worst one was drawn red).
  for (const auto& c : good.cameras) {
    const Eigen::Vector3d color = ResidualColor(c.rms_px, alone.residual_scale_px());
    EXPECT_LT(color.x(), 0.05) << c.name << " " << c.rms_px << " px";
  }
}

TEST(VizFrames, FrustumLooksAlongTheOpenCvOpticalAxis) {
  const Rigid3 cam_from_frustum = CamFromFrustum();
  EXPECT_NEAR(cam_from_frustum.linear().determinant(), 1.0, 1e-12);
  // Frustum +X (its axis) is the camera's +Z; frustum +Z (up) is the camera's -Y (image up).
  EXPECT_TRUE((cam_from_frustum.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE((cam_from_frustum.linear() * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitY()));
}

TEST(VizFrames, DisplayFrameHasTheCamerasUpAsZ) {
  const auto rig = MakeTestRig();
  const Rigid3 world_from_rig = WorldFromRig(rig.map);
  // The test cameras sit on a circle, upright: their mean up is the true world up.
  const Eigen::Vector3d true_up_in_rig = rig.world_from_rig.linear().transpose() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d shown_up = world_from_rig.linear() * true_up_in_rig;
  EXPECT_GT(shown_up.z(), std::cos(1.0 * M_PI / 180.0));
  EXPECT_NEAR(world_from_rig.linear().determinant(), 1.0, 1e-9);
}

TEST(VizViewCamera, FramingKeepsEveryPointInside) {
  ViewCamera v;
  v.viewport_width = 800;
  v.viewport_height = 400;
  v.image_height = 400;
  std::vector<Eigen::Vector3d> pts = {{0, 0, 0}, {3, 0, 0}, {0, 2, 1}, {-1, -1, 2}, {1, 1, -0.5}};
  FramePoints(pts, 0.05, &v);
  for (const auto& p : pts) {
    Eigen::Vector2d px;
    ASSERT_TRUE(v.Project(p, &px));
    EXPECT_GE(px.x(), 0.05 * 800 - 1e-6);
    EXPECT_LE(px.x(), 0.95 * 800 + 1e-6);
    EXPECT_GE(px.y(), 0.05 * 400 - 1e-6);
    EXPECT_LE(px.y(), 0.95 * 400 + 1e-6);
  }
  // Tight: 10% closer and some point leaves the margin.
  ViewCamera closer = v;
  closer.distance *= 0.9;
  bool all_inside = true;
  for (const auto& p : pts) {
    Eigen::Vector2d px;
    const bool in = closer.Project(p, &px) && px.x() >= 40 && px.x() <= 760 && px.y() >= 20 && px.y() <= 380;
    all_inside = all_inside && in;
  }
  EXPECT_FALSE(all_inside);
  // The pointing target lands at the viewport centre.
  Eigen::Vector2d c;
  ASSERT_TRUE(v.Project(v.pointing, &c));
  EXPECT_NEAR(c.x(), 400, 1e-6);
  EXPECT_NEAR(c.y(), 200, 1e-6);
}

TEST(VizRender, CamerasAndObjectAppearWhereTheViewerCameraProjectsThem) {
  const int w = 800, h = 450;
  const auto rig = MakeTestRig(4, 12);
  SceneOptions o = BareOptions(w, h);
  VizScene scene(o);
  scene.SetPanels({PanelInput{"map", rig.map, rig.trajectory}});
  scene.SetCurrentFrame(5);
  cv::Mat img = scene.Render(&Renderer(w, h));
  ASSERT_EQ(img.cols, w);
  ASSERT_EQ(img.rows, h);
  const cv::Vec3b bg = Background(w, h);
  for (const auto& cam : rig.map.cameras) {
    Eigen::Vector2d px;
    ASSERT_TRUE(scene.ProjectRigPoint(0, cam.rig_from_cam.translation(), &px)) << cam.name;
    EXPECT_TRUE(NotBackgroundNear(img, px, bg, 1)) << cam.name << " at " << px.transpose();
  }
  Eigen::Vector2d obj;
  ASSERT_TRUE(scene.ProjectRigPoint(0, rig.trajectory[5].rig_from_object.translation(), &obj));
  EXPECT_TRUE(NotBackgroundNear(img, obj, bg, 1)) << "object at " << obj.transpose();

  Dump(img, "cameras_object.png");
  // Control: with camera 2 moved 5 m back (same view, same display frame), its old place is
  // background, so the check can fail.
  RigMap without = rig.map;
  without.cameras[2].rig_from_cam = without.cameras[2].rig_from_cam * Rigid3(Eigen::Translation3d(0, 0, -5));
  VizScene other(o);
  other.SetPanels({PanelInput{"map", without, rig.trajectory}});
  other.SetView(scene.view(0));
  other.SetCurrentFrame(5);
  cv::Mat img2 = other.Render(&Renderer(w, h));
  Eigen::Vector2d px2;
  ASSERT_TRUE(other.ProjectRigPoint(0, rig.map.cameras[2].rig_from_cam.translation(), &px2));
  EXPECT_FALSE(NotBackgroundNear(img2, px2, bg, 1)) << "removed camera still drawn at " << px2.transpose();
}

// Pixels within `radius` of px whose colour passes `looks(r, g, b)`.
template <class Looks>
int PixelsNear(const cv::Mat& bgr, const Eigen::Vector2d& px, int radius, Looks looks) {
  int n = 0;
  for (int y = static_cast<int>(px.y()) - radius; y <= static_cast<int>(px.y()) + radius; ++y)
    for (int x = static_cast<int>(px.x()) - radius; x <= static_cast<int>(px.x()) + radius; ++x) {
      if (x < 0 || y < 0 || x >= bgr.cols || y >= bgr.rows) continue;
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      n += looks(static_cast<double>(p[2]), static_cast<double>(p[1]), static_cast<double>(p[0]));
    }
  return n;
}

// Pixels within `radius` of px that look orange (R high, G about half of R, B low) or red (G and B low).
int ColouredNear(const cv::Mat& bgr, const Eigen::Vector2d& px, bool orange, int radius = 4) {
  return PixelsNear(bgr, px, radius, [orange](double r, double g, double b) {
    if (r < 100 || b > 0.25 * r) return false;
    return orange ? (g > 0.3 * r && g < 0.8 * r) : g < 0.2 * r;
  });
}

// Pixels within `radius` of px that look violet (B high, R above half of B, G below half of R): neither a
// residual colour (B low), nor orange or red, nor the neutral light blue (G high).
int VioletNear(const cv::Mat& bgr, const Eigen::Vector2d& px, int radius = 4) {
  return PixelsNear(bgr, px, radius,
                    [](double r, double g, double b) { return b > 100 && r > 0.5 * b && g < 0.5 * r; });
}

// A 4-camera rig rendered with the tracker's camera states (`states[i]` for camera i) as the live viewer
// receives them (MCMT_TRACKER_STATUS through the collector), and the same view without them; the map has
// no residuals (as from MCMT_MAP): cameras neutral unless flagged.
struct StatesRender {
  std::map<std::string, int> states;  // the collector's
  std::vector<std::string> names;     // the cameras'
  cv::Mat with, without;
  Eigen::Vector2d px[4];  // the cameras in the image
};
StatesRender RenderCameraStates(const std::vector<int8_t>& states, const std::string& dump) {
  const int w = 800, h = 450;
  const auto rig = MakeTestRig(4, 12);
  lcm::LCM lcm("memq://");
  LcmCollector collector(lcm, 0);
  StatesRender out;
  tracker_status_t status;
  for (size_t i = 0; i < rig.map.cameras.size(); ++i) {
    camera_health_t c;
    c.camera = rig.map.cameras[i].name;
    c.state = states.at(i);
    status.cameras.push_back(c);
    out.names.push_back(c.camera);
  }
  status.num_cameras = static_cast<int32_t>(status.cameras.size());
  const std::vector<uint8_t> bytes = Encode(status);
  collector.Handle(kTrackerStatusChannel, bytes.data(), bytes.size());
  EXPECT_EQ(collector.status_count(), 1);
  RigMap map = rig.map;
  for (MapCamera& c : map.cameras) c.rms_px = 0.0;
  for (MapMarker& m : map.markers) m.rms_px = 0.0;
  auto render = [&](const std::map<std::string, int>& with_states, VizScene* scene) {
    scene->SetCameraStates(with_states);
    scene->SetPanels({PanelInput{"map", map, rig.trajectory}});
    scene->SetCurrentFrame(5);
    return scene->Render(&Renderer(w, h));
  };
  out.states = collector.camera_states();
  VizScene flagged(BareOptions(w, h)), plain(BareOptions(w, h));
  out.with = render(out.states, &flagged);
  plain.SetView(flagged.view(0));
  out.without = render({}, &plain);
  Dump(out.with, dump);
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(flagged.ProjectRigPoint(0, map.cameras[i].rig_from_cam.translation(), &out.px[i])) << i;
  return out;
}

TEST(VizRender, SuspectCamerasOrangeExcludedRedFromTheTrackerStatus) {
  const StatesRender r = RenderCameraStates({camera_health_t::STATE_OK, camera_health_t::STATE_SUSPECT,
                                             camera_health_t::STATE_EXCLUDED, camera_health_t::STATE_OK},
                                            "camera_states.png");
  EXPECT_GT(ColouredNear(r.with, r.px[1], true), 3) << "cam 1 (suspect) is not orange";
  EXPECT_GT(ColouredNear(r.with, r.px[2], false), 3) << "cam 2 (excluded) is not red";
  for (int i : {0, 3}) {
    EXPECT_EQ(ColouredNear(r.with, r.px[i], true), 0) << i;
    EXPECT_EQ(ColouredNear(r.with, r.px[i], false), 0) << i;
  }
  // Control: the same scene without the states has neither colour there.
  EXPECT_EQ(ColouredNear(r.without, r.px[1], true), 0);
  EXPECT_EQ(ColouredNear(r.without, r.px[2], false), 0);
}

TEST(VizRender, NotJudgedCamerasVioletFromTheTrackerStatus) {
  const StatesRender r = RenderCameraStates({camera_health_t::STATE_OK, camera_health_t::STATE_NOT_JUDGED,
                                             camera_health_t::STATE_SUSPECT, camera_health_t::STATE_OK},
                                            "camera_not_judged.png");
  ASSERT_EQ(r.states.size(), 4u);
  EXPECT_EQ(r.states.at(r.names[1]), camera_health_t::STATE_NOT_JUDGED);
  EXPECT_GT(VioletNear(r.with, r.px[1]), 3) << "cam 1 (not judged) is not violet";
  EXPECT_EQ(ColouredNear(r.with, r.px[1], true), 0) << "cam 1 (not judged) drawn as suspect";
  EXPECT_EQ(ColouredNear(r.with, r.px[1], false), 0) << "cam 1 (not judged) drawn as excluded";
  EXPECT_GT(ColouredNear(r.with, r.px[2], true), 3) << "cam 2 (suspect) is not orange";
  EXPECT_EQ(VioletNear(r.with, r.px[2]), 0) << "cam 2 (suspect) drawn as not judged";
  for (int i : {0, 3}) EXPECT_EQ(VioletNear(r.with, r.px[i]), 0) << i;
  // Control: the same scene without the states has no violet there (the neutral blue is not violet).
  EXPECT_EQ(VioletNear(r.without, r.px[1]), 0);
  EXPECT_EQ(CameraStateSuffix(camera_health_t::STATE_NOT_JUDGED), " (not judged)");
  EXPECT_EQ(CameraStateSuffix(camera_health_t::STATE_OK), "");
}

TEST(VizRender, FrustumOpensAlongTheCameraZAxis) {
  const int w = 640, h = 480;
  auto rig = MakeTestRig(2, 0);
  SceneOptions o = BareOptions(w, h);
  VizScene scene(o);
  scene.SetPanels({PanelInput{"map", rig.map, {}}});
  cv::Mat img = scene.Render(&Renderer(w, h));
  Dump(img, "frustum.png");
  const cv::Vec3b bg = Background(w, h);
  // Camera 1 (not the reference, so no rig axes there). The frustum is a wireframe drawn to 0.3 x the
  // distance between the cameras (no trajectory): its four edges open along +Z at the camera's field
  // of view; the same distance along -Z is empty space, and so is its axis (no faces).
  const Rigid3& rig_from_cam = rig.map.cameras[1].rig_from_cam;
  const CameraModel& m = rig.map.cameras[1].model;
  const double length =
      0.3 * (rig.map.cameras[0].rig_from_cam.translation() - rig_from_cam.translation()).norm();
  const double tx = 0.5 * m.width / m.fx, ty = 0.5 * m.height / m.fy;
  int edge_hits = 0, edge_points = 0, empty_hits = 0;
  for (double f : {0.5, 0.7, 0.9}) {
    const double d = f * length;
    for (int sx : {-1, 1})
      for (int sy : {-1, 1}) {
        Eigen::Vector2d edge;
        ASSERT_TRUE(
            scene.ProjectRigPoint(0, rig_from_cam * Eigen::Vector3d(sx * tx * d, sy * ty * d, d), &edge));
        edge_hits += NotBackgroundNear(img, edge, bg, 2, 6);
        ++edge_points;
      }
    Eigen::Vector2d axis, back;
    ASSERT_TRUE(scene.ProjectRigPoint(0, rig_from_cam * Eigen::Vector3d(0, 0, d), &axis));
    ASSERT_TRUE(scene.ProjectRigPoint(0, rig_from_cam * Eigen::Vector3d(0, 0, -d), &back));
    empty_hits += NotBackgroundNear(img, axis, bg, 0, 6) + NotBackgroundNear(img, back, bg, 0, 6);
  }
  EXPECT_EQ(edge_hits, edge_points);
  EXPECT_EQ(empty_hits, 0);
}

// The object sits inside every camera's field of view: translucent frustum faces drawn over it hid the
// board of the caliscope rig view. The object's pixels are the same with and without the cameras'
// frustums, but for the few their edges cross.
TEST(VizRender, FrustumsDoNotCoverTheObject) {
  const int w = 800, h = 450;
  const auto rig = MakeTestRig(4, 12);
  SceneOptions o = BareOptions(w, h);
  o.rays = false;
  // The frame whose object is farthest from camera 0's optical axis: the control below draws the rig's axes
  // (at camera 0, along its axis) as long as its cameras are far, and they must not lie on the object.
  size_t frame = 0;
  for (size_t k = 0; k < rig.trajectory.size(); ++k)
    if (rig.trajectory[k].rig_from_object.translation().head<2>().norm() >
        rig.trajectory[frame].rig_from_object.translation().head<2>().norm())
      frame = k;
  VizScene scene(o);
  scene.SetPanels({PanelInput{"map", rig.map, rig.trajectory}});
  scene.SetCurrentFrame(static_cast<int>(frame));
  // Seen from behind camera 0 (a little above it): its frustum lies between the eye and the object.
  const Rigid3 world_from_rig = WorldFromRig(rig.map);
  const Eigen::Vector3d object = world_from_rig * rig.trajectory[frame].rig_from_object.translation();
  const Eigen::Vector3d cam = world_from_rig * rig.map.cameras[0].rig_from_cam.translation();
  const double d = (cam - object).norm();
  const Eigen::Vector3d eye = cam + 0.4 * (cam - object) + Eigen::Vector3d(0, 0, 0.15 * d);
  ViewCamera view = scene.view(0);
  const Eigen::Vector3d dir = (eye - object).normalized();
  view.pointing = object;
  view.distance = (eye - object).norm();
  view.azimuth_deg = std::atan2(dir.y(), dir.x()) * 180.0 / M_PI;
  view.elevation_deg = std::asin(dir.z()) * 180.0 / M_PI;
  view.fov_deg = 20;
  scene.SetView(view);
  const cv::Mat with = scene.Render(&Renderer(w, h)).clone();
  Dump(with, "object_in_frustums.png");
  // Control: the cameras 50 m back along their axes, the same view.
  RigMap far = rig.map;
  for (auto& c : far.cameras) c.rig_from_cam = c.rig_from_cam * Rigid3(Eigen::Translation3d(0, 0, -50));
  VizScene control(o);
  control.SetPanels({PanelInput{"map", far, rig.trajectory}});
  control.SetView(scene.view(0));
  control.SetCurrentFrame(static_cast<int>(frame));
  const cv::Mat without = control.Render(&Renderer(w, h)).clone();
  Dump(without, "object_alone.png");
  // The object's region: the bounding box of its marker corners in the image, where the control draws
  // something (the object).
  cv::Rect2d box(w, h, 0, 0);
  for (const auto& m : rig.map.markers)
    for (const Eigen::Vector3d& c : MarkerCornersInMarker(m.size)) {
      Eigen::Vector2d px;
      const Eigen::Vector3d p =
          world_from_rig * (rig.trajectory[frame].rig_from_object * (m.object_from_marker * c));
      ASSERT_TRUE(view.Project(p, &px));
      box |= cv::Rect2d(px.x(), px.y(), 1, 1);
    }
  const cv::Vec3b bg = Background(w, h);
  int object_pixels = 0, changed = 0;
  for (int y = std::max(0, int(box.y)); y < std::min(h, int(box.br().y)); ++y)
    for (int x = std::max(0, int(box.x)); x < std::min(w, int(box.br().x)); ++x) {
      const cv::Vec3b a = with.at<cv::Vec3b>(y, x), b = without.at<cv::Vec3b>(y, x);
      bool is_object = false, differs = false;
      for (int c = 0; c < 3; ++c) {
        is_object = is_object || std::abs(int(b[c]) - int(bg[c])) > 20;
        differs = differs || std::abs(int(a[c]) - int(b[c])) > 24;
      }
      object_pixels += is_object;
      changed += is_object && differs;
    }
  ASSERT_GT(object_pixels, 1000) << "the object should be in view";
  RecordProperty("object pixels covered", std::to_string(changed) + " of " + std::to_string(object_pixels));
  EXPECT_LT(changed, object_pixels / 20) << changed << " of " << object_pixels << " object pixels covered";
}

TEST(VizRender, MarkerTextureIsUprightWithArucoTopLeftAtMinusXPlusY) {
  const int w = 640, h = 640;
  auto rig = MakeTestRig(4, 1);
  SceneOptions o = BareOptions(w, h);
  o.rays = false;
  VizScene scene(o);
  scene.SetPanels({PanelInput{"map", rig.map, rig.trajectory}});
  scene.SetCurrentFrame(0);
  const auto dict = LoadDictionary("DICT_4X4_50");
  const int cells = dict->markerSize + 2;
  for (const auto& marker : rig.map.markers) {
    SCOPED_TRACE("marker " + std::to_string(marker.id));
    const Rigid3 rig_from_marker = rig.trajectory[0].rig_from_object * marker.object_from_marker;
    // Look straight at the marker's face from 0.35 m.
    const Rigid3 world_from_marker = scene.world_from_rig() * rig_from_marker;
    const Eigen::Vector3d n = world_from_marker.linear().col(2);
    ViewCamera v = scene.view(0);
    v.pointing = world_from_marker.translation();
    v.azimuth_deg = std::atan2(n.y(), n.x()) * 180.0 / M_PI;
    v.elevation_deg = std::asin(std::clamp(n.z(), -1.0, 1.0)) * 180.0 / M_PI;
    v.distance = 0.35;
    v.fov_deg = 30;
    scene.SetView(v);
    cv::Mat img = scene.Render(&Renderer(w, h));
    Dump(img, "marker_" + std::to_string(marker.id) + ".png");
    cv::Mat gray;
    cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
    const cv::Mat bitmap = MarkerImage(*dict, marker.id, cells * 10);
    // Sample each cell's centre; compare to the bitmap, and to the bitmap flipped upside down.
    std::vector<double> values;
    std::vector<int> truth, flipped;
    for (int r = 0; r < cells; ++r) {
      for (int c = 0; c < cells; ++c) {
        const double s = marker.size;
        const Eigen::Vector3d p_marker(-s / 2 + (c + 0.5) * s / cells, s / 2 - (r + 0.5) * s / cells, 0);
        Eigen::Vector2d px;
        ASSERT_TRUE(scene.ProjectRigPoint(0, rig_from_marker * p_marker, &px));
        const cv::Rect patch(static_cast<int>(px.x()) - 1, static_cast<int>(px.y()) - 1, 3, 3);
        values.push_back(cv::mean(gray(patch))[0]);
        truth.push_back(bitmap.at<uchar>(r * 10 + 5, c * 10 + 5) > 127);
        flipped.push_back(bitmap.at<uchar>((cells - 1 - r) * 10 + 5, c * 10 + 5) > 127);
      }
    }
    const double lo = *std::min_element(values.begin(), values.end());
    const double hi = *std::max_element(values.begin(), values.end());
    ASSERT_GT(hi - lo, 60) << "no contrast: the marker is not textured";
    int match = 0, match_flipped = 0;
    for (size_t i = 0; i < values.size(); ++i) {
      const int seen = values[i] > 0.5 * (lo + hi);
      match += seen == truth[i];
      match_flipped += seen == flipped[i];
    }
    EXPECT_EQ(match, cells * cells);
    EXPECT_LT(match_flipped, cells * cells);
  }
}

TEST(VizRender, BackgroundColourIsKnown) {
  const cv::Vec3b measured = Background(64, 48), expected = BackgroundBgr();
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(measured[c], expected[c], 2);
}

TEST(VizRender, BeforeAfterPanelsSitSideBySide) {
  const int w = 960, h = 400;
  const auto rig = MakeTestRig(3, 8);
  RigMap initial = rig.map;
  for (auto& c : initial.cameras) c.rig_from_cam.translation() += Eigen::Vector3d(0.05, -0.03, 0.04);
  for (auto& c : initial.cameras) c.rms_px += 3.0;
  SceneOptions o;
  o.width = w;
  o.height = h;
  o.grid = false;
  VizScene scene(o);
  scene.SetPanels(
      {PanelInput{"initial", initial, rig.trajectory}, PanelInput{"refined", rig.map, rig.trajectory}});
  ASSERT_EQ(scene.num_panels(), 2);
  EXPECT_EQ(scene.view(0).viewport_width, w / 2);
  EXPECT_EQ(scene.view(1).viewport_x, w / 2);
  EXPECT_EQ(scene.residual_scale_px(), kDefaultResidualScalePx);  // absolute, whatever the maps
  cv::Mat img = scene.Render(&Renderer(w, h));
  Dump(img, "before_after.png");
  const cv::Vec3b bg = Background(w, h);
  for (int panel = 0; panel < 2; ++panel) {
    const RigMap& map = panel == 0 ? initial : rig.map;
    for (const auto& cam : map.cameras) {
      Eigen::Vector2d px;
      ASSERT_TRUE(scene.ProjectRigPoint(panel, cam.rig_from_cam.translation(), &px));
      EXPECT_EQ(px.x() >= w / 2, panel == 1);
      EXPECT_TRUE(NotBackgroundNear(img, px, bg, 1)) << "panel " << panel << " " << cam.name;
    }
  }
}

TEST(VizRender, ObjectCloseUpFillsTheView) {
  const int w = 640, h = 400;
  const auto rig = MakeTestRig(4, 6);
  SceneOptions o = BareOptions(w, h);
  o.rays = false;
  VizScene scene(o);
  scene.SetPanels({PanelInput{"map", rig.map, rig.trajectory}});
  scene.SetCurrentFrame(3);
  scene.FrameObject();
  cv::Mat img = scene.Render(&Renderer(w, h));
  Dump(img, "object.png");
  double top = h, bottom = 0;
  const Rigid3& rig_from_object = rig.trajectory[3].rig_from_object;
  for (const auto& m : rig.map.markers) {
    for (const auto& corner : MarkerCornersInMarker(m.size)) {
      Eigen::Vector2d px;
      ASSERT_TRUE(scene.ProjectRigPoint(0, rig_from_object * (m.object_from_marker * corner), &px));
      top = std::min(top, px.y());
      bottom = std::max(bottom, px.y());
    }
  }
  EXPECT_GT(bottom - top, 0.5 * h);
  // Most of the object's silhouette is drawn: pixels differ from the background there.
  cv::Mat diff;
  cv::absdiff(img, cv::Scalar(BackgroundBgr()[0], BackgroundBgr()[1], BackgroundBgr()[2]), diff);
  cv::Mat gray;
  cv::cvtColor(diff, gray, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(gray > 20), 0.1 * w * h);
}

TEST(VizLive, ManyPosesKeepBoundedRowsAndShowTheNewest) {
  const auto rig = MakeTestRig(3, 1);
  SceneOptions o;
  o.trail_max = 2000;
  VizScene scene(o);
  scene.SetPanels({PanelInput{"live", rig.map, {}}});
  EXPECT_FALSE(scene.CurrentPose(0).has_value());
  TrajectoryRow row = rig.trajectory[0];
  for (int i = 0; i < 30000; ++i) {
    row.seq = i;
    row.rig_from_object.translation().x() = 1e-4 * i;
    scene.AddPose(row);
  }
  EXPECT_LT(scene.trajectory().size(), 10000u);
  EXPECT_GE(scene.trajectory().size(), 2000u);
  EXPECT_EQ(scene.trajectory().back().seq, 29999);
  ASSERT_TRUE(scene.CurrentPose(0).has_value());
  EXPECT_DOUBLE_EQ(scene.CurrentPose(0)->translation().x(), 1e-4 * 29999);
}

TEST(VizOptions, SizeParsing) {
  int w = 0, h = 0;
  ParseSize("1280x720", &w, &h);
  EXPECT_EQ(w, 1280);
  EXPECT_EQ(h, 720);
  EXPECT_THROW(ParseSize("1280", &w, &h), std::invalid_argument);
  EXPECT_THROW(ParseSize("12x720", &w, &h), std::invalid_argument);
  EXPECT_THROW(ParseSize("1280x720x3", &w, &h), std::invalid_argument);
}

}  // namespace
// MCMT_MAP through the collector: the mapper's rig_map2_t (here with two bodies) and an old log's
// rig_map_t both become the map drawn (core's DecodeMapMessage); anything else is counted, not drawn.
TEST(VizCollector, TakesMapsOfEitherType) {
  const auto rig = MakeTestRig(3, 4);
  RigMap bodies = rig.map;
  for (const char* name : {"tool", "patient"}) {
    MapObject o;
    o.name = name;
    o.markers = {rig.map.markers[o.name == "tool" ? 0 : 1]};
    o.reference_marker = o.markers[0].id;
    bodies.objects.push_back(o);
  }
  bodies.version = kMapVersionBodies;
  lcm::LCM lcm("memq://");
  LcmCollector collector(lcm, 0);
  const std::vector<uint8_t> v2 = Encode(ToRigMap2Msg(bodies, 5));
  collector.Handle(kMapChannel, v2.data(), v2.size());
  ASSERT_TRUE(collector.has_map());
  EXPECT_EQ(collector.map().objects.size(), 2u);
  EXPECT_EQ(collector.map().objects[1].name, "patient");
  const std::vector<uint8_t> v1 = Encode(ToRigMapMsg(rig.map, 6));
  collector.Handle(kMapChannel, v1.data(), v1.size());
  EXPECT_EQ(collector.map_count(), 2);
  EXPECT_TRUE(collector.map().objects.empty());
  EXPECT_EQ(collector.map().markers.size(), rig.map.markers.size());
  const std::vector<uint8_t> other = Encode(mcmt::tracker_status_t());
  collector.Handle(kMapChannel, other.data(), other.size());
  EXPECT_EQ(collector.map_count(), 2);
  EXPECT_EQ(collector.stats().decode_errors, 1);
}

// A pose stream renamed by tracker.channels ({tool: NAV}) reaches the live viewer through its
// subscription (every channel, poses told by type) under the body its object field names; a foreign
// message on another channel is not a pose.
TEST(VizCollector, RenamedPoseChannelIsTheBodyOfItsObjectField) {
  lcm::LCM lcm("memq://");
  LcmCollector collector(lcm, 0);
  for (int64_t seq = 0; seq < 3; ++seq) {
    object_pose_t p{};
    p.utime = 1000 + seq;
    p.seq = seq;
    p.object = "tool";
    p.status = object_pose_t::STATUS_TRACKING;
    Rigid3 pose = Rigid3::Identity();
    pose.translation().x() = 0.1 * static_cast<double>(seq);
    p.rig_from_object = ToPose3d(pose);
    const std::vector<uint8_t> data = Encode(p);
    lcm.publish("NAV", data.data(), static_cast<unsigned>(data.size()));
  }
  const std::vector<uint8_t> other(40, 7);
  lcm.publish("OTHER", other.data(), static_cast<unsigned>(other.size()));
  while (lcm.handleTimeout(50) > 0) {
  }
  ASSERT_EQ(collector.body_poses().size(), 1u);
  const PoseStream& tool = collector.body_poses().at("tool");
  ASSERT_EQ(tool.rows.size(), 3u);
  EXPECT_DOUBLE_EQ(tool.rows[2].rig_from_object.translation().x(), 0.2);
  EXPECT_TRUE(collector.poses().empty());
}

}  // namespace mcmt::viz
