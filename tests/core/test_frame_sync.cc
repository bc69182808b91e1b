#include <gtest/gtest.h>

#include "core/frame_sync.h"

namespace mcmt {
namespace {

constexpr int64_t kPeriod = 33333;

detections_t View(const std::string& camera, int64_t frame, int64_t jitter_us = 0) {
  detections_t d;
  d.utime = 1000000 + frame * kPeriod + jitter_us;
  d.seq = frame;
  d.camera = camera;
  d.dictionary = "DICT_6X6_250";
  d.num_markers = 0;
  d.detection_ms = 0;
  return d;
}

void Append(std::vector<SyncedFrame>* out, std::vector<SyncedFrame> more) {
  for (auto& f : more) out->push_back(std::move(f));
}

std::vector<std::string> CamerasOf(const SyncedFrame& f) {
  std::vector<std::string> out;
  for (const auto& v : f.views) out.push_back(v.camera);
  return out;
}

TEST(FrameSync, GroupsInOrderViewsIntoCompleteFrames) {
  FrameSynchronizer sync;
  std::vector<SyncedFrame> frames;
  int64_t wall = 0;
  for (int f = 0; f < 50; ++f) {
    Append(&frames, sync.Add(View("cam0", f, 0), wall += 100));
    Append(&frames, sync.Add(View("cam1", f, 800), wall += 100));
    Append(&frames, sync.Add(View("cam2", f, -900), wall += 100));
  }
  // The last frame completes with its third view; nothing stays pending.
  EXPECT_TRUE(sync.Flush().empty());
  ASSERT_EQ(frames.size(), 50u);
  for (int f = 0; f < 50; ++f) {
    EXPECT_EQ(frames[f].utime, 1000000 + f * kPeriod) << f;
    EXPECT_EQ(frames[f].seq, f);
    EXPECT_TRUE(frames[f].complete);
    EXPECT_EQ(CamerasOf(frames[f]), (std::vector<std::string>{"cam0", "cam1", "cam2"}));
  }
  EXPECT_EQ(sync.stats().frames_emitted, 50);
  EXPECT_EQ(sync.stats().frames_incomplete, 0);
  EXPECT_EQ(sync.stats().duplicates, 0);
  EXPECT_EQ(sync.stats().out_of_order, 0);
  EXPECT_EQ(sync.Cameras(), (std::set<std::string>{"cam0", "cam1", "cam2"}));
  EXPECT_TRUE(sync.StaleCameras().empty());
}

TEST(FrameSync, FirstFrameWaitsForTheCameraSet) {
  // Without the camera list, the first frame is held until the set settles, then completes.
  FrameSynchronizer sync;
  EXPECT_TRUE(sync.Add(View("a", 0), 0).empty());
  EXPECT_TRUE(sync.Add(View("b", 0), 0).empty());
  const auto out = sync.Add(View("a", 1), 0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].views.size(), 2u);
  EXPECT_TRUE(out[0].complete);
  // With the list, a frame completes as soon as every listed camera has reported.
  FrameSyncOptions options;
  options.cameras = {"a", "b"};
  FrameSynchronizer listed(options);
  EXPECT_TRUE(listed.Add(View("b", 0), 0).empty());
  const auto first = listed.Add(View("a", 0), 0);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(CamerasOf(first[0]), (std::vector<std::string>{"b", "a"}));
}

TEST(FrameSync, ToleranceSeparatesFrames) {
  FrameSyncOptions options;
  options.tolerance_us = 2000;
  options.cameras = {"a", "b"};
  FrameSynchronizer sync(options);
  EXPECT_TRUE(sync.Add(View("a", 0, 0), 0).empty());
  // 2500 us later: not the same capture, a frame of its own. a's frame cannot get b any more (b is
  // past it), so it leaves at once, incomplete.
  const auto first = sync.Add(View("b", 0, 2500), 0);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(CamerasOf(first[0]), std::vector<std::string>{"a"});
  EXPECT_FALSE(first[0].complete);
  // 1500 us after b: joins b's frame.
  const auto second = sync.Add(View("a", 0, 4000), 0);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(CamerasOf(second[0]), (std::vector<std::string>{"b", "a"}));
  EXPECT_TRUE(second[0].complete);
  EXPECT_TRUE(sync.Flush().empty());
  EXPECT_EQ(sync.stats().frames_incomplete, 1);
}

TEST(FrameSync, DuplicatesAreDropped) {
  FrameSyncOptions options;
  options.cameras = {"a", "b"};
  FrameSynchronizer sync(options);
  EXPECT_TRUE(sync.Add(View("a", 0), 0).empty());
  EXPECT_TRUE(sync.Add(View("a", 0, 10), 0).empty());  // same camera, same frame
  const auto out = sync.Add(View("b", 0), 0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].views.size(), 2u);
  EXPECT_EQ(sync.stats().duplicates, 1);
}

