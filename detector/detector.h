// Marker detection with unbiased sub-pixel corners.
//
// Candidates and ids come from OpenCV's ArUco detector (no corner refinement). The corners are then
// refined by RefineMarkerCorners(): a crossing pass locates each side's outer edge at many points and
// fits a line to each side (in undistorted pixels when the camera model is known); then side-model
// passes (detector/side_model.h) fit, across each side, blurred steps at the outer edge and at the
// boundaries between the border and the code rows the decoded marker says are there (edges known on
// both sides), with the surround's levels and margin, the blur and the gamma fitted, and move each line
// to the fitted outer edge; the corners are the intersections of adjacent lines. The passes repeat
// until the corners settle, so the result does not depend on the starting corners.
//
// Fast mode (DetectorOptions::fast): after a full-frame search, the next frames are searched only near
// the markers' last positions (a band of `fast_band_sides` marker sides around each, searched as the
// full search searches the image); a full search runs every `full_search_every` frames and whenever no
// marker was found. Corners are refined the same way in both modes, to the same place.
#pragma once

#include <array>
#include <memory>
#include <opencv2/aruco.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/config.h"
#include "detector/tone.h"
#include "mcmt/detections_t.hpp"
#include "mcmt/marker_t.hpp"

namespace mcmt {

struct DetectorOptions {
  // "edges": this project's line-fit refinement (default, unbiased); "none": OpenCV's contour corners;
  // "subpix": cv::cornerSubPix (OpenCV CORNER_REFINE_SUBPIX with subpix_window); "contour": OpenCV's
  // CORNER_REFINE_CONTOUR.
  std::string corner_refinement = "edges";
  int subpix_window = 2;  // half window of "subpix", pixels
  int edge_passes = 1;    // crossing passes of "edges" before its two side-model passes
  // "edges": correct each side's offset with a blurred-step model fitted to its mean profile (removes
  // the bias of narrow quiet zones under blur).
  bool edge_model = true;
  // "edges" on sharp frames (the mean fitted blur of the frame's markers, refined on smoothed regions,
  // < 0.55 px; never earlier frames'): refine on each marker's region smoothed with this Gaussian sigma
  // (px), which removes the pixel-grid locking of interpolated profiles. 0: off.
  double sharp_smoothing = 0.6;
  // "edges": the camera's transfer curve. 0 (default): estimated with each side's model (the model's
  // linear light is encoded as 255 (v / 255)^(1 / gamma), gamma fitted). > 0: known; the marker's region
  // is linearised as 255 * (v / 255)^gamma first (1: linear images).
  double gamma = 0.0;
  // "edges": the camera's sharpening, an unsharp mask y = (1 + amount) x - amount G_sigma x on its
  // encoded values (or, unsharp_linear with gamma > 0, on linear light before its transfer curve),
  // undone on each marker's region before its sides are fitted. With it a known gamma is held in every
  // side's model (the region stays encoded). amount 0: none.
  double unsharp_amount = 0.0;
  double unsharp_sigma = 1.0;  // px
  bool unsharp_linear = false;
  // "edges": "given" (default): gamma and unsharp_* as above. "auto": estimated per camera from its
  // first `tone_markers` decoded markers (at most 4 a frame, the largest; detector/tone.h: no board
  // geometry), then used as if given; until then markers are refined with gamma 0 and no sharpening.
  // The estimate is logged and kept in MarkerDetector::tone(). It is made after `tone_frames` frames at
  // the latest, from the markers those gave if at least kToneMinMarkers; with fewer the given tone stays
  // (logged), so a recording's first pass (DetectRecording, mcmt-detector) reads at most that many.
  std::string tone = "given";
  int tone_markers = 60;
  int tone_frames = 300;

