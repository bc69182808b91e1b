// MapperOptions: every key of the rig's `mapper:` section declared once (MapperOptionTable), read by
// FromConfig and checked by Validate, whether the options come from a file or are built in code.
#include "core/options.h"

#include <algorithm>
#include <cmath>

#include "core/marker.h"
#include "mapper/bodies.h"
#include "mapper/mapper.h"

namespace mcmt {

const OptionTable<MapperOptions>& MapperOptionTable() {
  using O = MapperOptions;
  static const OptionTable<O>* table =
      &(*new OptionTable<O>("mapper"))
           .Add("tau_e", &O::tau_e, "",
                "keep both IPPE hypotheses of a marker when their error ratio is below this (the paper's "
                "tau_e)",
                AtLeast(1))
           .Add("tau_n", &O::tau_n, "",
                "graph edge cost (d / s) * max(1, tau_n / s): pairs seen together fewer times cost more",
                Above(0))
           .Add("huber_px", &O::huber_px, "px", "Huber threshold on an observation's RMS corner error")
           .Add("view_weight_power", &O::view_weight_power, "",
                "squared corner residuals weighted by cos(view angle)^this (0: equal weights)", AtLeast(0))
           .Add("corner_weights", OptionTable<O>::Of(&O::corner_weighting, &CornerWeighting::mode),
                kCornerWeightsHelp, OneOf({"equal", "sides"}))
           .Add("corner_weight_floor", OptionTable<O>::Of(&O::corner_weighting, &CornerWeighting::floor), "",
                kCornerWeightFloorHelp, AtLeast(0))
           .Add("outlier_px", &O::outlier_px, "px",
                "after a solve, observations with a larger RMS corner error are rejected and the problem "
                "re-solved",
                Above(0))
           .Add("max_rejection_rounds", &O::max_rejection_rounds, "",
                "solve, reject, re-solve at most this often", AtLeast(0))
           .Add("max_iterations", &O::max_iterations, "", "bundle adjustment iterations per solve",
                AtLeast(1))
           .Add("paper_stop", &O::paper_stop,
                "the paper's stopping rule (RMS improving by less than paper_stop_px)")
           .Add("paper_stop_px", &O::paper_stop_px, "px", "the paper's stopping threshold", Above(0))
           .Add("threads", &O::threads, "", "solver threads, 0: all cores", AtLeast(0))
           .Add("linear_solver", &O::linear_solver,
                "auto (dense Schur for small reduced systems, else sparse)",
                OneOf({"auto", "sparse_schur", "dense_schur", "iterative_schur"}))
           .Add("refine", &O::refine, "false: initialisation only, no bundle adjustment")
           .Add("reference_camera", &O::reference_camera, "the rig frame's camera (empty: best connected)")
           .Add("reference_marker", &O::reference_marker, "",
                "the object frame's marker (-1: best connected)")
           .Add("allow_partial", &O::allow_partial,
                "map the connected part instead of failing (and write a map no camera supports, with a "
                "warning)")
           .Add("unsupported_rms_ratio", &O::unsupported_rms_ratio, "",
                "the map is an error (a warning with allow_partial) when every camera with 10 or more "
                "inlier observations has a reprojection RMS above this multiple of the RMS its corner noise "
                "predicts (report.json diagnostics predicted_rms_px; 0: no check) ...",
                AtLeast(0))
           .Add("unsupported_side_fraction", &O::unsupported_side_fraction, "",
                "... and above this fraction of its markers' median side in pixels (0.04: 4 %)", AtLeast(0))
           .Add("marker_size_sigma_percent", &O::marker_size_sigma_percent, "%",
                "the printed marker size's relative 1-sigma (print scale, measuring): the covariance the "
                "mapper writes holds it as a scale every position shares (0: the size is exact; "
                "docs/report.md)",
                InRange(0, 10, false, true))
           .Add("min_marker_support", &O::min_marker_support, "frames",
                "a marker must be seen with another (same camera, same frame) this often to be placed",
                AtLeast(1))
           .Add("marker_inlier_fraction", &O::marker_inlier_fraction, "",
                "... and agree with the chosen relative pose in at least this fraction of those frames",
                InRange(0, 1))
           .Add("consistency_deg", &O::consistency_deg, "deg", "\"agree\": within this angle", Above(0))
           .Add("consistency_m", &O::consistency_m, "m",
                "\"agree\": within consistency_m + consistency_rel * distance")
           .Add("consistency_rel", &O::consistency_rel, "",
                "\"agree\": the part of the position tolerance that grows with distance")
           .Add("consistency_noise_px", &O::consistency_noise_px, "px",
                "... or (marker pairs) within the square poses' noise for this corner noise (0: off)",
                AtLeast(0))
           .Add("marker_reject_fraction", &O::marker_reject_fraction, "",
                "a marker with more of its observations rejected is dropped (reported)", InRange(0, 1, true))
           .Add("max_pair_events", &O::max_pair_events, "",
                "co-observations per camera / marker pair entering the medoid (strided subset: linear time)",
                AtLeast(10))
           .Add("continuity_gap_s", &O::continuity_gap_s, "s",
                "a frame seen by one camera only takes, of both hypotheses of each marker, the pose nearest "
                "to the nearest decided frame at most this far in time (0: the paper's rule alone)",
                AtLeast(0))
           .Other("refine_intrinsics", "",
                  "refine the intrinsics in the bundle adjustment: none, focal, focal_center, all")
           .Other("refine_intrinsics_cameras", "", "only these cameras (a list of names; absent: all)")
           .Other("intrinsics_sigma", "",
                  "prior sigmas of the given intrinsics: {focal_rel (relative), center_px (px), radial, "
                  "tangential}, each > 0")
           .Add("observability_ratio",
                OptionTable<O>::Of(&O::intrinsics, &IntrinsicsSettings::observability_ratio), "",
                "an intrinsic is refined only where its posterior sigma < this * its prior sigma",
                InRange(0, 1, true))
           .Add("time_offsets", &O::estimate_time_offsets,
                "estimate per-camera clock offsets against the reference camera in the bundle adjustment")
           .Add("clock_drift", &O::estimate_clock_drift,
                "time_offsets: also a linear drift of each camera's clock against the reference camera's "
                "(map.yaml time_drift_ppm)")
           .Add("max_time_offset_ms", &O::max_time_offset_ms, "ms",
                "time_offsets: frames are first assembled over this tolerance", Above(0))
           .Add("detect_moves", &O::detect_moves,
                "find cameras that moved within the session and solve one pose per epoch")
           .Add("move_min_score", &O::move_min_score, "",
                "a camera is split into two epochs where its split statistic exceeds this", Above(0))
           .Add("move_min_deg", &O::move_min_deg, "deg", "smallest rotation reported as a move", Above(0))
           .Add("move_min_mm", &O::move_min_mm, "mm", "smallest translation reported as a move", Above(0))
           .Add("move_min_rms_ratio", &O::move_min_rms_ratio, "",
                "a moved camera's RMS must exceed the others' median by this factor", Above(0))
           .Add("maintain_frames", &O::maintain_frames, "frames",
                "--maintain: frames seen by the others collected before a suspect camera is re-estimated",
                AtLeast(10))
           .Add("maintain_added_frames", &O::maintain_added_frames, "frames",
                "--maintain: frames collected before a camera not in the map is added", AtLeast(10))
           .Add("maintain_max_rms_ratio", &O::maintain_max_rms_ratio, "",
                "--maintain: a re-estimated camera's RMS must be at most this multiple of the others' "
                "median to be published",
                Above(0));
  return *table;
}

namespace {

std::string CameraNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// mapper.refine_intrinsics, refine_intrinsics_cameras and intrinsics_sigma (the table has the other keys).
void ReadIntrinsicsSettings(const RigConfig& rig, IntrinsicsSettings* out) {
  const YamlSection& s = rig.mapper;
  try {
    out->refine = IntrinsicsRefinementFromName(s.GetString("refine_intrinsics", "none"));
  } catch (const std::invalid_argument& e) {
    s.Fail("refine_intrinsics", e.what());
  }
  if (s.Has("refine_intrinsics_cameras")) {
    const YAML::Node list = s.node()["refine_intrinsics_cameras"];
    if (!list.IsSequence()) s.Fail("refine_intrinsics_cameras", "expected a list of camera names");
    for (const YAML::Node& n : list) {
      const std::string name = n.as<std::string>();
      if (!rig.FindCamera(name)) s.Fail("refine_intrinsics_cameras", "no camera named '" + name + "'");
      out->cameras.push_back(name);
    }
  }
  const YamlSection sigma = s.Child("intrinsics_sigma");
  sigma.CheckKnownKeys({"focal_rel", "center_px", "radial", "tangential"});
  out->sigma.focal_rel = sigma.GetPositiveDouble("focal_rel", out->sigma.focal_rel);
  out->sigma.center_px = sigma.GetPositiveDouble("center_px", out->sigma.center_px);
  out->sigma.radial = sigma.GetPositiveDouble("radial", out->sigma.radial);
  out->sigma.tangential = sigma.GetPositiveDouble("tangential", out->sigma.tangential);
}

}  // namespace

MapperOptions MapperOptions::FromConfig(const RigConfig& rig) {
  MapperOptions o;
  o.sync_tolerance_ms = LoadSyncOptions(rig).tolerance_ms;
  for (const CameraConfig& c : rig.cameras) o.cameras.push_back(c.name);
  o.marker_ids = rig.markers.ids;
  o.sizes = rig.markers.Sizes();
  o.dictionary = rig.markers.dictionary;
  o.bodies = BodiesFromRig(rig);  // several objects (mapper/bodies.h)
  o.rig_frame = rig.objects.rig_frame;
  MapperOptionTable().Load(rig.mapper, &o);
  ReadIntrinsicsSettings(rig, &o.intrinsics);
  o.Validate(rig.path);
  return o;
}

void MapperOptions::Validate(const std::string& file) const {
  const OptionTable<MapperOptions>& table = MapperOptionTable();
  table.Check(*this, file);
  if (!(sync_tolerance_ms >= 0))
    throw OptionError(file, "sync.tolerance_ms",
                      "must be >= 0, got " + FormatOptionNumber(sync_tolerance_ms));
  if (!reference_camera.empty() && !cameras.empty() &&
      std::find(cameras.begin(), cameras.end(), reference_camera) == cameras.end())
    table.Fail(file, "reference_camera",
               "no camera named '" + reference_camera + "' (cameras: " + CameraNames(cameras) + ")");
  if (reference_marker >= 0 && !marker_ids.empty() &&
      std::find(marker_ids.begin(), marker_ids.end(), reference_marker) == marker_ids.end())
    table.Fail(file, "reference_marker", std::to_string(reference_marker) + " is not in markers.ids");
  if (estimate_clock_drift && !estimate_time_offsets)
    table.Fail(file, "clock_drift", "needs time_offsets: true (a drift is estimated with the offsets)");
  const IntrinsicsSigma& sigma = intrinsics.sigma;
  for (const auto& [key, v] : {std::pair<const char*, double>{"focal_rel", sigma.focal_rel},
                               {"center_px", sigma.center_px},
                               {"radial", sigma.radial},
                               {"tangential", sigma.tangential}})
    if (!(v > 0))
      table.Fail(file, std::string("intrinsics_sigma.") + key, "must be > 0, got " + FormatOptionNumber(v));
  if (bodies.empty() && !(sizes.default_size > 0)) {
    bool all_overridden = !marker_ids.empty();
    for (int id : marker_ids)
      if (!(sizes.Get(id) > 0)) all_overridden = false;
    if (!all_overridden) throw OptionError(file, "markers.size", "must be positive");
  }
}

}  // namespace mcmt