TEST(FrameSync, ACameraWhoseFirstViewIsLateIsWaitedForAfterwards) {
  // A camera joining a running rig (a camera added to the map, issue 17) that reports after the others:
  // its first view comes after its frame was emitted; it must not stay unknown (every view late for ever).
  FrameSyncOptions options;
  options.cameras = {"a", "b"};
  FrameSynchronizer sync(options);
  std::vector<SyncedFrame> frames;
  for (int f = 0; f < 5; ++f) {
    Append(&frames, sync.Add(View("a", f), f * kPeriod));
    Append(&frames, sync.Add(View("b", f), f * kPeriod));
  }
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_TRUE(sync.Add(View("c", 4), 4 * kPeriod + 100).empty());  // late: frame 4 is out
  EXPECT_EQ(sync.stats().out_of_order, 1);
  for (int f = 5; f < 10; ++f) {
    Append(&frames, sync.Add(View("a", f), f * kPeriod));
    Append(&frames, sync.Add(View("b", f), f * kPeriod));
    Append(&frames, sync.Add(View("c", f), f * kPeriod + 100));
  }
  ASSERT_EQ(frames.size(), 10u);
  for (int f = 5; f < 10; ++f)
    EXPECT_EQ(CamerasOf(frames[f]), (std::vector<std::string>{"a", "b", "c"})) << f;
  EXPECT_EQ(sync.stats().out_of_order, 1);
}

TEST(FrameSync, OutOfOrderAndLateViewsAreDropped) {
  FrameSyncOptions options;
  options.cameras = {"a", "b"};
  FrameSynchronizer sync(options);
  std::vector<SyncedFrame> frames;
  for (int f = 0; f < 5; ++f) {
    Append(&frames, sync.Add(View("a", f), 0));
    Append(&frames, sync.Add(View("b", f), 0));
  }
  ASSERT_EQ(frames.size(), 5u);
  // An old frame arriving now.
  EXPECT_TRUE(sync.Add(View("a", 2), 0).empty());
  EXPECT_EQ(sync.stats().out_of_order, 1);
  // A view of frame 5 emitted by its deadline, then b's late view of it.
  EXPECT_TRUE(sync.Add(View("a", 5), 1000).empty());
  EXPECT_TRUE(sync.Poll(1000 + options.deadline_us - 1).empty());
  const auto due = sync.Poll(1000 + options.deadline_us);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_FALSE(due[0].complete);
  EXPECT_EQ(due[0].views.size(), 1u);
  EXPECT_TRUE(sync.Add(View("b", 5, 300), 50000).empty());
  EXPECT_EQ(sync.stats().out_of_order, 2);
  EXPECT_EQ(sync.stats().frames_incomplete, 1);
  // The next frame is unaffected.
  EXPECT_TRUE(sync.Add(View("a", 6), 60000).empty());
  const auto next = sync.Add(View("b", 6), 60000);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_TRUE(next[0].complete);
}

