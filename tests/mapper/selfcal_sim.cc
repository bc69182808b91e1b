#include "tests/mapper/selfcal_sim.h"

#include <algorithm>
#include <random>

#include "core/lcm_util.h"

namespace mcmt {
namespace testing {
namespace {

constexpr int kFine = 40;  // trajectory samples per frame interval (poses between them interpolated)

// The object's pose at time t (seconds after the first frame) from a finely sampled trajectory.
Rigid3 PoseAt(const std::vector<sim::SimFrame>& fine, double fine_rate_hz, double t) {
  const double x = std::clamp(t * fine_rate_hz, 0.0, static_cast<double>(fine.size() - 1));
  const size_t i = std::min(static_cast<size_t>(x), fine.size() - 2);
  const double a = x - static_cast<double>(i);
  const Rigid3& p = fine[i].rig_from_object;
  const Rigid3& q = fine[i + 1].rig_from_object;
  Rigid3 out = Rigid3::Identity();
  out.linear() = Eigen::Quaterniond(p.linear()).slerp(a, Eigen::Quaterniond(q.linear())).toRotationMatrix();
  out.translation() = (1 - a) * p.translation() + a * q.translation();
  return out;
}

}  // namespace

SelfCalRun SimulateSelfCal(const SelfCalSession& session, const std::map<std::string, int64_t>& offsets_us) {
  SelfCalRun run;
  sim::RigOptions ro;
  ro.num_cameras = 5;
  ro.seed = session.seed;
  ro.distortion = session.distortion;
  sim::ObjectOptions oo;
  oo.kind = session.object;
  oo.seed = session.seed;
  sim::TrajectoryOptions to;
  to.frames = session.frames * kFine;
  to.fps = session.fps * kFine / session.speed;
  to.seed = session.seed;
  run.truth.cameras = sim::MakeRig(ro);
  const sim::SimObject object = sim::MakeObject(oo);
  run.truth.object = sim::ObjectKindNames()[static_cast<int>(session.object)];
  run.truth.markers = object.markers;
  run.truth.marker_size = object.Sizes().default_size;
  for (const auto& m : object.markers) run.truth.marker_sizes[m.id] = m.size;
  run.truth.fps = session.fps;
  const std::vector<sim::SimFrame> fine = sim::MakeTrajectory(to);
  const double fine_rate = session.fps * kFine;
  for (size_t i = 0; i + 1 < fine.size(); ++i)
    run.max_speed_m_s =
        std::max(run.max_speed_m_s,
                 (fine[i + 1].rig_from_object.translation() - fine[i].rig_from_object.translation()).norm() *
                     fine_rate);
  for (int k = 0; k < session.frames; ++k) {
    sim::SimFrame f;
    f.seq = k;
    f.utime = sim::FrameUtime(k, session.fps);
    f.rig_from_object = fine[static_cast<size_t>(k) * kFine].rig_from_object;
    run.truth.frames.push_back(f);
  }
  sim::DetectionSimOptions dso;
  dso.corner_noise_px = session.corner_noise_px;
  for (size_t c = 0; c < run.truth.cameras.size(); ++c) {
    const sim::SimCamera& camera = run.truth.cameras[c];
    const auto offset = offsets_us.find(camera.name);
    const int64_t offset_us = offset == offsets_us.end() ? 0 : offset->second;
    std::mt19937_64 rng(session.seed * 100 + c);
    for (const sim::SimFrame& truth_frame : run.truth.frames) {
      // The camera captured at its frame time; its clock reads capture time + offset.
      sim::SimFrame f = truth_frame;
      f.utime = truth_frame.utime + offset_us;
      f.rig_from_object =
          PoseAt(fine, fine_rate, 1e-6 * static_cast<double>(truth_frame.utime - sim::kStartUtime));
      detections_t d;
      if (sim::SimulateDetections(camera, object, f, dso, rng, &d)) run.detections.push_back(d);
    }
  }
  std::stable_sort(run.detections.begin(), run.detections.end(),
                   [](const detections_t& a, const detections_t& b) { return a.utime < b.utime; });
  return run;
}

void PerturbIntrinsics(const std::string& camera, const IntrinsicsError& e, SelfCalRun* run) {
  for (detections_t& d : run->detections) {
    if (d.camera != camera) continue;
    CameraModel m = FromCameraModelMsg(d.camera_model);
    m.fx *= 1 + e.focal_rel;
    m.fy *= 1 + e.focal_rel;
    m.cx += e.cx_px;
    m.cy += e.cy_px;
    if (!m.distortion.empty()) m.distortion[0] += e.k1;
    d.camera_model = ToCameraModelMsg(m);
  }
}

void GiveIntrinsics(const std::string& camera, const CameraModel& model, SelfCalRun* run) {
  for (detections_t& d : run->detections)
    if (d.camera == camera) d.camera_model = ToCameraModelMsg(model);
}

MapperOptions SelfCalOptions(const sim::GroundTruth& truth) {
  MapperOptions o;
  for (const auto& c : truth.cameras) o.cameras.push_back(c.name);
  o.sizes.default_size = truth.marker_size;
  for (const auto& [id, size] : truth.marker_sizes)
    if (size != truth.marker_size) o.sizes.overrides[id] = size;
  o.dictionary = truth.dictionary;
  return o;
}

MapResult MapDetections(const std::vector<detections_t>& detections, const MapperOptions& options) {
  Mapper mapper(options);
  for (const auto& d : detections) mapper.Add(d);
  return mapper.Solve();
}

}  // namespace testing
}  // namespace mcmt