  // Candidate search. "opencv" (default): cv::aruco::detectMarkers, always used with corner_refinement
  // other than "edges", aruco3 or inverted markers. "own": detector/candidates.h, binary images at two
  // levels of the tiles' range, each quad read at its cell centres (dark border, ids by the dictionary).
  // "own" takes fewer instructions; its recall is OpenCV's over the catalogue but not yet in every
  // condition (bench/results/2026-12-04-search2.md: blur 1.2 and webcam at 60-75 deg), hence not the
  // default.
  std::string candidate_search = "opencv";
  int threshold_tile_px = 4;             // "own": threshold tile side (range over 3 x 3 tiles)
  int min_tile_contrast = 30;            // "own": grey levels; less range: no dark pixels
  double threshold_level = 0.5;          // "own": dark below min + level * (max - min) of 3 x 3 tiles
  double second_threshold_level = 0.35;  // "own": a second binary image at this level (0: none) ...
  double low_threshold_level = 0.25;     // "own": ... and these two, on the tiles where no marker was
  double high_threshold_level = 0.65;    // found at the levels before (0: none)
  int mean_window_px = 5;  // "own": last, there, dark below the mean of this window - adaptive_constant
  // OpenCV candidate search.
  int adaptive_window_min = 5;  // adaptive threshold window sizes: min, max, step (odd sizes)
  int adaptive_window_max = 15;
  int adaptive_window_step = 10;
  double adaptive_constant = 7.0;       // subtracted from the local mean
  double min_perimeter_px = 40.0;       // smallest marker perimeter searched (15 px markers: 60)
  double max_perimeter_rate = 4.0;      // largest, relative to the image's larger side
  double polygonal_approx_rate = 0.05;  // contour -> quadrilateral tolerance, relative to perimeter
  double min_corner_distance_rate = 0.05;
  // Candidates whose corners are closer than this (rms, relative to the smaller perimeter) are one
  // candidate to OpenCV, which decodes only the biggest. OpenCV's default 0.05 puts a narrow margin's
  // outer edge (a quad half a cell outside the marker, over a dark surround) with the marker and decodes
  // only the margin's quad, whose border reads white: the marker is lost. 0.01 keeps margins of 0.2 cell
  // and more apart; quads of one marker from two threshold windows then both decode (the same id at
  // one place: kept once, the one whose code reads best).
  double min_marker_distance_rate = 0.01;
  // Candidates OpenCV could not decode (blurred small markers: the contour's polygon a pixel inside,
  // its cells read half a cell off) are read again at their sides' mid-level crossings (cell centres,
  // at most one border cell wrong, the id checked by the dictionary with error_correction_rate). Only
  // with dictionaries where a random pattern is within the correction margin of an id with a chance
  // below 1e-3 (DICT_6X6_250: 1.1e-4; not DICT_4X4_*), and not with inverted markers.
  bool reread_rejected = true;
  // A rejected candidate that is no marker read again may hold one: a dark card or tool face around a
  // marker whose margin is too thin at a steep view to part its border from the card at the adaptive
  // threshold (the candidate is the card's outline). Its box is searched again for quads at
  // low_threshold_level and at this level of the local range (detector/candidates.h), each read as the
  // own search reads them (0: not searched). With reread_rejected's dictionaries only.
  double inside_rejected_level = 0.15;
  // A marker whose thin blurred border (60-75 deg under 1.2 px blur) breaks at OpenCV's adaptive
  // threshold where white code cells touch it has no candidate. On a blurred frame (its markers' mean
  // fitted blur >= 0.55 px, as sharp_smoothing judges it; needs sharp_smoothing > 0) the tiles with
  // contrast that no marker found touches are searched again for quads dark below the mean of this
  // window (px) less broken_border_offset grey levels (a negative offset: darker than the mean plus
  // |offset|), each read as a rejected candidate (0: not searched). With reread_rejected's dictionaries.
  int broken_border_window = 5;
  double broken_border_offset = -3;
  double broken_border_min_perimeter_px = 80;  // smaller quads of that search are not read
  int min_distance_to_border = 1;              // pixels
  double error_correction_rate = 0.6;          // of the dictionary's correction capacity
  int perspective_pixels_per_cell = 6;         // bit sampling resolution
  double perspective_ignored_margin = 0.3;     // part of each cell ignored when reading its bit
  bool inverted = false;     // also look for white-on-black markers (default: markers.inverted)
  bool aruco3 = false;       // OpenCV's ArUco3 fast search (downsampled candidate search)
  int aruco3_min_side = 32;  // its minSideLengthCanonicalImg
  // Fast mode.
  bool fast = false;
  int full_search_every = 10;  // frames between full searches in fast mode
  // Between them, each previous marker's box grown by this many of its sides (its larger side on every
  // side; overlapping boxes merged) is searched as the full search searches the image: a marker coming
  // into view there (a box's next face, a neighbour) is found in the frame it appears in.
  double fast_band_sides = 2.0;
  // Drop every marker whose id is detected twice in one image (one of them is wrong).
  bool drop_duplicate_ids = true;
  // A marker whose edges cannot be fitted keeps cv::cornerSubPix corners (small markers often: they still
  // connect cameras and markers); true: dropped. A refinement that slid a cell off (its refined corners
  // no longer read the code) is always dropped.
  bool drop_unrefined = false;

