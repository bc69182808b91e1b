// Stage: the object's pose per frame (the paper's step 4), weak frames decided by continuity.
#include <cmath>

#include "mapper/parallel.h"
#include "mapper/stages.h"

namespace mcmt {
namespace {

// The frame's candidates (kept hypotheses) and their observations, and all hypotheses.
struct FrameCandidates {
  std::vector<Rigid3> kept, all;
  std::vector<int> source;
  bool one_camera = true;
};

FrameCandidates CandidatesOf(const Observations& observations, int begin, int end, const ObjectPoses& poses,
                             const std::vector<Rigid3>& rig_from_cam,
                             const std::vector<Rigid3>& marker_from_object) {
  FrameCandidates out;
  int first_camera = -1;
  for (int i = begin; i < end; ++i) {
    if (!poses.usable[i]) continue;
    const Observation& ob = observations.obs[i];
    if (first_camera < 0) first_camera = ob.camera;
    out.one_camera = out.one_camera && ob.camera == first_camera;
    const SquarePose& square = observations.poses[i];
    for (int h = 0; h < square.num_hypotheses; ++h) {
      const Rigid3 pose =
          rig_from_cam[ob.camera] * square.hypotheses[h].cam_from_marker * marker_from_object[ob.marker];
      if (h < ob.kept) {
        out.kept.push_back(pose);
        out.source.push_back(i);
      }
      out.all.push_back(pose);
    }
  }
  return out;
}

// Forward, then backward: a weak frame within continuity_gap_s of the last decided frame takes its
// candidate nearest to that frame's pose in rotation, and is decided in turn.
void DecideByContinuity(const std::vector<Frame>& frames, const std::vector<std::vector<Rigid3>>& weak,
                        double continuity_gap_s, ObjectPoses* poses, MapReport* report) {
  const int n = static_cast<int>(frames.size());
  std::vector<char> decided(n, 0);
  for (int f = 0; f < n; ++f) decided[f] = poses->has_pose[f] && weak[f].empty();
  const int64_t max_gap_us = static_cast<int64_t>(1e6 * continuity_gap_s);
  for (const int step : {1, -1}) {
    int last = -1;
    for (int f = step > 0 ? 0 : n - 1; f != (step > 0 ? n : -1); f += step) {
      if (!poses->has_pose[f]) continue;
      if (!decided[f] && last >= 0 && std::llabs(frames[f].utime - frames[last].utime) <= max_gap_us) {
        const std::vector<Rigid3>& cands = weak[f];
        size_t best = 0;
        double best_angle = RotationAngle(cands[0], poses->rig_from_object[last]);
        for (size_t k = 1; k < cands.size(); ++k) {
          const double angle = RotationAngle(cands[k], poses->rig_from_object[last]);
          if (angle < best_angle) best = k, best_angle = angle;
        }
        poses->rig_from_object[f] = Normalized(cands[best]);
        decided[f] = 1;
      }
      if (decided[f]) last = f;
    }
  }
  for (int f = 0; f < n; ++f)
    if (!weak[f].empty()) {
      ++report->weak_frames;
      report->undecided_frames += !decided[f];
    }
}

}  // namespace

ObjectPoses InitialObjectPoses(const Observations& observations, const std::vector<Frame>& frames,
                               const MarkerLayout& layout, const CameraPlacement& cameras,
                               const MapperOptions& o, int threads, MapReport* report) {
  const std::vector<Observation>& obs = observations.obs;
  const int num_frames = static_cast<int>(frames.size());
  const double object_scale = layout.ObjectScale();
  std::vector<Rigid3> marker_from_object(layout.object_from_marker.size());
  for (size_t m = 0; m < marker_from_object.size(); ++m)
    marker_from_object[m] = Inverse(layout.object_from_marker[m]);
  ObjectPoses poses;
  poses.rig_from_object.assign(num_frames, Rigid3::Identity());
  poses.has_pose.assign(num_frames, 0);
  poses.usable.assign(obs.size(), 0);
  for (size_t i = 0; i < obs.size(); ++i)
    poses.usable[i] = obs[i].kept > 0 && layout.placed[obs[i].marker] && cameras.placed[obs[i].camera];
  std::vector<int> frame_first(num_frames + 1, static_cast<int>(obs.size()));
  for (int i = static_cast<int>(obs.size()) - 1; i >= 0; --i) frame_first[obs[i].frame] = i;
  for (int f = num_frames - 1; f >= 0; --f) frame_first[f] = std::min(frame_first[f], frame_first[f + 1]);
  // A frame is weak when its markers are all seen by one camera, or when no two of its observations
  // agree on its pose: a small or distant marker's two planar hypotheses fit its corners about equally,
  // the ratio test may keep the wrong one, and the bundle adjustment cannot leave that minimum. Its
  // candidates (both hypotheses of every marker) are kept and it is decided by continuity with the
  // nearest frame whose observations agree.
  std::vector<std::vector<Rigid3>> weak(num_frames);
  const double support_angle = o.consistency_deg * M_PI / 180.0;
  ParallelFor(num_frames, threads, [&](int f) {
    FrameCandidates c = CandidatesOf(observations, frame_first[f], frame_first[f + 1], poses,
                                     cameras.rig_from_cam, marker_from_object);
    if (c.kept.empty()) return;
    const size_t medoid = MedoidIndex(c.kept, object_scale);
    poses.rig_from_object[f] = Normalized(c.kept[medoid]);
    poses.has_pose[f] = 1;
    // Supported: another observation's candidate agrees with the medoid.
    bool supported = false;
    for (size_t k = 0; k < c.kept.size() && !supported; ++k)
      supported = c.source[k] != c.source[medoid] &&
                  RotationAngle(c.kept[k], c.kept[medoid]) < support_angle &&
                  (c.kept[k].translation() - c.kept[medoid].translation()).norm() <
                      o.consistency_m + o.consistency_rel * object_scale;
    if (c.one_camera || !supported) weak[f] = std::move(c.all);
  });
  DecideByContinuity(frames, weak, o.continuity_gap_s, &poses, report);
  return poses;
}

}  // namespace mcmt