TEST(FrameSync, DeadCameraStopsBeingWaitedFor) {
  FrameSyncOptions options;
  options.cameras = {"a", "b", "c"};
  options.camera_timeout_us = 10 * kPeriod;
  FrameSynchronizer sync(options);
  std::vector<SyncedFrame> frames;
  auto wall = [](int f) { return 5000000000 + f * kPeriod; };  // live: arrivals as the frames are taken
  for (int f = 0; f < 40; ++f) {
    Append(&frames, sync.Add(View("a", f), wall(f)));
    Append(&frames, sync.Add(View("b", f), wall(f)));
    if (f < 10) Append(&frames, sync.Add(View("c", f), wall(f)));  // c dies after frame 9
  }
  Append(&frames, sync.Flush());
  // No frame is lost or duplicated; frames are in order.
  ASSERT_EQ(frames.size(), 40u);
  for (int f = 0; f < 40; ++f) EXPECT_EQ(frames[f].seq, f);
  for (int f = 0; f < 10; ++f) EXPECT_EQ(frames[f].views.size(), 3u);
  for (int f = 10; f < 40; ++f) EXPECT_EQ(frames[f].views.size(), 2u);
  EXPECT_EQ(sync.StaleCameras(), (std::set<std::string>{"c"}));
  // Once c is stale, frames complete with a and b alone, as soon as b reports.
  FrameSynchronizer again(options);
  for (int f = 0; f < 40; ++f) {
    again.Add(View("a", f), wall(f));
    const auto out = again.Add(View("b", f), wall(f));
    if (f < 10) again.Add(View("c", f), wall(f));
    if (f >= 25) {
      ASSERT_EQ(out.size(), 1u) << f;
      EXPECT_EQ(out[0].seq, f);
      EXPECT_TRUE(out[0].complete);
    }
  }
}

// Issue 14: detectors that drift apart in message time (videos at --rate max in parallel) made the slow
// one "stale" by message time, and its views were dropped. Live, a camera is alive while it is heard
// of; the slow camera's views join their frames within max_wait_us.
TEST(FrameSync, DetectorsThatDriftApartStayAliveLive) {
  FrameSyncOptions options;
  options.cameras = {"fast", "slow"};
  options.camera_timeout_us = 1000000;
  options.deadline_us = 15000;
  options.max_wait_us = 5000000;
  FrameSynchronizer sync(options);
  std::vector<SyncedFrame> frames;
  int64_t wall = 5000000000;
  // fast runs through its video at 3x real time; slow at 0.8x, then 0.55x halfway (a harder part of its
  // video): slow's lag grows all the time, and fast ends seconds ahead.
  int slow_frame = 0;
  for (int step = 0; step < 310; ++step) {
    wall += 10000;
    Append(&frames, sync.Add(View("fast", step), wall));
    const int pace = slow_frame < 30 ? 4 : 6;
    if (step % pace == pace - 1 && slow_frame < 60)
      Append(&frames, sync.Add(View("slow", slow_frame++), wall + 100));
    Append(&frames, sync.Poll(wall + 200));
  }
  EXPECT_FALSE(sync.StaleCameras().count("slow"));
  int both = 0;
  for (const SyncedFrame& f : frames) both += f.views.size() == 2;
  // Frames wait up to 5 s of wall time (the whole run is 3.1 s): every slow view meets its fast one.
  EXPECT_EQ(both, 60);
}

TEST(FrameSync, NeverSeenListedCameraTimesOut) {
  FrameSyncOptions options;
  options.cameras = {"a", "ghost"};
  options.camera_timeout_us = 5 * kPeriod;
  FrameSynchronizer sync(options);
  std::vector<SyncedFrame> frames;
  for (int f = 0; f < 20; ++f) Append(&frames, sync.Add(View("a", f), 5000000000 + f * kPeriod));
  // Waited for ghost for 5 periods, then frames flow (the held ones emitted in order).
  ASSERT_GE(frames.size(), 19u);
  for (size_t i = 0; i < frames.size(); ++i) EXPECT_EQ(frames[i].seq, static_cast<int64_t>(i));
  EXPECT_EQ(sync.StaleCameras(), (std::set<std::string>{"ghost"}));
}

