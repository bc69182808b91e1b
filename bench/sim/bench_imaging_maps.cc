// Maps from rendered sessions under varied imaging: the paper's rig (5 cameras on a circle, 640x480,
// four-sided object with 4 cm markers unless a row names another, 300 frames), each session rendered under
// one imaging condition,
// every frame detected by mcmt's detector (accurate mode, the camera's intrinsics), mapped by the mapper,
// evaluated against the ground truth: metric scale error (least-squares ratio of all camera-to-camera
// distances, estimate over truth), camera position and configuration errors (sim/eval.h). Prints a
// markdown table. Beside each map, a reference: the same markers in the same frames (those the detector
// found) at their true corners plus Gaussian noise of kReferenceNoisePx per coordinate, mapped alike; what
// the corners' bias costs is the difference, the rest is what the session's information allows.
//   bench_imaging_maps [--quick | frames (default 300)] [radius, m (default: 1.0 and 1.3)]
// (--quick: 100 frames at 1.0 m.)
// Diagnosis (issue 15, systematic corner errors), environment:
//   MCMT_IMAGING_CONDITIONS=0,3  only these conditions (indices into the table's rows per radius)
//   MCMT_IMAGING_DUMP=FILE      one CSV line per detected corner: its error against the truth with the
//                               marker's view angle, size, occlusion, distance to the image border
//   MCMT_IMAGING_DROP=WHAT      map without the detections WHAT names: "occluded" (the truth says part of
//                               the marker is hidden), "unseen" (not fully_visible), "err:PX" (any corner
//                               farther than PX from the truth: an oracle, for measuring only), "angle:DEG"
//                               (view angle above DEG)
//   MCMT_VIEW_WEIGHT_POWER=P    the mapper's view_weight_power (both maps)
//   MCMT_CORNER_WEIGHTS=W       the mapper's corner_weights (equal or sides; both maps)
//   MCMT_CORNER_WEIGHT_FLOOR=F  the mapper's corner_weight_floor
//   MCMT_CANDIDATE_SEARCH=S     the detector's candidate_search (opencv or own)
//   MCMT_IMAGING_RENDERER=reference  the sessions drawn by the independent reference renderer
//                               (tests/mapper/reference_rig_view.h) under the conditions of its catalogue
//                               (tests/detector/reference_renderer.h) instead of mcmt-sim's; the rows are
//                               the catalogue's conditions
//   MCMT_IMAGING_REPORT=1       print the mapper's report for each map of mcmt's detector to stderr: its
//                               warnings, rejected markers, RMS, per-camera verdicts, and each camera's
//                               and marker's error against the truth
//   MCMT_IMAGING_SAVE=FILE      the detections each map of mcmt's detector is given, written to FILE (a new
//                               LCM log, channels MCMT_DETECTIONS_<camera>: mcmt-mapper reads it too)
//   MCMT_IMAGING_LOAD=FILE      map the detections MCMT_IMAGING_SAVE wrote instead of rendering (one
//                               condition; no reference map)
//   MCMT_IMAGING_OVERRIDE=SPEC  with MCMT_IMAGING_RENDERER=reference: every catalogue condition with the
//                               Imaging fields SPEC names set ("motion_px=0,jpeg_quality=0"; ablations)
//   MCMT_IMAGING_SIM_OVERRIDE=SPEC  with mcmt-sim's renders: the RenderOptions fields SPEC names set in the
//                               session and every camera ("surface_albedo=0.45,blur_sigma=0.5"); a field
//                               prefixed "cN." only in camera N ("c0.blur_sigma=0.5"; ablations). "cN."
//                               acts only on rows with per-camera options (--imaging random), and not on
//                               the surface_* fields (the renderer takes those from the session's options);
//                               "supersampling=S": S x S point samples per pixel instead of the exact box
//   MCMT_IMAGING_OBJECT=KIND    every row's session with this object (mcmt-sim's kinds: four_sided, box,
//                               pentagon, cube, board; its default marker size), e.g. the pentagon's small
//                               markers drawn by the reference renderer
//   MCMT_IMAGING_CAMERA=N       detect camera N's frames only (with MCMT_IMAGING_DUMP: one camera's corners;
//                               the maps fail for want of the other cameras)
//   MCMT_IMAGING_SIDE_ORACLE=R[:LO-HI]  an oracle (measuring only): the sides whose role R names (comma-
//                               separated: top, bottom, near, far, or all) lose their mean offset along the
//                               true side's outward normal before mapping; their tilt and the other sides'
//                               offsets are kept. Roles as 2026-12-07-seeds13-split.py: side 0 (corners 0-1)
//                               top, 2 bottom, of 1 / 3 the longer in the image near, the other far. With
//                               :LO-HI only markers seen at view angles LO-HI deg. With "tilt" in R the
//                               named sides lose instead their ends' difference (each end set to the side's
//                               mean), with "both" both (the side's two corners at the truth along its
//                               normal)
//   MCMT_IMAGING_SHRINK_PCT=P   each detected marker's corners moved P % of the way to their centroid before
//                               mapping (an oracle: what an isotropic size bias of the corners costs the
//                               map's scale; negative P enlarges)
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/dictionary.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "core/log_writer.h"
#include "detector/detector.h"
#include "mapper/diagnostics.h"
#include "mapper/mapper.h"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/mapper/reference_rig_view.h"
#include "tests/mapper/rendered_session.h"

