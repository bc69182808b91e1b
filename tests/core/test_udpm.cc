// A detections_t published over real UDP multicast on loopback arrives byte-equal.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "core/lcm_util.h"

namespace mcmt {
namespace {

// Port 7600 belongs to the core tests (7600-7619).
constexpr char kUrl[] = "udpm://239.255.76.67:7600?ttl=0";

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
    publisher = OpenLcm(kUrl);
    subscriber = OpenLcm(kUrl);
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
  ASSERT_TRUE(got) << "nothing received on " << kUrl << " (multicast route? ip route add 224.0.0.0/4 dev lo)";
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
  constexpr char kChildUrl[] = "udpm://239.255.76.67:7601?ttl=0";
  std::unique_ptr<lcm::LCM> subscriber;
  try {
    subscriber = OpenLcm(kChildUrl);
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
    lcm::LCM publisher(kChildUrl);
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
  ASSERT_TRUE(got) << "nothing received from the child process on " << kChildUrl;
  EXPECT_EQ(receiver.bytes_, expected);
}

}  // namespace
}  // namespace mcmt