  // From the rig YAML `detector:` section (keys as the field names, declared in detector/options.cc),
  // markers.inverted as the default of `inverted`. Unknown keys and bad values throw OptionError naming
  // the file and key.
  static DetectorOptions FromConfig(const RigConfig& rig);
  // The same checks for options built in code (file empty) or read from `file`; throws OptionError.
  void Validate(const std::string& file = "") const;
};

// Every `detector:` key of the marker detector: name, member, unit, check, help (loading, checks, docs).
template <class T>
class OptionTable;
const OptionTable<DetectorOptions>& DetectorOptionTable();

struct DetectorStats {
  long long frames = 0;
  long long full_searches = 0;
  long long markers = 0;
  long long refine_failures = 0;  // markers whose edges could not be fitted (cornerSubPix or dropped)
  long long dropped = 0;          // ... of which dropped
  long long rereads = 0;          // rejected candidates read again (reread_rejected) ...
  long long rereads_found = 0;    // ... of which markers
  // Codes read from unmixed cell levels (cells as narrow as the blur: MarkerDetector::ReadCode).
  long long deconvolved_reads = 0;
  // Quads of the broken-border search read (DetectorOptions::broken_border_window) ...
  long long broken_border_quads = 0;
  long long broken_border_found = 0;  // ... of which markers
};

// Refines the corners (ArUco order, raw image pixels, pixel centres at integer coordinates) of one
// marker in place. `gray` is 8-bit. `cells` is the marker's width in cells including the border
// (bits + 2). `bits` (cells-2 x cells-2, CV_8U 0/1, the marker's bits as in its dictionary at corner 0 =
// top-left) may be empty; with it, edge samples next to bit cells of value 1 are skipped. `camera` may be
// null (straight sides in the image). Returns false (corners unchanged) if an edge cannot be located or
// the corners would end more than two cells from where they started (the start is a candidate on the
// marker's outline: such corners have left the marker).
// A side without a clean mid-level crossing keeps the line through its current corners for the side
// model to fit; `kept_lines` (optional) tells whether any side did. `polarity`: +1 the border is darker
// than the code's other colour, -1 brighter, 0 unknown (side fits of the wrong polarity are retried a
// cell outward: SideProfiles::polarity). `held_gamma` > 0 (with fit_gamma): the camera's gamma, known,
// held in every side's model (SideProfiles::hold_gamma) instead of fitted per side.
bool RefineMarkerCorners(const cv::Mat& gray, int cells, const cv::Mat& bits, const CameraModel* camera,
                         int passes, std::array<cv::Point2d, 4>* corners, bool model_fit = true,
                         double* blur_sigma = nullptr, bool fit_gamma = false, bool* kept_lines = nullptr,
                         int polarity = 0, double held_gamma = 0.0);

// What the refinements (RefineMarkerCorners) of this thread have done since it started: model passes
// (every side located with the side model, or kept where it had settled), side-model fits (FitSide: one
// side's profiles fitted, with its refits) and model-only rounds. Their cost is about proportional to the
// side fits (issue 15's speed: bench/results/2026-12-07-passes.md); tests bound them.
struct RefinementCounts {
  long long model_passes = 0, side_fits = 0, rounds = 0;
};
RefinementCounts RefinementCountsOnThisThread();

struct QuadSearch;  // detector/candidates.h
class QuadFinder;   // detector/candidates.h

class MarkerDetector {
 public:
  MarkerDetector(const MarkerConfig& markers, const DetectorOptions& options);
  ~MarkerDetector();

  // Refinement with the camera model (edges fitted as straight lines in undistorted pixels). Without it
  // sides are fitted as straight lines in the image.
  void SetCamera(const CameraModel& camera);