using namespace mcmt;

namespace {

// About the detector's median corner error on these renders (0.08-0.10 px, 2-D, markers 15-22 px).
constexpr double kReferenceNoisePx = 0.07;

struct Condition {
  std::string name;
  sim::RenderOptions render;
  const testing::Imaging* reference = nullptr;  // drawn by the reference renderer under this instead
  sim::ObjectKind object = sim::ObjectKind::kFourSided;
};

// MCMT_IMAGING_OBJECT: every row's object; an unknown kind stops the bench naming it.
std::vector<Condition> WithObjectOverride(std::vector<Condition> c) {
  const char* e = std::getenv("MCMT_IMAGING_OBJECT");
  if (!e) return c;
  try {
    const sim::ObjectKind kind = sim::ObjectKindFromName(e);
    for (Condition& row : c) row.object = kind;
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "MCMT_IMAGING_OBJECT=%s: %s\n", e, ex.what());
    std::exit(2);
  }
  return c;
}

std::vector<Condition> Conditions() {
  std::vector<Condition> c;
  if (const char* e = std::getenv("MCMT_IMAGING_RENDERER"); e && std::string(e) == "reference") {
    static const std::vector<testing::Imaging> catalogue = [] {
      std::vector<testing::Imaging> list = testing::ImagingCatalogue();
      if (const char* spec = std::getenv("MCMT_IMAGING_OVERRIDE"))
        for (testing::Imaging& im : list) testing::OverrideImaging(spec, &im);
      return list;
    }();
    for (const testing::Imaging& im : catalogue) c.push_back({"reference renderer: " + im.name, {}, &im});
    return c;
  } else if (e && std::string(e) != "sim") {
    std::fprintf(stderr, "MCMT_IMAGING_RENDERER=%s: expected sim or reference\n", e);
    std::exit(2);
  }
  sim::RenderOptions plain;
  c.push_back({"mcmt-sim default (linear, 1-cell margin)", plain});
  sim::RenderOptions webcam = plain;
  webcam.gamma = 2.2, webcam.sharpen = 0.6, webcam.jpeg_quality = 75, webcam.blur_sigma = 0.7;
  webcam.vignetting = 0.25, webcam.shot_noise = 0.08, webcam.quiet_zone_cells = 1,
  webcam.surface_albedo = 0.3;
  c.push_back({"webcam (gamma 2.2, sharpen 0.6, JPEG 75, blur 0.7)", webcam});
  sim::RenderOptions margin = plain;
  margin.quiet_zone_cells = 0, margin.surface_albedo = 0.45, margin.surface_texture = 0.2;
  c.push_back({"no margin, grained surface 0.45", margin});
  for (uint64_t seed : {11, 12, 13}) {
    sim::RenderOptions r = sim::RandomImaging(plain, 5, seed);
    c.push_back({"--imaging random, seed " + std::to_string(seed), r});
  }
  // Rows appended here keep the indices above (MCMT_IMAGING_CONDITIONS in the write-ups).
  // Small markers on small faces: 2.5 cm markers, 11-15 px at 1.0 m, the next face about 2 cells away.
  c.push_back({"pentagon object (2.5 cm markers)", plain, nullptr, sim::ObjectKind::kPentagon});
  // Wide paper margins: the margin's far side near the end of the side profiles' outward reach.
  sim::RenderOptions wide = plain;
  wide.quiet_zone_cells = 2;
  c.push_back({"2-cell paper margin", wide});
  wide.quiet_zone_cells = 3, wide.blur_sigma = 1.2;
  c.push_back({"3-cell paper margin, blur 1.2", wide});
  return c;
}

