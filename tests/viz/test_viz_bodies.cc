// The viewer with several rigid bodies (issue 16), rendered offscreen (EGL): two moving bodies and a
// static floor, each in its own colour where its markers project, with its trail and its name; measured
// on the pixels of the render, with controls that show the checks can fail.
#include <gtest/gtest.h>
#include <mrpt/opengl/CFBORender.h>

#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "core/marker.h"
#include "tests/viz/viz_test_util.h"
#include "viz/scene.h"

namespace mcmt::viz {
namespace {

using testing::BodiesTestRig;
using testing::BodyPixelsIn;
using testing::BodyPixelsNear;
using testing::MakeBodiesTestRig;
using testing::Outline;
using testing::OutlineHits;

constexpr int kW = 1280, kH = 720;

mrpt::opengl::CFBORender& Renderer() {
  static std::unique_ptr<mrpt::opengl::CFBORender> r = std::make_unique<mrpt::opengl::CFBORender>(kW, kH);
  return *r;
}

void Dump(const cv::Mat& img, const std::string& name) {
  if (const char* dir = std::getenv("MCMT_VIZ_DUMP")) cv::imwrite(std::string(dir) + "/" + name, img);
}

SceneOptions Options() {
  SceneOptions o;
  o.width = kW;
  o.height = kH;
  o.grid = false;
  o.legend = false;
  o.rays = false;
  return o;
}

TEST(VizBodies, EachBodyInItsColourWhereItsMarkersProjectWithTrailAndName) {
  const BodiesTestRig rig = MakeBodiesTestRig(24);
  VizScene scene(Options());
  PanelInput in{"map", rig.map, rig.trajectory, rig.bodies};
  scene.SetPanels({in});
  const int frame = 17;
  scene.SetCurrentFrame(frame);
  const cv::Mat img = scene.Render(&Renderer());
  Dump(img, "bodies.png");

  // The bodies are where the inputs put them.
  ASSERT_TRUE(scene.BodyPose(0, "patient").has_value());
  EXPECT_LT(
      TranslationDistance(*scene.BodyPose(0, "patient"), rig.bodies.at("patient")[frame].rig_from_object),
      1e-12);
  EXPECT_LT(TranslationDistance(*scene.BodyPose(0, "floor"), rig.map.objects[2].rig_from_object), 1e-12);

  for (size_t k = 0; k < 3; ++k) {
    const OutlineHits h = Outline(scene, img, rig.map, k);
    std::printf("%-8s outline points %d: own colour %d, another body's %d\n", rig.map.objects[k].name.c_str(),
                h.points, h.own, h.other);
    ASSERT_GT(h.points, 0);
    // Cube faces turned away or hidden by the cube's own faces: most, not all, outline points show.
    EXPECT_GE(h.own, 0.5 * h.points) << rig.map.objects[k].name;
    // Another body's colour only where its trail passes close by (1 point of 20 or 32 measured).
    EXPECT_LE(h.other, h.points / 10) << rig.map.objects[k].name;
  }

  // Trails: the moving bodies' positions of frames 3..12 (away from their current pose) lie on a line of
  // their colour.
  for (size_t k = 0; k < 2; ++k) {
    const auto& rows = k == 0 ? rig.trajectory : rig.bodies.at("patient");
    int on = 0, n = 0;
    for (int i = 3; i <= 12; ++i) {
      Eigen::Vector2d px;
      ASSERT_TRUE(scene.ProjectRigPoint(0, rows[i].rig_from_object.translation(), &px));
      ++n;
      if (BodyPixelsNear(img, px, k, 2) > 0) ++on;
    }
    EXPECT_GE(on, 8) << rig.map.objects[k].name << " trail: " << on << " of " << n;
  }

  // Names: text of the body's colour right of the label's anchor, above the body (no marker there).
  const Rigid3 rig_from_world = Inverse(scene.world_from_rig());
  for (size_t k = 0; k < 3; ++k) {
    const Rigid3 pose = *scene.BodyPose(0, rig.map.objects[k].name);
    double reach = 0.0;
    for (const MapMarker& m : rig.map.objects[k].markers)
      reach = std::max(reach, m.object_from_marker.translation().norm() + m.size);
    // The anchor (VizScene::LabelPoint): above the body's origin by its reach and a quarter frustum.
    Eigen::Vector2d origin_px, anchor_px;
    ASSERT_TRUE(scene.ProjectRigPoint(0, pose.translation(), &origin_px));
    const Eigen::Vector3d world_anchor = scene.world_from_rig() * pose.translation();
    bool found = false;
    for (double up = reach; up < reach + 0.5 && !found; up += 0.01) {  // the frustum length is the scene's
      ASSERT_TRUE(
          scene.ProjectRigPoint(0, rig_from_world * (world_anchor + Eigen::Vector3d(0, 0, up)), &anchor_px));
      found =
          BodyPixelsIn(img, static_cast<int>(anchor_px.x()), static_cast<int>(anchor_px.y()) - 14,
                       static_cast<int>(anchor_px.x()) + 8 * static_cast<int>(rig.map.objects[k].name.size()),
                       static_cast<int>(anchor_px.y()) + 2, k) >= 15;
    }
    EXPECT_TRUE(found) << rig.map.objects[k].name << ": no label of its colour above it";
  }

  // Control: the same map as one object (version 1) draws none of the body colours.
  RigMap single = rig.map;
  single.objects.clear();
  VizScene plain(Options());
  plain.SetPanels({PanelInput{"map", single, rig.trajectory, {}}});
  plain.SetView(scene.view(0));
  plain.SetCurrentFrame(frame);
  const cv::Mat img1 = plain.Render(&Renderer());
  Dump(img1, "bodies_single.png");
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(BodyPixelsIn(img1, 0, 0, kW, kH, k), 0) << k;
}

TEST(VizBodies, LivePosesOfAnotherBodyMoveItAndItsTrail) {
  const BodiesTestRig rig = MakeBodiesTestRig(24);
  VizScene scene(Options());
  PanelInput in{"live", rig.map, {}, {}};
  scene.SetPanels({in});
  EXPECT_FALSE(scene.BodyPose(0, "patient").has_value());  // no pose yet
  EXPECT_TRUE(scene.BodyPose(0, "floor").has_value());     // static: always drawn
  for (int i = 0; i < 10; ++i) {
    scene.AddPose(rig.trajectory[i]);
    scene.AddBodyPose("patient", rig.bodies.at("patient")[i]);
  }
  scene.AddBodyPose("nobody", rig.trajectory[0]);  // not a body of the map: ignored
  ASSERT_TRUE(scene.BodyPose(0, "patient").has_value());
  EXPECT_LT(TranslationDistance(*scene.BodyPose(0, "patient"), rig.bodies.at("patient")[9].rig_from_object),
            1e-12);
  EXPECT_LT(TranslationDistance(*scene.BodyPose(0, "tool"), rig.trajectory[9].rig_from_object), 1e-12);
  // Browsing back to frame 4 shows the patient's row of frame 4's time.
  scene.SetCurrentFrame(4);
  EXPECT_LT(TranslationDistance(*scene.BodyPose(0, "patient"), rig.bodies.at("patient")[4].rig_from_object),
            1e-12);
  // A body whose newest pose is older than kBodyPoseMaxAgeUs at the frame shown is hidden.
  TrajectoryRow late = rig.trajectory[9];
  late.utime += 2 * kBodyPoseMaxAgeUs;
  late.seq = 100;
  scene.AddPose(late);
  EXPECT_FALSE(scene.BodyPose(0, "patient").has_value());
}

}  // namespace
}  // namespace mcmt::viz