  // Markers in the image (8-bit gray or BGR), corners in ArUco order, whitelist applied, sorted by id.
  std::vector<marker_t> Detect(const cv::Mat& image);
  // Forgets the previous frame (fast mode).
  void Reset();

  const DetectorStats& stats() const { return stats_; }
  const DetectorOptions& options() const { return options_; }
  const cv::aruco::Dictionary& dictionary() const { return *dictionary_; }
  // tone "auto": the estimate once made (ok false before).
  const ToneEstimate& tone() const { return tone_estimate_; }
  // tone "auto": `tone` (ok) used from the next frame on instead of an estimate of its own.
  void UseTone(const ToneEstimate& tone);
  // tone "auto": still collecting markers (false once estimated or given up after tone_frames).
  bool ToneEstimating() const { return tone_ != nullptr; }

 private:
  struct Raw {
    int id;
    std::array<cv::Point2d, 4> corners;
    bool deconvolved = false;  // read from unmixed cell levels (DeconvolvedCells)
  };
  // corner_refinement "edges": a marker's corners refined on a smoothed region (sharp_smoothing).
  struct Refined {
    std::array<cv::Point2d, 4> corners;
    bool refined = false, kept_lines = false;
  };
  std::vector<Raw> Search(const cv::Mat& gray, const cv::Rect& roi, double min_perimeter,
                          double max_perimeter, int window_min, int window_max);
  // The full search's candidate search (every threshold window, every perimeter) in `roi`.
  std::vector<Raw> FullSearch(const cv::Mat& gray, const cv::Rect& roi);
  // Fast mode's search regions: each previous marker's box grown by fast_band_sides of its larger side
  // (and 4 px) on every side, overlapping ones merged.
  std::vector<cv::Rect> TrackRegions(cv::Size size) const;
  const cv::Mat& MarkerBits(int id);                         // the dictionary's bits of `id` (cached)
  int Cells() const { return dictionary_->markerSize + 2; }  // a marker's width in cells, border included
  // The region a marker `r` is refined on: its box grown by half its larger side and 6 px, in the image.
  static cv::Rect RegionBox(const Raw& r, cv::Size image);
  // A candidate OpenCV rejected, read again at its sides' mid-level crossings; false if not a marker.
  bool RereadCandidate(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad, Raw* r);
  // A marker inside a candidate OpenCV rejected (DetectorOptions::inside_rejected_level): quads of the
  // candidate's box at low levels of the local range, read; false if none is a marker.
  bool SearchInsideRejected(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad, Raw* r);
  // Markers whose blurred border breaks at OpenCV's adaptive threshold (DetectorOptions::
  // broken_border_window): quads of a binary image dark below the local mean plus broken_border_offset
  // outside the markers in `out` (found in `roi`), read; markers added to `out`.
  void SearchBrokenBorders(const cv::Mat& gray, const cv::Rect& roi, double min_perimeter,
                           double max_perimeter, std::vector<Raw>* out);
  // A marker region with the camera's sharpening undone (unsharp_amount), smoothed by `smoothing` px.
  void UnsharpRegion(const cv::Mat& from, double smoothing, cv::Mat to);
  // The code of a candidate read at the cell centres of `corners` (`quad`'s corners or refined ones),
  // `polarity` as MarkerPolarity's; r->corners: `quad` in the order of the code's rotation.
  bool ReadCode(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad,
                const std::array<cv::Point2d, 4>& corners, int polarity, int max_border_errors, Raw* r);
  // The code of the cells' levels `values` (cells x cells, row-major) thresholded, as ReadCode's.
  bool IdentifyCells(const std::vector<float>& values, const std::array<cv::Point2d, 4>& quad, int polarity,
                     int max_border_errors, Raw* r);
  // The own candidate search's settings (detector/candidates.h) for quads of this perimeter range, px.
  QuadSearch OwnQuadSearch(double min_perimeter, double max_perimeter) const;
  // A quad of the own search read at its cell centres with a dark border (at most own_border_errors_
  // border cells bright), or where that fails (and the dictionary makes it safe) at its sides' mid-level
  // crossings; false if it is no marker.
  bool ReadQuad(const cv::Mat& gray, const std::array<cv::Point2d, 4>& quad, Raw* r);
  // candidate_search "own": quads of detector/candidates.h, polarity-checked and read.
  std::vector<Raw> OwnSearch(const cv::Mat& gray, const cv::Rect& roi, double min_perimeter,
                             double max_perimeter);
  // Reads `quads` (found by `finder` in region `roi`, in its pixels): each that is a marker of the set is
  // added to `out` and covered in the finder. Returns how many were read.
  int ReadRegionQuads(const cv::Mat& gray, const cv::Rect& roi,
                      const std::vector<std::array<cv::Point2d, 4>>& quads, QuadFinder* finder,
                      std::vector<Raw>* out);

