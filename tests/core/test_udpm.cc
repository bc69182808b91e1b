// A detections_t published over real UDP multicast on loopback arrives byte-equal; the tests' udpm ports
// (tests/support/udpm.h) are never shared with another run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "core/lcm_util.h"
#include "tests/support/udpm.h"

namespace mcmt {
namespace {

// Ports 7600-7619 belong to the core tests (shifted by the run's offset: tests/support/udpm.h).
std::string Url() { return test::UdpmUrl(7600); }

class Receiver {
 public:
  void On(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    channel_ = channel;
    bytes_.assign(static_cast<const uint8_t*>(rbuf->data),
                  static_cast<const uint8_t*>(rbuf->data) + rbuf->data_size);
    ++count_;
  }
  int count_ = 0;
  std::string channel_;
  std::vector<uint8_t> bytes_;
};

detections_t Sample();

TEST(Udpm, DetectionsRoundTripByteEqual) {
  std::unique_ptr<lcm::LCM> publisher, subscriber;
  try {
    publisher = OpenLcm(Url());
    subscriber = OpenLcm(Url());
  } catch (const std::exception& e) {
    GTEST_SKIP() << "UDP multicast unavailable here: " << e.what();
  }
  Receiver receiver;
  subscriber->subscribe(kDetectionsChannelRegex, &Receiver::On, &receiver);

  const detections_t d = Sample();
  const std::vector<uint8_t> sent = Encode(d);

  // Publish repeatedly until one arrives (the first datagram can race the subscription's join).
  bool got = false;
  for (int attempt = 0; attempt < 50 && !got; ++attempt) {
    publisher->publish(DetectionsChannel(d.camera), sent.data(), static_cast<unsigned int>(sent.size()));
    got = HandleUntil(
        *subscriber, [&] { return receiver.count_ > 0; }, std::chrono::milliseconds(200));
  }
  ASSERT_TRUE(got) << "nothing received on " << Url()
                   << " (multicast route? ip route add 224.0.0.0/4 dev lo)";
  EXPECT_EQ(receiver.channel_, "MCMT_DETECTIONS_CAM3");
  EXPECT_EQ(receiver.bytes_, sent);
  const detections_t back = DecodeOrThrow<detections_t>(receiver.bytes_.data(), receiver.bytes_.size());
  EXPECT_EQ(back.num_markers, 40);
  EXPECT_EQ(back.markers[39].corners[3][1], d.markers[39].corners[3][1]);
}

detections_t Sample() {
  detections_t d;
  d.utime = 1700000000123456;
  d.seq = 17;
  d.camera = "cam3";
  d.dictionary = "DICT_6X6_250";
  d.camera_model.width = 640;
  d.camera_model.height = 480;
  d.camera_model.fx = d.camera_model.fy = 500.25;
  d.camera_model.cx = 319.5;
  d.camera_model.cy = 239.5;
  d.camera_model.distortion_model = "radtan";
  d.camera_model.num_distortion = 5;
  d.camera_model.distortion = {-0.1, 0.01, 0.001, -0.001, 0.0001};
  d.num_markers = 40;
  for (int i = 0; i < d.num_markers; ++i) {
    marker_t m;
    m.id = i;
    for (int c = 0; c < 4; ++c) {
      m.corners[c][0] = 10.5 * i + c / 3.0;
      m.corners[c][1] = 7.25 * i - c / 7.0;
    }
    d.markers.push_back(m);
  }
  d.detection_ms = 4.5;
  return d;
}

// Across processes: a forked child publishes, the parent receives the same bytes.
TEST(Udpm, DetectionsFromAnotherProcess) {
  const std::string child_url = test::UdpmUrl(7601);
  std::unique_ptr<lcm::LCM> subscriber;
  try {
    subscriber = OpenLcm(child_url);
  } catch (const std::exception& e) {
    GTEST_SKIP() << "UDP multicast unavailable here: " << e.what();
  }
  Receiver receiver;
  subscriber->subscribe("MCMT_DETECTIONS_CAM3", &Receiver::On, &receiver);
  const std::vector<uint8_t> expected = Encode(Sample());
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Child: its own LCM instance; publish until killed (at most ~10 s).
    lcm::LCM publisher(child_url);
    if (!publisher.good()) ::_exit(3);
    const std::vector<uint8_t> bytes = Encode(Sample());
    for (int i = 0; i < 500; ++i) {
      publisher.publish("MCMT_DETECTIONS_CAM3", bytes.data(), static_cast<unsigned int>(bytes.size()));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ::_exit(0);
  }
  const bool got = HandleUntil(
      *subscriber, [&] { return receiver.count_ > 0; }, std::chrono::seconds(10));
  ::kill(child, SIGTERM);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(got) << "nothing received from the child process on " << child_url;
  EXPECT_EQ(receiver.bytes_, expected);
}

// Two runs of the suite on one machine (a CI clone and a worktree) never share a port: a port another
// run holds is skipped, and one process keeps the port it claimed.
TEST(UdpmPorts, APortHeldByAnotherRunIsSkipped) {
  constexpr int kBase = 7619;  // the core tests' last port
  int other_fd = -1;
  int other_port = 0;
  for (int slot = 0; slot < test::kUdpmSlots && other_fd < 0; ++slot) {  // the other run's claim
    other_port = kBase + slot * test::kUdpmSlotStride;
    other_fd = ::open(test::UdpmLockPath(other_port).c_str(), O_RDWR | O_CREAT, 0666);
    ASSERT_GE(other_fd, 0) << test::UdpmLockPath(other_port);
    if (::flock(other_fd, LOCK_EX | LOCK_NB) != 0) {
      ::close(other_fd);
      other_fd = -1;
    }
  }
  ASSERT_GE(other_fd, 0) << "every slot of " << kBase << " is held";
  const int port = test::UdpmPort(kBase);
  EXPECT_NE(port, other_port);
  EXPECT_EQ((port - kBase) % test::kUdpmSlotStride, 0) << port;
  EXPECT_EQ(test::UdpmPort(kBase), port);  // the same port for the whole process
  EXPECT_EQ(test::UdpmUrl(kBase), "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0");
  ::close(other_fd);
}

}  // namespace
}  // namespace mcmt