// One RenderOptions field by name (MCMT_IMAGING_SIM_OVERRIDE); false if it is not one of these.
bool SetRenderField(const std::string& field, double value, sim::RenderOptions* o) {
  if (field == "surface_albedo")
    o->surface_albedo = value;
  else if (field == "surface_texture")
    o->surface_texture = value;
  else if (field == "surface_tint")
    o->surface_tint[0] = o->surface_tint[1] = o->surface_tint[2] = value;
  else if (field == "shading")
    o->shading = value;
  else if (field == "lighting_gradient")
    o->lighting_gradient = value;
  else if (field == "vignetting")
    o->vignetting = value;
  else if (field == "blur_sigma")
    o->blur_sigma = value;
  else if (field == "defocus_radius")
    o->defocus_radius = value;
  else if (field == "noise_sigma")
    o->noise_sigma = value;
  else if (field == "shot_noise")
    o->shot_noise = value;
  else if (field == "gamma")
    o->gamma = value;
  else if (field == "sharpen")
    o->sharpen = value;
  else if (field == "jpeg_quality")
    o->jpeg_quality = static_cast<int>(value);
  else if (field == "quiet_zone_cells")
    o->quiet_zone_cells = static_cast<int>(value);
  else if (field == "supersampling")
    o->supersampling = static_cast<int>(value);
  else
    return false;
  return true;
}

// MCMT_IMAGING_SIM_OVERRIDE applied to the session's options and its cameras' (top of the file); a
// malformed item or an unknown field stops the bench with one line naming it.
void OverrideRender(const std::string& spec, sim::RenderOptions* render) {
  std::vector<testing::OverrideItem> items;
  try {
    items = testing::ParseOverrideSpec(spec);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "MCMT_IMAGING_SIM_OVERRIDE: %s\n", e.what());
    std::exit(2);
  }
  for (const testing::OverrideItem& item : items) {
    std::string field = item.name;
    int camera = -1;  // "cN.field": camera N only
    if (field.size() > 2 && field[0] == 'c' && field.find('.') != std::string::npos) {
      camera = std::atoi(field.c_str() + 1);
      field = field.substr(field.find('.') + 1);
    }
    bool ok = true;
    if (camera < 0) ok = SetRenderField(field, item.value, render);
    for (size_t c = 0; c < render->cameras.size() && ok; ++c)
      if (camera < 0 || static_cast<int>(c) == camera)
        ok = SetRenderField(field, item.value, &render->cameras[c]);
    if (!ok) {
      std::fprintf(stderr, "MCMT_IMAGING_SIM_OVERRIDE: unknown field '%s'\n", item.text.c_str());
      std::exit(2);
    }
  }
}

// MCMT_IMAGING_SIDE_ORACLE (see the top of the file).
struct SideOracle {
  bool role[4] = {false, false, false, false};  // top, bottom, near, far
  bool offset = true, tilt = false;
  double lo_deg = -1.0, hi_deg = 1e9;
};

SideOracle ParseSideOracle(const char* text) {
  SideOracle o;
  if (!text || !*text) return o;
  std::string s = text;
  const size_t colon = s.find(':');
  if (colon != std::string::npos) {
    std::sscanf(s.c_str() + colon + 1, "%lf-%lf", &o.lo_deg, &o.hi_deg);
    s = s.substr(0, colon);
  }
  const char* names[4] = {"top", "bottom", "near", "far"};
  for (int r = 0; r < 4; ++r)
    o.role[r] = s.find(names[r]) != std::string::npos || s.find("all") != std::string::npos;
  o.tilt = s.find("tilt") != std::string::npos || s.find("both") != std::string::npos;
  o.offset = s.find("tilt") == std::string::npos;
  return o;
}

