// mcmt-tracker as a real process with several bodies (issue 16): the sim's bodies scene and mcmt-mapper's
// map (two moving bodies and the static floor), detections published live over udpm on loopback (port
// 7940), a subscriber checks each channel's poses against the truth; --out writes one file per stream;
// bad streams stop it with one line (ports 7940-7949 belong to this file).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/udpm.h"
#include "tests/tracker/bodies_session.h"

namespace mcmt {
namespace {

using tracker_test::Bodies;
using tracker_test::BodiesSession;

const std::string kTracker = test::Bin("mcmt-tracker");
using test::UdpmUrl;

struct Received {
  std::map<std::string, std::map<int64_t, object_pose_t>> by_channel;  // channel -> seq -> pose
  void OnPose(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    object_pose_t msg;
    if (Decode(rbuf->data, rbuf->data_size, &msg)) by_channel[channel][msg.seq] = msg;
  }
  size_t Count(const std::string& channel) const {
    const auto it = by_channel.find(channel);
    return it == by_channel.end() ? 0 : it->second.size();
  }
};

TEST(TrackerBodiesProcess, EachBodyOnItsChannelOverUdpm) {
  const BodiesSession& s = Bodies();
  const std::string url = UdpmUrl(7940);
  lcm::LCM lcm(url + "&recv_buf_size=4194304");
  if (!lcm.good()) GTEST_SKIP() << "no multicast (ip route add 224.0.0.0/4 dev lo): " << url;
  Received got;
  lcm.subscribe("MCMT_POSE.*", &Received::OnPose, &got)->setQueueCapacity(100000);
  const std::string rig = s.Rig("rig_process.yaml", "tracker:\n  relative: [{of: tool, in: patient}]\n");
  const std::string err = s.dir->File("tracker_process.err"), out = s.dir->File("poses.csv");
  test::Child tracker({kTracker, "--config", rig, "--map", s.map_path, "--lcm-url", url, "--out", out}, err);
  ASSERT_TRUE(test::WaitForText(err, "ready", 20)) << test::ReadText(err);
  EXPECT_NE(test::ReadText(err).find("poses on MCMT_POSE_TOOL, MCMT_POSE_PATIENT, MCMT_POSE_TOOL_IN_PATIENT"),
            std::string::npos)
      << test::ReadText(err);
  // Frame by frame, every camera's message, then a little time to receive.
  int64_t seq = -1;
  for (const detections_t& d : s.detections) {
    if (d.seq != seq) {
      seq = d.seq;
      const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(3);
      while (std::chrono::steady_clock::now() < until) lcm.handleTimeout(1);
    }
    lcm.publish(DetectionsChannel(d.camera), &d);
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (got.Count("MCMT_POSE_TOOL_IN_PATIENT") < 300 && std::chrono::steady_clock::now() < end)
    lcm.handleTimeout(20);
  // While it runs, every published pose is already in its stream's partial file (what survives a crash).
  for (const char* name : {"tool", "patient", "tool_in_patient"}) {
    const std::string partial = test::ReadText(s.dir->File(std::string("poses_") + name + ".csv.partial"));
    EXPECT_GE(std::count(partial.begin(), partial.end(), '\n'), 286) << name;  // header + >= 285 poses
  }
  EXPECT_TRUE(test::ReadText(out + ".partial").empty());  // several bodies: no single partial file
  tracker.Signal(SIGTERM);
  EXPECT_EQ(tracker.Wait(20), 0) << test::ReadText(err);
  const std::string log = test::ReadText(err);

  // Nothing on MCMT_POSE or for the floor; every frame on each stream (loopback loses none at this pace;
  // a few frames of slack for a loaded machine).
  EXPECT_EQ(got.by_channel.size(), 3u) << log;
  std::map<std::string, std::vector<object_pose_t>> poses;
  for (const char* channel : {"MCMT_POSE_TOOL", "MCMT_POSE_PATIENT", "MCMT_POSE_TOOL_IN_PATIENT"}) {
    EXPECT_GE(got.Count(channel), 295u) << channel << "\n" << log;
    for (const auto& [seq_, msg] : got.by_channel[channel]) poses[channel].push_back(msg);
  }
  std::map<std::string, sim::EvalResult> eval;
  for (const auto& [body, channel] :
       std::map<std::string, std::string>{{"tool", "MCMT_POSE_TOOL"}, {"patient", "MCMT_POSE_PATIENT"}}) {
    std::vector<TrajectoryRow> rows;
    for (const object_pose_t& m : poses[channel]) {
      EXPECT_EQ(m.object, body);
      if (m.status != object_pose_t::STATUS_LOST) rows.push_back(FromObjectPoseMsg(m));
    }
    eval[body] = tracker_test::EvaluateBody(s, body, rows);
    const sim::EvalResult& e = eval[body];
    std::cout << body << " over udpm: " << rows.size() << " poses, " << e.object_translation_mm.mean
              << " mm mean / " << e.object_translation_mm.max << " mm max\n";
    EXPECT_GE(rows.size(), 285u);
    EXPECT_LT(e.object_translation_mm.mean, 0.3);
    EXPECT_LT(e.object_translation_mm.max, 1.0);
    EXPECT_LT(e.object_rotation_deg.mean, 0.15);
    // --out: the same poses in OUT's name + _NAME.
    const std::vector<TrajectoryRow> file = ReadTrajectory(s.dir->File("poses_" + body + ".csv"));
    EXPECT_EQ(file.size(), rows.size());
  }
  std::vector<double> rel_mm;
  for (const object_pose_t& m : poses["MCMT_POSE_TOOL_IN_PATIENT"]) {
    if (m.status == object_pose_t::STATUS_LOST) continue;
    const Rigid3 gt_t = eval["tool"].gt_object_from_est_object,
                 gt_p = eval["patient"].gt_object_from_est_object;
    const Rigid3 truth = tracker_test::TrueRelative(s, "tool", "patient", m.seq, gt_t, gt_p);
    rel_mm.push_back(1e3 * TranslationDistance(gt_p * FromPose3d(m.rig_from_object) * Inverse(gt_t),
                                               gt_p * truth * Inverse(gt_t)));
  }
  const sim::Stats rel = sim::ComputeStats(rel_mm);
  std::cout << "tool_in_patient over udpm: " << rel.count << " poses, " << rel.mean << " mm mean / "
            << rel.max << " mm max\n";
  EXPECT_GE(rel.count, 285);
  EXPECT_LT(rel.mean, 0.6);
  EXPECT_LT(rel.max, 2.0);
  EXPECT_EQ(ReadTrajectory(s.dir->File("poses_tool_in_patient.csv")).size(), static_cast<size_t>(rel.count));
  EXPECT_TRUE(test::ReadText(s.dir->File("poses_tool.csv.partial")).empty());  // removed at a clean exit
  EXPECT_TRUE(test::ReadText(out + ".partial").empty());
}

// Bad streams: the process does not start, one line naming the file, the key and the name.
TEST(TrackerBodiesProcess, BadStreamsStopItWithOneLine) {
  const BodiesSession& s = Bodies();
  const std::string url = UdpmUrl(7941);
  struct Case {
    std::string section, expected;
  };
  const std::vector<Case> cases = {
      {"tracker:\n  relative: [{of: tool, in: patinet}]\n",
       "tracker.relative[0].in: no body named 'patinet' (bodies: tool, patient, floor)"},
      {"tracker:\n  channels: {tool: MCMT_POSE_PATIENT}\n",
       "tracker.channels.tool: channel MCMT_POSE_PATIENT of 'tool' is also 'patient''s"},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    const std::string rig = s.Rig("rig_bad_" + std::to_string(k) + ".yaml", cases[k].section);
    const test::ProcessResult r = test::RunCommand(
        kTracker + " --config " + rig + " --map " + s.map_path + " --lcm-url '" + url + "'", 30);
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("rig_bad_" + std::to_string(k) + ".yaml: " + cases[k].expected),
              std::string::npos)
        << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
}

}  // namespace
}  // namespace mcmt
