// The README's C++ subscriber (compiled from README.md by tests/logger/CMakeLists.txt), its output
// redirected to a file as a user would: every pose it received is in the file after Ctrl-C (it printed
// with stdio's full buffering and died on SIGINT, losing the last lines). Port 7777.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>

#include "core/lcm_util.h"
#include "test_util.h"

using namespace mcmt_test;

TEST(ReadmeSubscriber, KeepsEveryLineWhenRedirectedAndStoppedWithCtrlC) {
  const std::string dir = MakeTempDir("readme");
  const std::string url = UdpmUrl(7777);
  ::setenv("LCM_DEFAULT_URL", url.c_str(), 1);  // the subscriber's lcm::LCM() uses it
  Child subscriber({MCMT_README_SUBSCRIBER}, dir + "/out.txt", dir + "/err.txt");
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  // Publish until the subscriber has printed one pose (it needs a moment to subscribe).
  int published = 0;
  for (int i = 0; i < 300 && ReadText(dir + "/out.txt").empty(); ++i) {
    const mcmt::object_pose_t p = MakePose(published++, mcmt::object_pose_t::STATUS_TRACKING);
    lcm.publish("MCMT_POSE", &p);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(subscriber.Running());
  ASSERT_FALSE(ReadText(dir + "/out.txt").empty()) << "no pose printed (or only at exit)";
  for (int i = 0; i < 10; ++i) {
    const mcmt::object_pose_t p = MakePose(published++, mcmt::object_pose_t::STATUS_TRACKING);
    lcm.publish("MCMT_POSE", &p);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  subscriber.Signal(SIGINT);
  EXPECT_EQ(subscriber.Wait(5), 0);  // a normal exit, not death by SIGINT
  const std::string out = ReadText(dir + "/out.txt");
  // Every pose from the first one printed to the last one published, one line each.
  long first = -1;
  ASSERT_EQ(std::sscanf(out.c_str(), "frame %ld:", &first), 1) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), published - first) << out;
  EXPECT_NE(out.find("frame " + std::to_string(published - 1) + ": object at "), std::string::npos) << out;
  RemoveTree(dir);
}
