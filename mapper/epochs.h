// A camera that moved during a session (a bumped tripod): its observations fall into two epochs, each
// consistent with the rest of the rig but not with each other. Found after the bundle adjustment's first
// solve with one pose per camera (stages.h, RefineWithRejection): per camera, per frame another camera
// also sees, the Gauss-Newton normal equations (H_t, g_t) of a change of its pose, from its corners'
// residuals under the solved object poses (CameraPoseEvidence). A move at frame k makes the best pose
// change differ before and after k; the likelihood ratio T(k) of two pose changes against one
// (BestSplit, linear time through prefix sums) peaks at the move. A camera moved when max T exceeds
// move_min_score and the two pose changes differ by at least move_min_deg or move_min_mm.
//
// The mapper then solves again with the camera's earlier epoch as a camera of its own (SplitCameraEpochs),
// so that no observation is lost and no camera is dragged off, and the map holds the latest pose
// (MergeCameraEpochs).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/se3.h"
#include "mapper/bundle.h"
#include "mapper/stages.h"

namespace mcmt {

struct EpochSplit {
  int camera = 0;      // camera index
  int frame = 0;       // first frame index of the later epoch
  int64_t utime = 0;   // that frame's utime (messages of the camera at or after it: later epoch)
  int64_t seq = 0;     // that frame's seq
  double score = 0.0;  // T(k)
  double rotation_deg = 0.0, translation_mm = 0.0;  // between the epochs' median poses
  int samples_before = 0, samples_after = 0;
};

// Per frame, a camera's Gauss-Newton normal equations for a change of its pose (cam_from_rig, the
// bundle's left perturbation) at the bundle's current parameters: h = sum J^T J, g = -sum J^T r over its
// observations (active or not, rms <= max_px) in frames another camera also sees; sigma2 the residuals'
// per-coordinate variance (median over the active observations).
struct PoseEvidence {
  std::vector<int> frame;  // frame index per entry, increasing
  std::vector<Matrix6d> h;
  std::vector<Vector6d> g;
  double sigma2 = 1.0;
};
PoseEvidence CameraPoseEvidence(const BundleProblem& problem, int camera, double max_px);

// The split k (first entry of the later epoch, at least min_segment entries each side) maximising the
// likelihood ratio of one pose change per epoch against one for all:
//   T(k) = (g_a^T H_a^-1 g_a + g_b^T H_b^-1 g_b - g^T H^-1 g) / sigma2
// (prefix sums: linear time); the epochs' pose changes in *before, *after. -1 when too short.
int BestSplit(const PoseEvidence& evidence, int min_segment, double* score, Vector6d* before,
              Vector6d* after);

// Every camera (but those to skip) whose observations split into two epochs, strongest first, after the
// bundle adjustment's first solve. A move drags the object poses, so that the cameras seeing the object
// with the moved one split too, more weakly: the mapper splits the strongest only, solves again and
// looks again (SolveWithEpochs in mapper.cc), one move per camera.
std::vector<EpochSplit> FindCameraMoves(const BundleProblem& problem, const std::vector<Frame>& frames,
                                        const MapperOptions& options, const std::vector<char>& skip);

// The camera's pose from every frame another placed, not excluded camera sees: rig_from_cam = base *
// the component-wise median of Log(inv(base) * rig_from_cam_t) (twice, about the first median). Returns
// the number of frames (0: none, *rig_from_cam untouched). The offline update checks a camera with it.
int PoseAgainstOthers(int camera, const Rigid3& base, const std::vector<ViewPose>& views, int num_frames,
                      const CameraPlacement& cameras, const std::vector<char>& excluded,
                      Rigid3* rig_from_cam);

// The name a camera's earlier epoch gets while solving ("cam2@before").
std::string EarlierEpochName(const std::string& camera);

// Messages of a moved camera before its split go to a new camera (index camera_names->size(), named
// EarlierEpochName, same model); the later epoch keeps the camera's name and index.
void SplitCameraEpochs(const std::vector<EpochSplit>& splits, std::vector<StoredMessage>* messages,
                       std::vector<std::string>* camera_names, std::vector<CameraModel>* models);

// The map (and initial map) without the earlier epochs' cameras, whose poses and the move go into
// report.moved_cameras; the detections of an earlier epoch leave result->detections (the diagnostics
// judge the map's poses). The second solve names the first one's reference camera (its later epoch when
// it moved), so the reference is never an earlier epoch.
void MergeCameraEpochs(const std::vector<EpochSplit>& splits, const std::vector<std::string>& camera_names,
                       MapResult* result);

// report.json's "moved_cameras": [{camera, seq, utime, translation_mm, rotation_deg, rig_from_cam_before,
// observations_before}] and "added_cameras": [names], each line ending with ",\n".
std::string CameraChangesJson(const MapReport& report);

}  // namespace mcmt
