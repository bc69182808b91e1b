// The map's own uncertainty, written by mcmt-mapper into map.yaml (key `covariance`, docs/files.md) so
// that the tracker can publish poses whose covariance holds the map's error as well as the frame's noise.
//
// It is the joint covariance of the camera poses (cam_from_rig) and marker poses (object_from_marker) the
// bundle adjustment estimated, from mapper/diagnostics.h's reduced system: the Gauss-Newton information
// of the inlier observations with every frame pose eliminated, inverted and scaled by the residuals'
// variance. The reference camera and the reference marker define the rig and object frames and are not in
// it (their error is zero by definition). An entry's 6 rows are the mapper's left perturbation (dr, dt) of
// its pose block (mapper/bundle.h PoseBlock): R <- Exp(dr) R, t <- t + dt, for cam_from_rig (the inverse of
// the map's rig_from_cam) and for object_from_marker. Entries: the cameras in their order, then the markers.
// The camera intrinsics' and the clocks' uncertainties are not in it.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/files.h"

namespace mcmt {

struct MapCovariance {
  std::vector<std::string> cameras;
  std::vector<int> markers;
  Eigen::MatrixXd matrix;  // 6 * Entries() square, symmetric

  size_t Entries() const { return cameras.size() + markers.size(); }
  // The entry of a camera (its index) or of a marker (cameras.size() + its index); -1 when not listed.
  int CameraEntry(const std::string& name) const;
  int MarkerEntry(int id) const;
};

// The YAML text WriteMap writes.
std::string MapYaml(const RigMap& map);
// map.yaml's `covariance` section: cameras (names), markers (ids), matrix (one row per line).
std::string MapCovarianceYaml(const MapCovariance& covariance);
// WriteMap, then the covariance section when there is one (atomically, as WriteMap).
void WriteMapWithCovariance(const std::string& path, const RigMap& map, const MapCovariance* covariance);
// The `covariance` of a map file; nullopt when it has none (maps older than the key, maps of another
// writer). Throws FileFormatError naming the file and the key when the section is malformed (sizes that do
// not agree, a non-finite or asymmetric matrix, a negative variance, a name or id listed twice).
std::optional<MapCovariance> ReadMapCovariance(const std::string& path);

}  // namespace mcmt
