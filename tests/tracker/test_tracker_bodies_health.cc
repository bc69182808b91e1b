// Camera health with several bodies (issue 17): every camera is judged on the bodies it sees (its
// residuals under each body's pose from the other cameras, pooled), so a camera that sees only the second
// body is judged too, and one bumped is suspected and excluded from every body's pose. On the simulator's
// bodies scene (bodies_session.h: tool, patient, static floor; 5 cameras, 300 frames) with the mapper's map
// of the unbumped session; the same session generated again with a camera bumped (mcmt-sim --move-camera).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <vector>

#include "core/stop.h"
#include "tests/tracker/bodies_session.h"
#include "tracker/tracker.h"

namespace mcmt {
namespace {

using tracker_test::Bodies;
using tracker_test::BodiesSession;

constexpr int kFrames = 300;        // the bodies session's
constexpr int kBumpFrame = 150;     // the bump
constexpr char kCamera[] = "cam3";  // the camera that sees only the patient (the tool hidden from it)

bool IsTool(int id) { return id >= 0 && id <= 3; }  // the tool's ids (sim/scene_bodies.cc: four_sided 0-3)

// The session's messages with the tool's markers taken out of kCamera's (as if the tool were outside its
// view): kCamera sees the patient and the floor only.
std::vector<detections_t> PatientOnlyFor(const std::string& camera, std::vector<detections_t> messages) {
  for (detections_t& d : messages) {
    if (d.camera != camera) continue;
    d.markers.erase(
        std::remove_if(d.markers.begin(), d.markers.end(), [](const marker_t& m) { return IsTool(m.id); }),
        d.markers.end());
    d.num_markers = static_cast<int32_t>(d.markers.size());
  }
  return messages;
}

struct Health {
  std::vector<CameraHealth> cameras;
  int64_t tool_posed = 0, patient_posed = 0;
  const CameraHealth& Of(const std::string& name) const {
    for (const CameraHealth& h : cameras)
      if (h.camera == name) return h;
    throw std::out_of_range(name);
  }
};

// Tracks `messages` with the session's map and the rig's tracker options.
Health Track(const BodiesSession& s, const std::vector<detections_t>& messages, const std::string& name) {
  const std::string log = s.dir->File(name + ".lcmlog");
  sim::WriteMessagesLog(log, messages);
  const RigConfig rig = LoadRigConfig(s.dir->File("rig.yaml"));
  TrackerNodeOptions options;
  options.tracker = TrackerOptions::FromConfig(rig);
  options.log_mode = true;
  options.quiet = true;
  lcm::LCM input("memq://");
  TrackerNode node(input, rig, options, s.map);
  node.RunLog(log, StopToken());
  Health out;
  out.cameras = node.health()->Snapshot();
  for (const PoseStream& st : node.streams()) {
    if (st.name == "tool") out.tool_posed = st.tracked;
    if (st.name == "patient") out.patient_posed = st.tracked;
  }
  return out;
}

int64_t Frame(int64_t utime) { return std::llround(30e-6 * static_cast<double>(utime - sim::kStartUtime)); }

// The bodies session generated again with kCamera bumped by 0.5 deg (a pan) at kBumpFrame.
std::vector<detections_t> BumpedMessages() {
  test::TempDir dir("tracker_bodies_bump");
  sim::DatasetOptions o = sim::DetectionsOnlySession(dir.str(), kFrames, 1);
  o.moves = {{kCamera, kBumpFrame, 0.5, 0.0}};
  const sim::DatasetSummary summary = sim::GenerateBodiesDataset(o);
  EXPECT_EQ(summary.truth.moves.size(), 1u);
  std::vector<detections_t> out;
  for (const LogEvent& e : ReadEventLog(dir.File("detections.lcmlog"))) {
    detections_t d;
    if (Decode(e.data.data(), e.data.size(), &d)) out.push_back(d);
  }
  return out;
}

// Without a bump: every camera judged (kCamera on the patient alone), none ever suspect.
TEST(TrackerBodiesHealth, NoAlarmWithoutABumpAndACameraOnTheSecondBodyIsJudged) {
  const BodiesSession& s = Bodies();
  const Health run = Track(s, PatientOnlyFor(kCamera, s.detections), "quiet");
  ASSERT_EQ(run.cameras.size(), 5u);
  for (const CameraHealth& h : run.cameras) {
    std::cout << "[ health ] " << h.camera << ": " << CameraStateName(h.state) << ", " << h.frames
              << " frames judged, rms " << h.rms_px << " px, baseline " << h.baseline_px << " px\n";
    EXPECT_EQ(h.state, CameraState::kOk) << h.camera;
    EXPECT_EQ(h.first_suspect_utime, -1) << h.camera;
    EXPECT_GT(h.frames, kFrames / 2) << h.camera;
  }
  EXPECT_GT(run.patient_posed, 0.9 * kFrames);
}

// kCamera, seeing only the patient, bumped by 0.5 deg at frame 150: suspect within 30 frames and excluded;
// the other cameras never suspect.
TEST(TrackerBodiesHealth, ABumpedCameraThatSeesOnlyTheSecondBodyIsSuspectedAndExcluded) {
  const BodiesSession& s = Bodies();
  const Health run = Track(s, PatientOnlyFor(kCamera, BumpedMessages()), "bumped");
  ASSERT_EQ(run.cameras.size(), 5u);
  for (const CameraHealth& h : run.cameras) {
    std::cout << "[ health ] " << h.camera << ": " << CameraStateName(h.state) << " since frame "
              << (h.since_utime > 0 ? Frame(h.since_utime) : 0) << ", first suspect at frame "
              << (h.first_suspect_utime < 0 ? -1 : Frame(h.first_suspect_utime)) << ", " << h.frames
              << " frames judged, rms " << h.rms_px << " px, baseline " << h.baseline_px << " px\n";
    if (h.camera != kCamera) {
      EXPECT_EQ(h.state, CameraState::kOk) << h.camera;
      EXPECT_EQ(h.first_suspect_utime, -1) << h.camera;
      continue;
    }
    EXPECT_EQ(h.state, CameraState::kExcluded);
    EXPECT_GE(h.first_suspect_utime, sim::FrameUtime(kBumpFrame, 30.0));
    EXPECT_LE(h.first_suspect_utime, sim::FrameUtime(kBumpFrame + 30, 30.0));
    EXPECT_LE(h.since_utime, sim::FrameUtime(kBumpFrame + 30, 30.0));
  }
  EXPECT_GT(run.patient_posed, 0.9 * kFrames);
}

}  // namespace
}  // namespace mcmt
