// Helpers shared by the simulator's sources (not part of the public API).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/se3.h"
#include "sim/sim.h"

namespace mcmt {
namespace sim {
namespace internal {

// Normalised image points a camera model maps one-to-one: beyond the first turning point of the
// radial distortion a point far outside the field of view could fold back into the image.
struct ValidRegion {
  explicit ValidRegion(const CameraModel& model);  // cached per distortion model and coefficients
  bool Contains(double x, double y) const { return x * x + y * y <= max_r2; }
  double max_r2 = 1e30;
};

// Does the open segment from -> to (object frame) cross a face of the object's body?
bool SegmentHitsBody(const SimObject& object, const Eigen::Vector3d& from, const Eigen::Vector3d& to);

// Undistorted normalised coordinates of a distorted normalised point (Newton; false if not converged
// or outside the valid region).
bool UndistortNormalized(const CameraModel& model, const ValidRegion& region, double xd, double yd, double* x,
                         double* y);

// Every camera's simulated detections of every frame, frame by frame and cameras in order (a log's order):
// `scene(i, &frame)` returns frame i's object and sets the frame (seq, utime, rig_from_object); with
// `camera_at`, camera k at a frame is the one it gives, and a camera it returns false for does not publish
// that frame. `publish(k, message)` gets each published message of camera k. One random generator per camera,
// seeded by `seed` and the camera index (the outcome does not depend on what `publish` does).
using SceneFn = std::function<const SimObject&(size_t, SimFrame*)>;
using CameraAtFrameFn = std::function<bool(size_t k, const SimFrame& frame, SimCamera* camera)>;
void SimulateFrames(const std::vector<SimCamera>& cameras, size_t frames, const DetectionSimOptions& options,
                    uint64_t seed, const SceneFn& scene, const CameraAtFrameFn& camera_at,
                    const std::function<void(size_t k, const detections_t& message)>& publish);

// Writes `path` (atomically) with every camera's simulated detections (detections_t on
// MCMT_DETECTIONS_<CAMERA>, event time = utime) of frame i's scene: `scene(i, &frame)` returns the object and
// sets the frame (seq, utime, rig_from_object). One random generator per camera, seeded by `seed` and the
// camera index. With `camera_at`, camera k at a frame is the one it gives (a camera moved during the
// session), and a camera it returns false for does not publish that frame (one that starts late).
// Returns the messages written.
// With `publish`, camera k's message is what it makes of the simulated one (the intrinsics it was given,
// its clock's utime), and the messages are written in utime order.
using PublishFn = std::function<void(size_t k, detections_t* msg)>;
int64_t WriteDetectionsLog(const std::string& path, const std::vector<SimCamera>& cameras,
                           const std::vector<SimFrame>& frames, const DetectionSimOptions& options,
                           uint64_t seed, const SceneFn& scene, const CameraAtFrameFn& camera_at = nullptr,
                           const PublishFn& publish = nullptr);

// --intrinsics-error and --clock (DatasetOptions): the intrinsics each camera is told (the rig's files and
// its messages; the truth unless perturbed), and the publish step that puts them and the camera's clock
// reading into its messages (empty when neither option is given; it refers to its arguments). Throws
// naming the option for a camera not in the rig.
std::vector<CameraModel> WrittenModels(const DatasetOptions& o, const std::vector<SimCamera>& cameras);
PublishFn CamerasTold(const DatasetOptions& o, const std::vector<SimCamera>& cameras,
                      const std::vector<CameraModel>& written_models);

}  // namespace internal
}  // namespace sim
}  // namespace mcmt