// Moves the detected corners so that each side the oracle names has zero mean offset along the true side's
// outward normal: corner j is on sides j - 1 and j; its error d is changed to d' with d'.n_k = d.n_k - o_k
// for the named sides k of the two (o_k: the mean of the side's two corners' d.n_k), d'.n_k = d.n_k else.
void ApplySideOracle(const SideOracle& o, const sim::MarkerView& v, marker_t* m) {
  if (v.view_angle_deg < o.lo_deg || v.view_angle_deg >= o.hi_deg) return;
  double n[4][2], off[4], len[4], end[4][2];
  const double cx = (v.corners[0][0] + v.corners[1][0] + v.corners[2][0] + v.corners[3][0]) / 4;
  const double cy = (v.corners[0][1] + v.corners[1][1] + v.corners[2][1] + v.corners[3][1]) / 4;
  for (int k = 0; k < 4; ++k) {
    const int j = (k + 1) % 4;
    const double ex = v.corners[j][0] - v.corners[k][0], ey = v.corners[j][1] - v.corners[k][1];
    len[k] = std::hypot(ex, ey);
    n[k][0] = ey / len[k], n[k][1] = -ex / len[k];
    const double mx = (v.corners[k][0] + v.corners[j][0]) / 2, my = (v.corners[k][1] + v.corners[j][1]) / 2;
    if (n[k][0] * (mx - cx) + n[k][1] * (my - cy) < 0) n[k][0] = -n[k][0], n[k][1] = -n[k][1];
    for (int e = 0; e < 2; ++e) {
      const int c = e == 0 ? k : j;
      end[k][e] =
          (m->corners[c][0] - v.corners[c][0]) * n[k][0] + (m->corners[c][1] - v.corners[c][1]) * n[k][1];
    }
    off[k] = 0.5 * (end[k][0] + end[k][1]);
  }
  // The change along side k's normal at its end e (0: corner k, 1: corner k + 1).
  auto change = [&](int k, int e) {
    return -(o.offset ? off[k] : 0.0) - (o.tilt ? end[k][e] - off[k] : 0.0);
  };
  const int near = len[1] >= len[3] ? 1 : 3;
  bool named[4];
  for (int k = 0; k < 4; ++k) named[k] = o.role[k == 0 ? 0 : k == 2 ? 1 : k == near ? 2 : 3];
  for (int j = 0; j < 4; ++j) {
    const int a = (j + 3) % 4, b = j;  // the corner's two sides
    const double ra = named[a] ? change(a, 1) : 0.0, rb = named[b] ? change(b, 0) : 0.0;
    // Solve delta.n_a = ra, delta.n_b = rb.
    const double det = n[a][0] * n[b][1] - n[a][1] * n[b][0];
    if (std::fabs(det) < 1e-9) continue;
    m->corners[j][0] += (ra * n[b][1] - rb * n[a][1]) / det;
    m->corners[j][1] += (rb * n[a][0] - ra * n[b][0]) / det;
  }
}

// The marker's corners scaled by `factor` about their centroid (MCMT_IMAGING_SHRINK_PCT).
void ScaleAboutCentroid(double factor, marker_t* m) {
  if (factor == 1.0) return;
  for (int x = 0; x < 2; ++x) {
    const double c = (m->corners[0][x] + m->corners[1][x] + m->corners[2][x] + m->corners[3][x]) / 4.0;
    for (int k = 0; k < 4; ++k) m->corners[k][x] = c + (m->corners[k][x] - c) * factor;
  }
}

// The detections MCMT_IMAGING_DROP names are left out of the map (see the top of the file).
struct DropRule {
  bool occluded = false, unseen = false;
  double err_px = 0.0;     // 0: no error rule
  double angle_deg = 0.0;  // 0: no view-angle rule
};

DropRule ParseDropRule(const char* text) {
  DropRule r;
  if (!text || !*text) return r;
  const std::string s = text;
  if (s == "occluded")
    r.occluded = true;
  else if (s == "unseen")
    r.unseen = true;
  else if (s.rfind("err:", 0) == 0 && std::atof(s.c_str() + 4) > 0)
    r.err_px = std::atof(s.c_str() + 4);
  else if (s.rfind("angle:", 0) == 0 && std::atof(s.c_str() + 6) > 0)
    r.angle_deg = std::atof(s.c_str() + 6);
  else {
    std::fprintf(stderr, "MCMT_IMAGING_DROP=%s: expected occluded, unseen, err:PX or angle:DEG (> 0)\n",
                 text);
    std::exit(2);
  }
  return r;
}

