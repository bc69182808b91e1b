// What the live continuous-calibration tests (issue 17) watch on the bus: the tracker's poses and
// statuses, the maintaining mapper's maps and messages, received in a thread of their own
// (test_mapper_maintain_process, test_mapper_maintain_detectors).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/lcm_util.h"
#include "core/se3.h"
#include "mcmt/camera_health_t.hpp"
#include "mcmt/mapper_status_t.hpp"
#include "mcmt/object_pose_t.hpp"
#include "mcmt/tracker_status_t.hpp"
#include "tests/support/udpm.h"

namespace mcmt {
namespace test {

struct Received {
  std::mutex mutex;
  std::map<int64_t, object_pose_t> poses;  // by seq
  std::vector<tracker_status_t> statuses;
  struct Map {
    MapMessage msg;              // the mapper publishes rig_map2_t (core's DecodeMapMessage)
    int64_t last_pose_seq = -1;  // newest pose seq received when the map arrived
  };
  std::vector<Map> maps;
  std::vector<std::string> mapper_messages;
  int64_t last_seq = -1;
};

class Subscriber {
 public:
  Subscriber(const std::string& url, Received* out) : lcm_(url), out_(out) {
    lcm_.subscribe("MCMT_POSE", &Subscriber::OnPose, this)->setQueueCapacity(10000);
    lcm_.subscribe(kTrackerStatusChannel, &Subscriber::OnStatus, this)->setQueueCapacity(10000);
    lcm_.subscribe(kMapChannel, &Subscriber::OnMap, this)->setQueueCapacity(100);
    lcm_.subscribe(kMapperStatusChannel, &Subscriber::OnMapperStatus, this)->setQueueCapacity(1000);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~Subscriber() {
    stop_ = true;
    thread_.join();
  }
  bool good() { return lcm_.good(); }

 private:
  void OnPose(const lcm::ReceiveBuffer*, const std::string&, const object_pose_t* m) {
    std::lock_guard<std::mutex> lock(out_->mutex);
    out_->poses[m->seq] = *m;
    out_->last_seq = std::max(out_->last_seq, m->seq);
  }
  void OnStatus(const lcm::ReceiveBuffer*, const std::string&, const tracker_status_t* m) {
    std::lock_guard<std::mutex> lock(out_->mutex);
    out_->statuses.push_back(*m);
  }
  void OnMap(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    MapMessage m;
    if (!DecodeMapMessage(rbuf->data, rbuf->data_size, &m)) return;
    std::lock_guard<std::mutex> lock(out_->mutex);
    out_->maps.push_back({m, out_->last_seq});
  }
  void OnMapperStatus(const lcm::ReceiveBuffer*, const std::string&, const mapper_status_t* m) {
    std::lock_guard<std::mutex> lock(out_->mutex);
    out_->mapper_messages.push_back(m->message);
  }
  lcm::LCM lcm_;
  Received* out_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

inline const camera_health_t* Health(const tracker_status_t& s, const std::string& camera) {
  for (const camera_health_t& h : s.cameras)
    if (h.camera == camera) return &h;
  return nullptr;
}

// The tracked poses (status TRACKING) against the truth by seq: the largest error before `first_seq`
// (the normal error) and over all.
struct PoseErrors {
  double normal_mm = 0.0;
  double worst_mm = 0.0;
  int64_t worst_seq = -1;
  int tracked = 0;
  // The same in units of each pose's own published translation uncertainty (error / sqrt of the trace of
  // its covariance's translation block): a frame seen by few cameras is allowed the error its covariance
  // admits to; a pose pulled off by a bumped camera is not (its covariance stays that of a good frame).
  double normal_ratio = 0.0;
  double worst_ratio = 0.0;
  int64_t worst_ratio_seq = -1;
};
inline PoseErrors CheckPoses(const std::map<int64_t, object_pose_t>& poses,
                             const std::map<int64_t, Rigid3>& truth_at, int64_t first_seq) {
  PoseErrors out;
  for (const auto& [seq, p] : poses) {
    if (p.status != object_pose_t::STATUS_TRACKING || !truth_at.count(seq)) continue;
    ++out.tracked;
    const double e = 1000.0 * TranslationDistance(FromPose3d(p.rig_from_object), truth_at.at(seq));
    if (seq < first_seq) out.normal_mm = std::max(out.normal_mm, e);
    const double sigma_mm = 1000.0 * std::sqrt(p.covariance[0][0] + p.covariance[1][1] + p.covariance[2][2]);
    const double ratio = sigma_mm > 0.0 ? e / sigma_mm : 0.0;
    if (seq < first_seq) out.normal_ratio = std::max(out.normal_ratio, ratio);
    if (ratio > out.worst_ratio) {
      out.worst_ratio = ratio;
      out.worst_ratio_seq = seq;
    }
    if (e > out.worst_mm) {
      out.worst_mm = e;
      out.worst_seq = seq;
    }
  }
  return out;
}

}  // namespace test
}  // namespace mcmt
