// Simulated detections: ground-truth projections with corner noise, misses and false detections.
#include <algorithm>
#include <cmath>
#include <set>

#include "core/lcm_util.h"
#include "sim/sim.h"

namespace mcmt {
namespace sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

bool SimulateDetections(const SimCamera& camera, const SimObject& object, const SimFrame& frame,
                        const DetectionSimOptions& o, std::mt19937_64& rng, detections_t* out) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Always draw the same random numbers for a frame, whatever is dropped, so that one option does
  // not reshuffle the others' outcomes.
  const bool dropped = uniform(rng) < o.drop_rate;
  // False detections draw a varying amount of numbers: from their own generator, seeded by one fixed
  // draw per frame, so that they do not reshuffle the following frames' noise and misses.
  const uint64_t false_seed = rng();
  detections_t& msg = *out;
  msg = detections_t();
  msg.utime = frame.utime;
  msg.seq = frame.seq;
  msg.camera = camera.name;
  msg.dictionary = o.dictionary;
  msg.camera_model = ToCameraModelMsg(camera.model);
  msg.detection_ms = 0.0;
  const std::vector<MarkerView> views = ProjectMarkers(camera, object, frame.rig_from_object);
  for (const MarkerView& v : views) {
    const bool detectable =
        v.fully_visible && v.view_angle_deg <= o.max_view_angle_deg && v.size_px >= o.min_size_px;
    double noise[8];
    for (double& n : noise) n = gauss(rng) * o.corner_noise_px;
    const bool missed = uniform(rng) < o.miss_rate;
    if (!detectable || missed) continue;
    marker_t m;
    m.id = v.id;
    for (int i = 0; i < 4; ++i) {
      m.corners[i][0] = v.corners[i].x() + noise[2 * i];
      m.corners[i][1] = v.corners[i].y() + noise[2 * i + 1];
    }
    msg.markers.push_back(m);
  }
  // False detections: a Poisson number of plausible quadrilaterals with ids not on the object.
  if (o.false_rate > 0) {
    std::mt19937_64 false_rng(false_seed);
    std::poisson_distribution<int> poisson(o.false_rate);
    const int count = poisson(false_rng);
    std::set<int> object_ids;
    for (const auto& m : object.markers) object_ids.insert(m.id);
    const int n_ids = std::max(1, o.dictionary_size);
    const double w = camera.model.width, h = camera.model.height;
    for (int k = 0; k < count; ++k) {
      int id = -1;
      for (int tries = 0; tries < 1000 && id < 0; ++tries) {
        const int candidate = static_cast<int>(uniform(false_rng) * n_ids) % n_ids;
        if (!object_ids.count(candidate)) id = candidate;
      }
      const double side = 12.0 + uniform(false_rng) * std::min(w, h) * 0.12;
      const double angle = 2 * kPi * uniform(false_rng);
      const double margin = side;
      const double cx = margin + uniform(false_rng) * std::max(1.0, w - 2 * margin);
      const double cy = margin + uniform(false_rng) * std::max(1.0, h - 2 * margin);
      marker_t m;
      m.id = id;
      // A square seen in perspective: corners of a rotated square, jittered by up to 12 % of the side;
      // clockwise in the image (y down), as a real marker's corners are.
      for (int i = 0; i < 4; ++i) {
        const double a = angle + i * kPi / 2;
        const double r = side / std::sqrt(2.0);
        m.corners[i][0] =
            std::clamp(cx + r * std::cos(a) + (uniform(false_rng) - 0.5) * 0.24 * side, 0.0, w - 1);
        m.corners[i][1] =
            std::clamp(cy + r * std::sin(a) + (uniform(false_rng) - 0.5) * 0.24 * side, 0.0, h - 1);
      }
      if (id >= 0) msg.markers.push_back(m);
    }
  }
  msg.num_markers = static_cast<int32_t>(msg.markers.size());
  return !dropped;
}

}  // namespace sim
}  // namespace mcmt
