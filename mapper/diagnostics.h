// What a person needs to judge a calibration, computed from the mapper's result alone (MapResult: the
// refined map and trajectory, the report's rejections, the detections it was given):
//  - every marker observation with its corner residuals (projected - observed, pixels) at the final
//    estimates, inlier or rejected with the reason -> OUTDIR/residuals.csv;
//  - per camera: RMS against the RMS its corner noise and marker sizes predict, image coverage,
//    observations, rejected share -> a verdict good / fair / poor with the reason;
//  - per camera: the 6x6 covariance of its pose from the bundle adjustment at the solution (a Ceres
//    problem rebuilt from the result with the mapper's own ReprojectionCost, reference camera and marker
//    held fixed, scaled by the residuals' variance), as 1-sigma position (mm) and rotation (deg).
// The verdicts go into report.json ("diagnostics") and the mapper's last lines; mcmt-report draws them.
//
// Predicted RMS of a camera (pixels, RMS of corner distances as the mapper reports it):
//   predicted^2 = 2 * corner_noise_px^2 + (print_tolerance * median_side_px / 2)^2
// the first term from isotropic corner noise, the second from a marker's printed size or flatness being
// off by print_tolerance (relative), which moves its corners by up to that fraction of half its side.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/map_covariance.h"
#include "mapper/mapper.h"

namespace mcmt {

struct DiagnosticsOptions {
  double corner_noise_px = 0.25;   // per-coordinate corner noise of a good detection, pixels
  double print_tolerance = 0.002;  // relative error of a marker's size / flatness
  int coverage_cells = 8;          // image split in coverage_cells x coverage_cells for coverage
  // Verdict thresholds: poor / fair when RMS exceeds these multiples of the predicted RMS, ...
  double poor_rms_ratio = 3.0, fair_rms_ratio = 1.5;
  double poor_rejected = 0.2, fair_rejected = 0.05;    // ... the rejected share exceeds these, ...
  double poor_coverage = 0.03, fair_coverage = 0.25;   // ... coverage is below these, ...
  int poor_observations = 10, fair_observations = 50;  // ... or it kept fewer inliers than these.
  bool covariance = true;
  // The printed marker size's relative 1-sigma (mapper.marker_size_sigma_percent / 100): a scale every
  // marker shares, which no residual can see; it enters the covariance as a common scale (diagnostics.cc
  // MarkerSizeScaleDirection). 0: the size is exact.
  double marker_size_sigma = 0.0;
};

struct ObservationResidual {
  int64_t utime = 0;  // of the detection
  int64_t seq = 0;
  std::string camera;
  int id = 0;
  std::array<Eigen::Vector2d, 4> observed;  // ArUco order
  std::array<Eigen::Vector2d, 4> residual;  // projected - observed; NaN when not computable
  double rms_px = 0.0;                      // NaN when not computable
  bool inlier = false;
  std::string reason;  // why not an inlier ("" for inliers)
};

struct CameraDiagnostics {
  std::string name;
  int observations = 0;  // marker observations in the input
  int inliers = 0;
  int rejected = 0;  // observations - inliers
  double rms_px = 0.0;
  double predicted_rms_px = 0.0;
  double median_side_px = 0.0;
  double coverage = 0.0;  // share of image cells holding an inlier corner
  std::string verdict;    // good | fair | poor
  std::string reason;
  bool reference = false;
  bool has_covariance = false;
  std::string covariance_note;                                                   // why not, when not
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();  // (dr, dt) of cam_from_rig
  Eigen::Vector3d sigma_position_mm = Eigen::Vector3d::Zero();  // camera centre in the rig frame
  Eigen::Vector3d sigma_rotation_deg = Eigen::Vector3d::Zero();
};

struct Diagnostics {
  DiagnosticsOptions options;
  std::vector<ObservationResidual> observations;
  std::vector<CameraDiagnostics> cameras;  // map order
  double residual_sigma_px = 0.0;          // sqrt(sum r^2 / (residuals - parameters)), per coordinate
  // The part of it every frame of a track (one camera seeing one marker) shares, per coordinate: the
  // residuals' track means beyond what independent errors give (diagnostics.cc TrackBiasTerm).
  double track_bias_sigma_px = 0.0;
  // The joint covariance of the camera and marker poses (core/map_covariance.h; the cameras' blocks are
  // CameraDiagnostics::covariance), scaled by residual_sigma_px^2, with the tracks' shared bias
  // (track_bias_sigma_px) propagated as a correlated error, and the marker size's common scale
  // (options.marker_size_sigma) about the reference camera and marker. Cameras and markers together when they
  // are at most kMaxMapCovarianceEntries, else the cameras alone (a board of many markers would make
  // map.yaml megabytes long). None when the poses are not determined or the covariance was not asked for.
  std::optional<MapCovariance> map_covariance;
};

constexpr int kMaxMapCovarianceEntries = 32;

Diagnostics ComputeDiagnostics(const MapResult& result, const DiagnosticsOptions& options = {});
// The same of the map's object, with several bodies of the first moving one (DiagnosticsView).
Diagnostics ComputeObjectDiagnostics(const MapResult& result, const DiagnosticsOptions& options = {});

// A map no camera supports: when every camera with at least options.poor_observations inliers has a
// reprojection RMS above both rms_ratio x its predicted RMS (more than its corner noise explains) and
// side_fraction x its markers' median side (pixels: residuals that grow with the markers' apparent size,
// as a marker pose's error does), one line naming each with its RMS, the prediction and the median side;
// "" otherwise (also when no camera has that many inliers, or rms_ratio is 0).
std::string UnsupportedMapText(const Diagnostics& d, double rms_ratio, double side_fraction);

// residuals.csv: utime,seq,camera,id,corner,x,y,dx,dy,status,reason (one row per corner).
extern const char kResidualsHeader[];
std::string ResidualsCsv(const Diagnostics& d);
// A JSON object (no trailing newline): cameras with verdicts, predictions, coverage and covariance.
std::string DiagnosticsJson(const Diagnostics& d);
// "camera cam0: good (rms 0.31 px, predicted 0.36 px; ...)" one line per camera.
std::string VerdictLines(const Diagnostics& d);
// report.json with "diagnostics": DiagnosticsJson(d) added as its last key.
std::string WithDiagnostics(const std::string& report_json, const Diagnostics& d);

}  // namespace mcmt