double BorderDistancePx(const MarkerCorners2d& c, int width, int height) {
  double d = 1e9;
  for (int k = 0; k < 4; ++k) d = std::min({d, c[k][0], c[k][1], width - 1 - c[k][0], height - 1 - c[k][1]});
  return d;
}

// MCMT_IMAGING_LOAD: the detections messages of an LCM log (MCMT_IMAGING_SAVE wrote it).
std::vector<detections_t> LoadDetections(const char* path) {
  std::vector<detections_t> all;
  for (const LogEvent& ev : ReadEventLog(path)) {
    if (!IsDetectionsChannel(ev.channel)) continue;
    all.emplace_back();
    if (!Decode(ev.data.data(), ev.data.size(), &all.back())) all.pop_back();
  }
  return all;
}

// MCMT_IMAGING_REPORT: what the mapper said about a map, beside its errors against the truth.
void PrintReport(const MapResult& result, const sim::EvalResult& e) {
  const MapReport& r = result.report;
  std::fprintf(stderr,
               "mapper: rms %.3f px (initial %.3f), %d of %d observations used, %zu rejected, %d ambiguous\n",
               r.final_rms_px, r.initial_rms_px, r.observations_used, r.observations_total,
               r.rejected_observations.size(), r.ambiguous_observations);
  for (const std::string& w : r.warnings) std::fprintf(stderr, "mapper warning: %s\n", w.c_str());
  for (const RejectedMarker& m : r.rejected_markers)
    std::fprintf(stderr, "mapper rejected marker %d (%d observations): %s\n", m.id, m.observations,
                 m.reason.c_str());
  std::fprintf(stderr, "%s", VerdictLines(ComputeDiagnostics(result)).c_str());
  for (const sim::CameraError& c : e.cameras)
    std::fprintf(stderr, "truth: camera %s %.2f mm %.3f deg\n", c.name.c_str(), c.position_mm,
                 c.rotation_deg);
  for (const sim::MarkerError& m : e.markers)
    std::fprintf(stderr, "truth: marker %d corners %.2f mm, side %+.2f mm\n", m.id, m.corner_mm, m.size_mm);
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int frames = quick ? 100 : argc > 1 ? std::atoi(argv[1]) : 300;
  std::vector<double> radii = {1.0, 1.3};
  if (quick) radii = {1.0};
  if (argc > 2) radii = {std::atof(argv[2])};
  cv::setNumThreads(1);
  std::vector<int> only;
  if (const char* e = std::getenv("MCMT_IMAGING_CONDITIONS"))
    for (const char* p = e; *p;) {
      only.push_back(std::atoi(p));
      while (*p && *p != ',') ++p;
      if (*p) ++p;
    }
  const char* report_env = std::getenv("MCMT_IMAGING_REPORT");
  const bool report = report_env && std::atoi(report_env) != 0;
  const DropRule drop = ParseDropRule(std::getenv("MCMT_IMAGING_DROP"));
  const char* shrink_env = std::getenv("MCMT_IMAGING_SHRINK_PCT");
  const double shrink_pct = shrink_env ? std::atof(shrink_env) : 0.0;
  const SideOracle side_oracle = ParseSideOracle(std::getenv("MCMT_IMAGING_SIDE_ORACLE"));
  std::unique_ptr<EventLogWriter> save;
  if (const char* path = std::getenv("MCMT_IMAGING_SAVE")) save = std::make_unique<EventLogWriter>(path);
  const std::vector<Condition> conditions = WithObjectOverride(Conditions());
  FILE* dump = nullptr;
  if (const char* path = std::getenv("MCMT_IMAGING_DUMP")) {
    dump = std::fopen(path, "w");
    if (!dump) {
      std::fprintf(stderr, "MCMT_IMAGING_DUMP=%s: cannot write\n", path);
      return 2;
    }
    std::fprintf(dump,
                 "radius,condition,camera,seq,id,corner,dx,dy,err,view_deg,size_px,occluded,fully_visible,"
                 "in_image,border_px,x,y\n");
  }
  std::printf(
      "## Maps under varied imaging (paper's rig, 5 cameras, 640x480, four-sided object with 4 cm markers "
      "unless the row names another, %d frames)\n\n",
      frames);
  std::printf(
      "| imaging | radius m | scale error %% | camera position mm (mean / max) | configuration mm (mean) | "
      "markers detected per frame | true corners + noise: scale error %% | true corners + noise: camera "
      "position mm (mean / max) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (double radius : radii)
    for (size_t ci = 0; ci < conditions.size(); ++ci) {
      if (!only.empty() && std::find(only.begin(), only.end(), static_cast<int>(ci)) == only.end()) continue;
      const Condition& condition = conditions[ci];
      sim::ObjectOptions object_options;
      object_options.kind = condition.object;
      object_options.marker_size = -1.0;  // the kind's default (pentagon 2.5 cm, the others 4 cm)
      const testing::RenderedMapSession session =
          testing::MakeRenderedMapSession(radius, frames, object_options);
      const std::vector<sim::SimCamera>& cameras = session.cameras;
      const sim::SimObject& object = session.object;
      const std::vector<sim::SimFrame>& trajectory = session.trajectory;
      sim::RenderOptions render = condition.render;
      if (const char* spec = std::getenv("MCMT_IMAGING_SIM_OVERRIDE")) OverrideRender(spec, &render);
      sim::Renderer renderer(object, session.markers.dictionary, render);
      const cv::Ptr<cv::aruco::Dictionary> dictionary = LoadDictionary(session.markers.dictionary);
      if (dump && !condition.reference)
        for (size_t c = 0; c < cameras.size(); ++c)
          std::fprintf(stderr, "condition %zu camera %zu: %s, tint %.3f\n", ci, c,
                       sim::DescribeImaging(render.ForCamera(static_cast<int>(c))).c_str(),
                       0.114 * render.surface_tint[0] + 0.587 * render.surface_tint[1] +
                           0.299 * render.surface_tint[2]);
      MapperOptions mo = session.Mapping();
      if (const char* e = std::getenv("MCMT_VIEW_WEIGHT_POWER")) mo.view_weight_power = std::atof(e);
      if (const char* e = std::getenv("MCMT_CORNER_WEIGHTS")) mo.corner_weighting.mode = e;
      if (const char* e = std::getenv("MCMT_CORNER_WEIGHT_FLOOR")) mo.corner_weighting.floor = std::atof(e);
      Mapper mapper(mo), reference(mo);
      if (const char* path = std::getenv("MCMT_IMAGING_LOAD")) {
        const std::vector<detections_t> loaded = LoadDetections(path);
        for (const detections_t& d : loaded) mapper.Add(d);
        try {
          const MapResult result = mapper.Solve();
          const sim::EvalResult e = sim::Evaluate(session.Truth(), &result.map, nullptr);
          if (report) PrintReport(result, e);
          std::printf("| %s (loaded) | %.1f | %+.3f | %.2f / %.2f | %.3f | | |\n", condition.name.c_str(),
                      radius, 100.0 * e.scale_error, e.camera_position_mm.mean, e.camera_position_mm.max,
                      e.configuration_mm.mean);
        } catch (const std::exception& ex) {
          std::printf("| %s (loaded) | %.1f | (no map: %s) | | | | |\n", condition.name.c_str(), radius,
                      ex.what());
        }
        return 0;
      }
      std::mt19937 rng(7);
      std::normal_distribution<double> noise(0.0, kReferenceNoisePx);
      long long detected = 0;
      const char* camera_env = std::getenv("MCMT_IMAGING_CAMERA");
      for (size_t c = 0; c < cameras.size(); ++c) {
        if (camera_env && std::atoi(camera_env) != static_cast<int>(c)) continue;
        DetectorOptions options;
        if (const char* e = std::getenv("MCMT_CANDIDATE_SEARCH")) options.candidate_search = e;
        // An inverted print's markers searched as such (markers.inverted, and `inverted` as a rig config
        // defaults it).
        MarkerConfig markers = session.markers;
        if (condition.reference) markers.inverted = options.inverted = condition.reference->inverted;
        MarkerDetector detector(markers, options);
        detector.SetCamera(cameras[c].model);
        for (const sim::SimFrame& f : trajectory) {
          detections_t d = condition.reference
                               ? session.Detect(testing::RenderReferenceRigView(
                                                    *dictionary, object, cameras[c], f.rig_from_object,
                                                    *condition.reference, 1000003 * ci + 1009 * c + f.seq),
                                                c, f, &detector)
                               : session.Detect(renderer, c, f, &detector);
          const std::vector<sim::MarkerView> views =
              sim::ProjectMarkers(cameras[c], object, f.rig_from_object);
          std::vector<marker_t> kept;
          for (const marker_t& m : d.markers) {
            const sim::MarkerView* v = nullptr;
            for (const sim::MarkerView& w : views)
              if (w.id == m.id) v = &w;
            double max_err = 0;
            for (int k = 0; k < 4 && v; ++k) {
              const double dx = m.corners[k][0] - v->corners[k][0], dy = m.corners[k][1] - v->corners[k][1];
              max_err = std::max(max_err, std::hypot(dx, dy));
              if (dump)
                std::fprintf(
                    dump, "%.1f,%zu,%zu,%lld,%d,%d,%.4f,%.4f,%.4f,%.2f,%.2f,%d,%d,%d,%.2f,%.2f,%.2f\n",
                    radius, ci, c, static_cast<long long>(f.seq), m.id, k, dx, dy, std::hypot(dx, dy),
                    v->view_angle_deg, v->size_px, v->occluded, v->fully_visible, v->in_image,
                    BorderDistancePx(v->corners, cameras[c].model.width, cameras[c].model.height),
                    v->corners[k][0], v->corners[k][1]);
            }
            const bool dropped = v && ((drop.occluded && v->occluded) || (drop.unseen && !v->fully_visible) ||
                                       (drop.err_px > 0 && max_err > drop.err_px) ||
                                       (drop.angle_deg > 0 && v->view_angle_deg > drop.angle_deg));
            if (!dropped) kept.push_back(m);
            if (!dropped && v) ApplySideOracle(side_oracle, *v, &kept.back());
          }
          d.markers = kept;
          for (marker_t& m : d.markers) ScaleAboutCentroid(1.0 - shrink_pct / 100.0, &m);
          d.num_markers = static_cast<int32_t>(d.markers.size());
          detected += d.num_markers;
          mapper.Add(d);
          if (save) {
            const std::vector<uint8_t> data = Encode(d);
            save->Write(d.utime, DetectionsChannel(d.camera), data.data(), data.size());
          }
          for (marker_t& m : d.markers)
            for (const sim::MarkerView& v : views)
              if (v.id == m.id)
                for (int k = 0; k < 4; ++k)
                  for (int x = 0; x < 2; ++x) m.corners[k][x] = v.corners[k][x] + noise(rng);
          reference.Add(d);
        }
      }
      const sim::GroundTruth truth = session.Truth();
      std::string reference_cells = "(no map) | ";
      try {
        const MapResult result = reference.Solve();
        const sim::EvalResult e = sim::Evaluate(truth, &result.map, nullptr);
        char cells[96];
        std::snprintf(cells, sizeof(cells), "%+.3f | %.2f / %.2f", 100.0 * e.scale_error,
                      e.camera_position_mm.mean, e.camera_position_mm.max);
        reference_cells = cells;
      } catch (const std::exception&) {
      }
      try {
        const MapResult result = mapper.Solve();
        const sim::EvalResult e = sim::Evaluate(truth, &result.map, nullptr);
        if (report) PrintReport(result, e);
        std::printf("| %s | %.1f | %+.3f | %.2f / %.2f | %.3f | %.2f | %s |\n", condition.name.c_str(),
                    radius, 100.0 * e.scale_error, e.camera_position_mm.mean, e.camera_position_mm.max,
                    e.configuration_mm.mean, double(detected) / (frames * cameras.size()),
                    reference_cells.c_str());
      } catch (const std::exception& ex) {
        std::printf("| %s | %.1f | (no map: %s) | | | %.2f | %s |\n", condition.name.c_str(), radius,
                    ex.what(), double(detected) / (frames * cameras.size()), reference_cells.c_str());
      }
      std::fflush(stdout);
    }
  if (save) save->Close();
  return 0;
}