  // Each id once: one marker found twice (regions overlapping in fast mode, quads of one marker from two
  // threshold windows, or the marker's and its narrow margin's quads both decoding: quads whose centres
  // lie inside each other) kept once, the quad whose code reads best; one id in two distinct places is
  // wrong once, so both are dropped (drop_duplicate_ids).
  std::vector<Raw> DropDuplicates(const cv::Mat& gray, const std::vector<Raw>& raw);
  // Quads that only look like markers dropped: the dark parts of an inverted print (markers.inverted),
  // a pattern of another marker's bits (its centre inside a quad 1.5 times its area).
  std::vector<Raw> DropLookAlikes(const cv::Mat& gray, std::vector<Raw> unique) const;
  // The image a marker is refined on (gray, or its region linearised / unsharpened into linear_), and the
  // region `roi` there.
  const cv::Mat* RefineRegion(const cv::Mat& gray, const Raw& r, cv::Rect* roi);
  // RefineMarkerCorners of `r` on `roi` of `from`, `corners` in the image's pixels.
  bool RefineInRegion(const cv::Mat& from, const cv::Rect& roi, const Raw& r,
                      std::array<cv::Point2d, 4>* corners, double* blur, bool* kept_lines);
  // Every marker refined on its smoothed region; `sharp_frame`: whether those refinements are the ones
  // to use (the frame's mean blur is small).
  std::vector<Refined> RefineSmoothed(const cv::Mat& gray, const std::vector<Raw>& unique, bool* sharp_frame);
  // r's corners refined ("edges"; `smoothed`: the smoothed region's refinement to use instead), judged
  // on its code, or OpenCV's corner refinement where no edge is clear. False: the marker is dropped.
  bool RefineCorners(const cv::Mat& gray, const Refined* smoothed, Raw* r);

  MarkerConfig markers_;
  DetectorOptions options_;
  cv::Ptr<cv::aruco::Dictionary> dictionary_;
  std::unique_ptr<CameraModel> camera_;
  bool reread_ = false;        // reread_rejected, where the dictionary makes it safe
  int own_border_errors_ = 0;  // candidate_search "own": border cells allowed of the other colour
  std::vector<cv::Mat> bits_;  // per id, cached
  cv::Mat smooth_;             // smoothed marker regions (sharp_smoothing)
  cv::Mat linear_;             // linearised marker regions (gamma)
  cv::Mat gamma_lut_;          // encoded value -> linear value
  cv::Mat unsharp_in_, unsharp_out_, unsharp_blur_;  // float regions of the unsharp mask's inverse
  DetectorStats stats_;
  // tone "auto": the markers collected until the estimate is made (then null), frames seen.
  void ObserveTone(const cv::Mat& gray, const std::vector<marker_t>& markers);
  std::unique_ptr<ToneEstimator> tone_;
  ToneEstimate tone_estimate_;
  int tone_frames_seen_ = 0;
  // Fast mode state.
  std::vector<Raw> last_;
  int frames_since_full_ = 0;
};

// Offline: every frame of one camera's recorded source (rig YAML), detected at full speed with the
// camera's intrinsics and the rig's detector settings, as the messages mcmt-detector would publish
// (utime, seq, camera, dictionary, camera model, markers, detection_ms). max_frames < 0: all. With
// tone auto the recording is read twice, as mcmt-detector reads one: the estimate (from its first
// frames' markers) is then used on every frame, the first ones too (live, only on the frames after it).
// Throws std::runtime_error naming the camera and file on bad input (see DetectorNode).
std::vector<detections_t> DetectRecording(const RigConfig& rig, const std::string& camera,
                                          int max_frames = -1);

}  // namespace mcmt