TEST(FrameSync, PollAndFlushEmitOldestFirst) {
  FrameSyncOptions options;
  options.cameras = {"a", "b"};
  FrameSynchronizer sync(options);
  sync.Add(View("a", 0), 100);
  sync.Add(View("a", 1), 200);
  sync.Add(View("a", 2), 300);
  const auto due = sync.Poll(200 + options.deadline_us);
  ASSERT_EQ(due.size(), 2u);
  EXPECT_EQ(due[0].seq, 0);
  EXPECT_EQ(due[1].seq, 1);
  const auto rest = sync.Flush();
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0].seq, 2);
  EXPECT_EQ(rest[0].last_arrival_us, 300);
  EXPECT_TRUE(sync.Flush().empty());
  EXPECT_EQ(sync.stats().frames_emitted, 3);
}

}  // namespace
}  // namespace mcmt

namespace mcmt {
namespace {

TEST(FrameSync, HalfRateCameraDoesNotHoldFrames) {
  // b runs at half the rate of a: frames without b are emitted (incomplete) as soon as b reports a
  // newer one, without waiting for a deadline.
  FrameSyncOptions options;
  options.cameras = {"a", "b"};
  FrameSynchronizer sync(options);
  std::vector<SyncedFrame> frames;
  for (int f = 0; f < 20; ++f) {
    Append(&frames, sync.Add(View("a", f), 0));
    if (f % 2 == 0) Append(&frames, sync.Add(View("b", f, 300), 0));
  }
  ASSERT_EQ(frames.size(), 19u);  // the last (odd) frame may still get b
  for (int f = 0; f < 19; ++f) {
    EXPECT_EQ(frames[f].seq, f);
    EXPECT_EQ(frames[f].views.size(), f % 2 == 0 ? 2u : 1u);
    EXPECT_EQ(frames[f].complete, f % 2 == 0);
  }
}

TEST(FrameSync, CamerasBeyondToleranceStillFlow) {
  // Clocks 10 ms apart with a 2 ms tolerance: never one frame, but nothing piles up either.
  FrameSyncOptions options;
  options.cameras = {"a", "b"};
  FrameSynchronizer sync(options);
  size_t emitted = 0;
  for (int f = 0; f < 100; ++f) {
    emitted += sync.Add(View("a", f), 0).size();
    emitted += sync.Add(View("b", f, 10000), 0).size();
  }
  EXPECT_GE(emitted, 198u);
  EXPECT_EQ(sync.stats().frames_incomplete, static_cast<int64_t>(emitted));
}

// Issue 14: one message stamped +100 s (live, wall-time arrivals) made every later frame late. It is
// rejected, named, and moves no clock; so is a camera whose clock runs 100 s ahead; a source that
// restarts on a new clock is followed after kClockJumpConfirm messages.
TEST(FrameSync, AFarFutureUtimeIsRejectedAndMovesNoClock) {
  FrameSynchronizer sync;
  std::vector<SyncedFrame> frames;
  int64_t wall = 5000000000;
  for (int f = 0; f < 60; ++f) {
    wall += kPeriod;
    detections_t b = View("cam1", f, 300);
    if (f == 20) b.utime += 100000000;
    Append(&frames, sync.Add(View("cam0", f), wall));
    Append(&frames, sync.Add(b, wall + 200));
    if (f == 20) {
      EXPECT_NE(sync.clock_rejection().find("camera 'cam1': utime"), std::string::npos)
          << sync.clock_rejection();
    } else {
      EXPECT_EQ(sync.clock_rejection(), "") << f;
    }
    Append(&frames, sync.Poll(wall + 20000));  // frame 20 leaves by its deadline without cam1
  }
  ASSERT_EQ(frames.size(), 60u);
  for (int f = 0; f < 60; ++f) EXPECT_EQ(frames[f].views.size(), f == 20 ? 1u : 2u) << f;
  EXPECT_EQ(sync.stats().clock_jumps, 1);
  EXPECT_EQ(sync.stats().out_of_order, 0);
  EXPECT_TRUE(sync.StaleCameras().empty());
}

TEST(FrameSync, ACameraAheadOfTheOthersIsRejectedARestartedOneFollowed) {
  FrameSynchronizer sync;
  int64_t wall = 5000000000;
  int64_t ahead_rejected = 0;
  for (int f = 0; f < 20; ++f) {
    wall += kPeriod;
    sync.Add(View("cam0", f), wall);
    sync.Add(View("cam1", f), wall);
    detections_t c = View("cam2", f);
    c.utime += 100000000;
    sync.Add(c, wall);
    ahead_rejected += sync.clock_rejection().find("the other cameras' clocks") != std::string::npos;
  }
  EXPECT_EQ(ahead_rejected, 20);  // every one: the others reported first, and outvote it
  // cam0 alone jumps 50 s while cam1 goes on: outvoted, every message rejected.
  int accepted = 0;
  for (int f = 20; f < 30; ++f) {
    wall += kPeriod;
    detections_t d = View("cam0", f);
    d.utime += 50000000;
    sync.Add(d, wall);
    accepted += sync.clock_rejection().empty();
    sync.Add(View("cam1", f), wall);
  }
  EXPECT_EQ(accepted, 0);
  // Then cam0 and cam1 both restart 50 s later (a new recording): followed once both runs are confirmed,
  // and their frames complete again.
  std::vector<SyncedFrame> frames;
  for (int f = 30; f < 50; ++f) {
    wall += kPeriod;
    for (const char* camera : {"cam0", "cam1"}) {
      detections_t d = View(camera, f);
      d.utime += 50000000;
      Append(&frames, sync.Add(d, wall));
    }
  }
  int both = 0;
  for (const SyncedFrame& f : frames) both += f.views.size() == 2 && f.utime > 50000000;
  EXPECT_GE(both, 20 - FrameSynchronizer::kClockJumpConfirm - 1);
}

// One camera alone (nothing to vote against) that restarts on a new clock is followed.
TEST(FrameSync, ASingleCameraThatRestartsIsFollowed) {
  FrameSynchronizer sync;
  int64_t wall = 5000000000;
  for (int f = 0; f < 10; ++f) sync.Add(View("cam0", f), wall += kPeriod);
  int accepted = 0;
  for (int f = 10; f < 20; ++f) {
    detections_t d = View("cam0", f);
    d.utime += 50000000;
    sync.Add(d, wall += kPeriod);
    accepted += sync.clock_rejection().empty();
  }
  EXPECT_EQ(accepted, 10 - FrameSynchronizer::kClockJumpConfirm + 1);
}

// Issue 14: a camera whose clock runs 100 s ahead and that happens to report first (live) set the clock:
// the others' views were all late and every frame had that one camera. When the cameras that came later
// agree with each other, they outvote it: it is rejected from then on, and the others' frames complete.
TEST(FrameSync, ACameraAheadThatReportsFirstIsOutvotedByTheOthers) {
  FrameSyncOptions o;
  o.cameras = {"cam0", "cam1", "cam2"};
  o.deadline_us = 15000;
  FrameSynchronizer sync(o);
  std::vector<SyncedFrame> frames;
  int64_t wall = 5000000000;
  std::string rejection;
  for (int f = 0; f < 40; ++f) {
    wall += kPeriod;
    detections_t c = View("cam2", f);
    c.utime += 100000000;
    Append(&frames, sync.Add(c, wall));
    if (!sync.clock_rejection().empty()) rejection = sync.clock_rejection();
    if (f >= 3) {  // the others start a tenth of a second later
      Append(&frames, sync.Add(View("cam0", f), wall + 100));
      Append(&frames, sync.Add(View("cam1", f), wall + 200));
    }
    Append(&frames, sync.Poll(wall + 20000));
  }
  Append(&frames, sync.Flush());
  EXPECT_NE(rejection.find("camera 'cam2'"), std::string::npos) << rejection;
  EXPECT_NE(rejection.find("ahead"), std::string::npos) << rejection;
  int both = 0;
  for (const SyncedFrame& f : frames) {
    const std::vector<std::string> cams = CamerasOf(f);
    both += cams == std::vector<std::string>{"cam0", "cam1"};
  }
  // Only the views that came before the vote (kClockJumpConfirm - 1 per camera) are lost.
  EXPECT_GE(both, 37 - FrameSynchronizer::kClockJumpConfirm) << frames.size();
  EXPECT_FALSE(sync.StaleCameras().count("cam0"));
}

// A camera 100 s behind the others is named (not taken for a lagging camera, whose wait would adapt).
TEST(FrameSync, ACameraFarBehindTheOthersIsNamed) {
  FrameSynchronizer sync;
  int64_t wall = 5000000000;
  std::string rejection;
  for (int f = 0; f < 20; ++f) {
    wall += kPeriod;
    sync.Add(View("cam0", f), wall);
    sync.Add(View("cam1", f), wall);
    detections_t c = View("cam2", f);
    c.utime -= 100000000;
    sync.Add(c, wall);
    if (!sync.clock_rejection().empty()) rejection = sync.clock_rejection();
  }
  EXPECT_NE(rejection.find("camera 'cam2'"), std::string::npos) << rejection;
  EXPECT_NE(rejection.find("behind"), std::string::npos) << rejection;
}

// Issue 14: detectors that drift apart lost views (declared late) whatever the deadline. The lag of each
// camera is measured and the wait adapts, within max_wait_us.
TEST(FrameSync, ALaggingCameraIsWaitedForWithinTheBound) {
  for (const int64_t max_wait : {int64_t{0}, int64_t{200000}}) {
    FrameSyncOptions o;
    o.deadline_us = 15000;
    o.max_wait_us = max_wait;
    o.cameras = {"cam0", "cam1"};
    FrameSynchronizer sync(o);
    std::vector<SyncedFrame> frames;
    const int64_t lag1 = 80000;  // cam1's messages arrive 80 ms after cam0's
    for (int64_t now = 0; now < 60 * kPeriod + 300000; now += 1000) {
      const int64_t f0 = now / kPeriod, f1 = (now - lag1) / kPeriod;
      if (now % kPeriod < 1000 && f0 < 60) Append(&frames, sync.Add(View("cam0", f0), 1000000 + now));
      if (now >= lag1 && (now - lag1) % kPeriod < 1000 && f1 < 60)
        Append(&frames, sync.Add(View("cam1", f1), 1000000 + now));
      Append(&frames, sync.Poll(1000000 + now));
    }
    Append(&frames, sync.Flush());
    int complete = 0;
    for (const auto& f : frames) complete += f.views.size() == 2;
    if (max_wait == 0) {
      EXPECT_GT(sync.stats().out_of_order, 50) << "fixed deadline: cam1's views come too late";
    } else {
      // Only the frames that left before cam1's first view arrived (its lag unknown until then).
      EXPECT_LE(sync.stats().out_of_order, lag1 / kPeriod + 1);
      EXPECT_GE(complete, 60 - (lag1 / kPeriod + 1));
      EXPECT_GE(sync.Lag("cam1") - sync.Lag("cam0"), lag1 - 1000);
    }
  }
}

// A dead camera costs at most max_wait_us per frame.
TEST(FrameSync, AdaptiveWaitIsBounded) {
  FrameSyncOptions o;
  o.deadline_us = 15000;
  o.max_wait_us = 50000;
  FrameSynchronizer sync(o);
  for (int f = 0; f < 10; ++f) {  // cam1 lags 30 ms
    sync.Add(View("cam0", f), 1000000 + f * kPeriod);
    sync.Add(View("cam1", f), 1000000 + f * kPeriod + 30000);
  }
  sync.Add(View("cam0", 10), 1000000 + 10 * kPeriod);  // cam1 stops
  const int64_t first = 1000000 + 10 * kPeriod;
  EXPECT_TRUE(sync.Poll(first + 15000).empty());       // past the plain deadline: still waiting
  EXPECT_TRUE(sync.Poll(first + 30000).empty());       // cam1 usually arrives at +30 ms (+ deadline)
  EXPECT_EQ(sync.Poll(first + 45000 + 1).size(), 1u);  // its usual arrival + deadline passed
}

}  // namespace
}  // namespace mcmt
