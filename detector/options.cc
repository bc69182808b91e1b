// The rig's `detector:` section declared once: DetectorOptions (the marker detector) and
// DetectorNodeOptions (the process: frame rate, images, status) share it, each table knowing the other's
// keys; FromConfig / LoadFromConfig load and check, Validate checks options built in code the same way.
#include "core/options.h"

#include "detector/detector.h"
#include "detector/node.h"

namespace mcmt {

const OptionTable<DetectorOptions>& DetectorOptionTable() {
  using O = DetectorOptions;
  static const OptionTable<O>* table =
      &(*new OptionTable<O>("detector"))
           .Add("corner_refinement", &O::corner_refinement,
                "edges (this project's unbiased line fit), none (OpenCV's contour corners), subpix "
                "(cv::cornerSubPix), contour (OpenCV's CORNER_REFINE_CONTOUR)",
                OneOf({"edges", "none", "subpix", "contour"}))
           .Add("subpix_window", &O::subpix_window, "px", "half window of subpix", AtLeast(1))
           .Add("edge_passes", &O::edge_passes, "", "edges: crossing passes before the two side-model passes",
                InRange(1, 10))
           .Add("edge_model", &O::edge_model, "edges: correct each side with a fitted blurred-step model")
           .Add("sharp_smoothing", &O::sharp_smoothing, "px",
                "edges on sharp frames (the mean fitted blur of the frame's markers < 0.55 px): Gaussian "
                "sigma "
                "each marker's region is smoothed with (0: off)",
                InRange(0, 3))
           .Add("gamma", &O::gamma, "",
                "edges: the camera's transfer curve, 0: estimated per side, > 0: known (1: linear images)",
                NumberCheck{"must be 0 (estimated) or in [0.2, 5]",
                            [](const double& v) { return v == 0 || (v >= 0.2 && v <= 5); }})
           .Add("unsharp_amount", &O::unsharp_amount, "",
                "edges: the camera's sharpening (unsharp mask amount; 0: none), undone before the side fits; "
                "a known gamma is then held in the side model",
                InRange(0, 5))
           .Add("unsharp_sigma", &O::unsharp_sigma, "px", "edges: the camera's unsharp mask's Gaussian sigma",
                InRange(0.3, 5))
           .Add("unsharp_linear", &O::unsharp_linear,
                "edges: the camera sharpens linear light, before its transfer curve (needs gamma > 0)")
           .Add("tone", &O::tone,
                "edges: given (gamma, unsharp_* as set) or auto (estimated per camera from its first "
                "tone_markers decoded markers, detector/tone.h)",
                OneOf({"given", "auto"}))
           .Add("tone_markers", &O::tone_markers, "markers",
                "tone auto: markers fitted (at most 4 a frame, the largest)", InRange(kToneMinMarkers, 1000))
           .Add("tone_frames", &O::tone_frames, "frames",
                "tone auto: the estimate is made after this many frames at the latest (from at least 8 "
                "markers, else the given tone stays)",
                InRange(1, 100000))
           .Add("candidate_search", &O::candidate_search,
                "opencv (cv::aruco::detectMarkers) or own (tile-range binary images, detector/candidates.h)",
                OneOf({"own", "opencv"}))
           .Add("threshold_tile_px", &O::threshold_tile_px, "px",
                "own candidate search: threshold tile side (levels of the range over 3 x 3 tiles)",
                InRange(2, 64))
           .Add("min_tile_contrast", &O::min_tile_contrast, "grey levels",
                "own candidate search: tiles (with their neighbours) of less contrast have no dark pixels",
                InRange(1, 255))
           .Add("threshold_level", &O::threshold_level, "",
                "own candidate search: dark below min + level * (max - min) of the 3 x 3 tiles",
                InRange(0, 1, true, true))
           .Add("second_threshold_level", &O::second_threshold_level, "",
                "own candidate search: a second binary image at this level (0: none)",
                InRange(0, 1, false, true))
           .Add("low_threshold_level", &O::low_threshold_level, "",
                "own candidate search: a binary image at this level on the tiles where no marker was found "
                "at the levels before (0: none)",
                InRange(0, 1, false, true))
           .Add("high_threshold_level", &O::high_threshold_level, "",
                "own candidate search: a binary image at this level after low_threshold_level's, on the "
                "tiles where no marker was found yet (0: none; the local mean's comes after it)",
                InRange(0, 1, false, true))
           .Add("mean_window_px", &O::mean_window_px, "px",
                "own candidate search: last, on the tiles where no marker was found, dark below the mean of "
                "this window less adaptive_constant (odd; 0: none)",
                NumberCheck{
                    "must be 0 or odd and >= 3",
                    [](const double& v) { return v == 0 || (v >= 3 && static_cast<int>(v) % 2 == 1); }})
           .Add("adaptive_window_min", &O::adaptive_window_min, "px", "adaptive threshold window: smallest",
                AtLeast(3))
           .Add("adaptive_window_max", &O::adaptive_window_max, "px",
                "adaptive threshold window: largest (>= adaptive_window_min)")
           .Add("adaptive_window_step", &O::adaptive_window_step, "px", "adaptive threshold window: step",
                AtLeast(1))
           .Add("adaptive_constant", &O::adaptive_constant, "grey levels", "subtracted from the local mean")
           .Add("min_perimeter_px", &O::min_perimeter_px, "px", "smallest marker perimeter searched",
                Above(0))
           .Add("max_perimeter_rate", &O::max_perimeter_rate, "",
                "largest marker perimeter, relative to the image's larger side", Above(0))
           .Add("polygonal_approx_rate", &O::polygonal_approx_rate, "",
                "contour -> quadrilateral tolerance, relative to the perimeter", InRange(0, 1, true, true))
           .Add("min_corner_distance_rate", &O::min_corner_distance_rate, "",
                "smallest corner distance, relative to the perimeter")
           .Add("min_marker_distance_rate", &O::min_marker_distance_rate, "",
                "candidates closer than this (rms corner distance / perimeter) are one (OpenCV keeps the "
                "biggest)",
                InRange(0, 1))
           .Add("reread_rejected", &O::reread_rejected,
                "read candidates OpenCV rejected again at their sides' mid-level crossings")
           .Add("inside_rejected_level", &O::inside_rejected_level, "",
                "a rejected candidate that is no marker (a dark card's outline around a marker whose margin "
                "the view made too thin) is searched inside for quads at low_threshold_level and this level "
                "of the local range (0: not)",
                InRange(0, 1, false, true))
           .Add("broken_border_window", &O::broken_border_window, "px",
                "on blurred frames (the mean fitted blur of the frame's markers >= 0.55 px, judged by "
                "sharp_smoothing's fit: sharp_smoothing 0 turns this search off too), markers whose thin "
                "border breaks at the adaptive threshold are searched for where none was found: dark below "
                "the mean of this window less broken_border_offset (0: not)",
                AtLeast(0))
           .Add("broken_border_offset", &O::broken_border_offset, "grey levels",
                "the broken-border search's offset from the local mean (negative: darker than the mean "
                "plus its magnitude)")
           .Add("broken_border_min_perimeter_px", &O::broken_border_min_perimeter_px, "px",
                "the broken-border search's quads with a smaller perimeter are not read (markers under 20 "
                "px found so had poor corners)",
                AtLeast(0))
           .Add("min_distance_to_border", &O::min_distance_to_border, "px",
                "smallest distance of a candidate to the image border")
           .Add("error_correction_rate", &O::error_correction_rate, "",
                "part of the dictionary's correction capacity used", InRange(0, 1))
           .Add("perspective_pixels_per_cell", &O::perspective_pixels_per_cell, "px",
                "bit sampling resolution", AtLeast(1))
           .Add("perspective_ignored_margin", &O::perspective_ignored_margin, "",
                "part of each cell ignored when reading its bit", InRange(0, 0.5, false, true))
           .Add("inverted", &O::inverted, "also look for white-on-black markers (default: markers.inverted)")
           .Add("aruco3", &O::aruco3, "OpenCV's ArUco3 fast search (downsampled candidate search)")
           .Add("aruco3_min_side", &O::aruco3_min_side, "px", "ArUco3's minSideLengthCanonicalImg")
           .Add("fast", &O::fast,
                "fast mode: full searches only every full_search_every frames; between them, a band of "
                "fast_band_sides around each marker of the frame before (a marker coming into view there is "
                "found in its first frame, elsewhere at the next full search)")
           .Add("full_search_every", &O::full_search_every, "frames",
                "fast mode: frames between full searches", AtLeast(1))
           .Add("fast_band_sides", &O::fast_band_sides, "marker sides",
                "fast mode: each previous marker's box grown by this many of its sides is searched every "
                "frame as the full search searches the image (below 0.4 markers meet their region's edge)",
                AtLeast(0.4))
           .Add("drop_duplicate_ids", &O::drop_duplicate_ids,
                "drop every marker whose id is detected twice in one image")
           .Add("drop_unrefined", &O::drop_unrefined,
                "drop a marker whose edges cannot be fitted (false: it keeps cornerSubPix corners)");
  return *table;
}

const OptionTable<DetectorNodeOptions>& DetectorNodeOptionTable() {
  using O = DetectorNodeOptions;
  static const OptionTable<O>* table =
      &(*new OptionTable<O>("detector"))
           .Add("fps", &O::fps, "Hz", "recordings: frame rate (0: the video's own, image folders 30)",
                AtLeast(0))
           .Add("images", &O::images, "publish JPEG images on MCMT_IMAGE_<CAMERA>")
           .Add("image_rate", &O::image_rate_hz, "Hz", "at most this many images per second (message time)",
                Above(0))
           .Add("image_quality", &O::image_quality, "", "JPEG quality", InRange(1, 100))
           .Add("image_scale", &O::image_scale, "", "images downscaled by this factor", InRange(0, 1, true))
           .Add("status_period_s", &O::status_period_s, "s", "status line period, wall time (<= 0: none)")
           .Add("max_lag_ms", &O::max_lag_ms, "ms",
                "--rate realtime: a frame already this late when the detector gets to it is dropped "
                "undetected, as a live camera drops what a slow detector cannot take (0: every frame)",
                AtLeast(0))
           .Add("caliscope_time", &O::caliscope_time,
                "Caliscope recordings: sync (one shared time per synchronised frame) or camera (each "
                "camera's own times)",
                OneOf({"sync", "camera"}));
  return *table;
}

DetectorOptions DetectorOptions::FromConfig(const RigConfig& rig) {
  DetectorOptions o;
  o.inverted = rig.markers.inverted;
  DetectorOptionTable().Load(rig.detector, &o, DetectorNodeOptionTable().Keys());
  o.Validate(rig.path);
  return o;
}

void DetectorOptions::Validate(const std::string& file) const {
  const OptionTable<DetectorOptions>& table = DetectorOptionTable();
  table.Check(*this, file);
  if (adaptive_window_max < adaptive_window_min)
    table.Fail(file, "adaptive_window_max",
               "must be >= adaptive_window_min (" + std::to_string(adaptive_window_min) + "), got " +
                   std::to_string(adaptive_window_max));
  if (unsharp_linear && unsharp_amount > 0 && gamma <= 0)
    table.Fail(file, "unsharp_linear", "needs a known gamma (> 0), got gamma 0");
  if (tone == "auto" && (gamma != 0 || unsharp_amount != 0))
    table.Fail(file, "tone", "auto estimates gamma and unsharp_*: give neither with it");
}

void DetectorNodeOptions::LoadFromConfig(const RigConfig& rig) {
  DetectorNodeOptionTable().Load(rig.detector, this, DetectorOptionTable().Keys());
}

}  // namespace mcmt
