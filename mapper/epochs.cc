// Cameras that moved during a session: the change-point search (mapper/epochs.h has the method), the split
// of a moved camera's messages into two epochs and the merge of the solved epochs into the map.
#include "mapper/epochs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "core/json.h"
#include "core/math.h"

namespace mcmt {
namespace {

constexpr int kMinSegment = 15;      // samples per epoch at least
constexpr int kClipHalfWindow = 10;  // running median over 2 * 10 + 1 samples
constexpr double kClipSigma = 4.0;   // whitened samples further than this from it are clipped
constexpr double kPi = 3.14159265358979323846;

struct CameraSeries {
  std::vector<Vector6d> x;  // Log(inv(rig_from_cam) * rig_from_cam_t)
  std::vector<int> frame;   // frame index per sample
};

// The object's pose at a frame from the most precise single-pose view of another placed, not excluded
// camera (a multi-marker fit before a lone marker with one kept hypothesis).
bool PoseFromOthers(const std::vector<ViewPose>& views, const std::vector<int>& frame_views, int camera,
                    const CameraPlacement& cameras, const std::vector<char>& excluded,
                    Rigid3* rig_from_object) {
  int best = -1;
  double best_rms = std::numeric_limits<double>::infinity();
  for (int v : frame_views) {
    const ViewPose& view = views[v];
    if (view.camera == camera || excluded[view.camera] || !cameras.placed[view.camera] ||
        view.cam_from_object.size() != 1)
      continue;
    const double rms = view.fit_rms >= 0 ? view.fit_rms : 1e6;
    if (rms < best_rms) {
      best_rms = rms;
      best = v;
    }
  }
  if (best < 0) return false;
  *rig_from_object = cameras.rig_from_cam[views[best].camera] * views[best].cam_from_object[0];
  return true;
}

std::vector<std::vector<int>> ViewsByFrame(const std::vector<ViewPose>& views, int num_frames) {
  std::vector<std::vector<int>> by_frame(num_frames);
  for (size_t v = 0; v < views.size(); ++v) by_frame[views[v].frame].push_back(static_cast<int>(v));
  return by_frame;
}

// The samples against `base` (a rig_from_cam).
CameraSeries SeriesOf(int camera, const Rigid3& base, const std::vector<ViewPose>& views,
                      const std::vector<std::vector<int>>& by_frame, const CameraPlacement& cameras,
                      const std::vector<char>& excluded) {
  CameraSeries s;
  const Rigid3 cam_from_rig = Inverse(base);
  for (size_t f = 0; f < by_frame.size(); ++f)
    for (int v : by_frame[f]) {
      const ViewPose& view = views[v];
      if (view.camera != camera || view.cam_from_object.size() != 1) continue;
      Rigid3 rig_from_object;
      if (!PoseFromOthers(views, by_frame[f], camera, cameras, excluded, &rig_from_object)) continue;
      s.x.push_back(ParamsFromRigid(cam_from_rig * rig_from_object * Inverse(view.cam_from_object[0])));
      s.frame.push_back(static_cast<int>(f));
    }
  return s;
}

// Component-wise median pose of samples [begin, end).
Rigid3 MedianPose(const std::vector<Vector6d>& x, int begin, int end) {
  Vector6d m;
  for (int d = 0; d < 6; ++d) {
    std::vector<double> v;
    for (int i = begin; i < end; ++i) v.push_back(x[i][d]);
    m[d] = Median(v);
  }
  return RigidFromParams(m);
}

}  // namespace

PoseEvidence CameraPoseEvidence(const BundleProblem& bp, int camera, double max_px) {
  const size_t num_frames = bp.rig_from_object.size();
  std::vector<std::set<int>> frame_cameras(num_frames);
  for (size_t k = 0; k < bp.observations.size(); ++k)
    if (bp.active[k]) frame_cameras[bp.observations[k].frame].insert(bp.observations[k].camera);
  const std::vector<double> rms = ObservationRms(bp);
  const Rigid3 cam_from_rig = RigidFromBlock(bp.cam_from_rig[camera].data());
  const CameraModel model = bp.Model(camera);
  PoseEvidence e;
  for (size_t k = 0; k < bp.observations.size(); ++k) {
    const BundleObservation& o = bp.observations[k];
    if (o.camera != camera || !(rms[k] <= max_px)) continue;
    if (frame_cameras[o.frame].size() - frame_cameras[o.frame].count(camera) == 0) continue;  // alone
    if (e.frame.empty() || e.frame.back() != o.frame) {
      e.frame.push_back(o.frame);
      e.h.push_back(Matrix6d::Zero());
      e.g.push_back(Vector6d::Zero());
    }
    const Rigid3 rig_from_marker =
        ObservedFramePose(bp, k) * RigidFromBlock(bp.object_from_marker[o.marker].data());
    const MarkerCorners3d corners = MarkerCornersInMarker(o.side);
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d p_cam = cam_from_rig * (rig_from_marker * corners[c]);
      Eigen::Vector2d pixel;
      Eigen::Matrix<double, 2, 3> d_pixel;
      if (!model.Project(p_cam, &pixel, &d_pixel)) continue;
      Eigen::Matrix<double, 3, 6> d_point;
      d_point << -Skew(p_cam - cam_from_rig.translation()), Eigen::Matrix3d::Identity();
      const Eigen::Matrix<double, 2, 6> j = d_pixel * d_point;
      e.h.back() += j.transpose() * j;
      e.g.back() -= j.transpose() * (pixel - o.corners[c]);
    }
  }
  std::vector<double> sq;
  for (size_t k = 0; k < rms.size(); ++k)
    if (bp.active[k] && std::isfinite(rms[k])) sq.push_back(rms[k] * rms[k]);
  e.sigma2 = std::max(0.5 * Median(sq), 1e-4);  // per coordinate
  return e;
}

namespace {

// g^T H^-1 g and H^-1 g.
double Explained(const Matrix6d& h, const Vector6d& g, Vector6d* delta) {
  const Matrix6d regular = h + Matrix6d::Identity() * (1e-9 * h.trace() + 1e-12);
  *delta = regular.ldlt().solve(g);
  return g.dot(*delta);
}

// cam_from_rig moved by the left perturbation delta (LeftPoseManifold's Plus), as rig_from_cam.
Rigid3 MovedRigFromCam(const Rigid3& cam_from_rig, const Vector6d& delta) {
  Rigid3 moved = cam_from_rig;
  moved.linear() = RotationFromVector(delta.head<3>()) * cam_from_rig.linear();
  moved.translation() = cam_from_rig.translation() + delta.tail<3>();
  return Inverse(moved);
}

}  // namespace

int BestSplit(const PoseEvidence& e, int min_segment, double* score, Vector6d* before, Vector6d* after) {
  const int n = static_cast<int>(e.frame.size());
  *score = 0.0;
  if (n < 2 * min_segment) return -1;
  std::vector<Matrix6d> hp(n + 1, Matrix6d::Zero());
  std::vector<Vector6d> gp(n + 1, Vector6d::Zero());
  for (int i = 0; i < n; ++i) {
    hp[i + 1] = hp[i] + e.h[i];
    gp[i + 1] = gp[i] + e.g[i];
  }
  Vector6d d_all, d_a, d_b;
  const double all = Explained(hp[n], gp[n], &d_all);
  int best = -1;
  for (int k = min_segment; k <= n - min_segment; ++k) {
    const double t =
        (Explained(hp[k], gp[k], &d_a) + Explained(hp[n] - hp[k], gp[n] - gp[k], &d_b) - all) / e.sigma2;
    if (t > *score) {
      *score = t;
      best = k;
      *before = d_a;
      *after = d_b;
    }
  }
  return best;
}

std::vector<EpochSplit> FindCameraMoves(const BundleProblem& bp, const std::vector<Frame>& frames,
                                        const MapperOptions& options, const std::vector<char>& skip) {
  std::vector<EpochSplit> splits;
  // A moved camera stands out: its RMS with one pose is well above the other cameras' (systematic
  // residual patterns of real lenses split every camera a little, and alike).
  const std::vector<double> rms = ObservationRms(bp);
  std::vector<double> sq(bp.cam_from_rig.size(), 0.0), camera_rms;
  std::vector<int> n(bp.cam_from_rig.size(), 0);
  for (size_t k = 0; k < rms.size(); ++k)
    if (bp.active[k] && std::isfinite(rms[k])) {
      sq[bp.observations[k].camera] += rms[k] * rms[k];
      ++n[bp.observations[k].camera];
    }
  for (size_t c = 0; c < sq.size(); ++c)
    if (n[c]) camera_rms.push_back(std::sqrt(sq[c] / n[c]));
  const double typical_rms = Median(camera_rms);
  for (size_t c = 0; c < bp.cam_from_rig.size(); ++c) {
    if (c < skip.size() && skip[c]) continue;
    if (!(n[c] && std::sqrt(sq[c] / n[c]) > options.move_min_rms_ratio * typical_rms)) continue;
    const PoseEvidence e = CameraPoseEvidence(bp, static_cast<int>(c), 4 * options.outlier_px);
    double score = 0;
    Vector6d before, after;
    const int k = BestSplit(e, kMinSegment, &score, &before, &after);
    if (k < 0 || !(score > options.move_min_score)) continue;
    const Rigid3 cam_from_rig = RigidFromBlock(bp.cam_from_rig[c].data());
    const Rigid3 a = MovedRigFromCam(cam_from_rig, before), b = MovedRigFromCam(cam_from_rig, after);
    EpochSplit s;
    s.camera = static_cast<int>(c);
    s.rotation_deg = RotationAngle(a, b) * 180.0 / kPi;
    s.translation_mm = 1000.0 * TranslationDistance(a, b);
    if (s.rotation_deg < options.move_min_deg && s.translation_mm < options.move_min_mm) continue;
    s.frame = e.frame[k];
    s.utime = frames[s.frame].utime;
    s.seq = frames[s.frame].seq;
    s.score = score;
    s.samples_before = k;
    s.samples_after = static_cast<int>(e.frame.size()) - k;
    splits.push_back(s);
  }
  std::sort(splits.begin(), splits.end(),
            [](const EpochSplit& x, const EpochSplit& y) { return x.score > y.score; });
  return splits;
}

int PoseAgainstOthers(int camera, const Rigid3& base, const std::vector<ViewPose>& views, int num_frames,
                      const CameraPlacement& cameras, const std::vector<char>& excluded,
                      Rigid3* rig_from_cam) {
  const CameraSeries s = SeriesOf(camera, base, views, ViewsByFrame(views, num_frames), cameras, excluded);
  const int n = static_cast<int>(s.x.size());
  if (n == 0) return 0;
  Rigid3 refined = base * MedianPose(s.x, 0, n);
  // Again about the first median (a far-off base, e.g. an unplaced camera's identity, makes the
  // components' median less exact).
  const CameraSeries again =
      SeriesOf(camera, refined, views, ViewsByFrame(views, num_frames), cameras, excluded);
  *rig_from_cam = refined * MedianPose(again.x, 0, n);
  return n;
}

std::string EarlierEpochName(const std::string& camera) { return camera + "@before"; }

void SplitCameraEpochs(const std::vector<EpochSplit>& splits, std::vector<StoredMessage>* messages,
                       std::vector<std::string>* camera_names, std::vector<CameraModel>* models) {
  for (const EpochSplit& s : splits) {
    const int earlier = static_cast<int>(camera_names->size());
    camera_names->push_back(EarlierEpochName((*camera_names)[s.camera]));
    models->push_back((*models)[s.camera]);
    for (StoredMessage& m : *messages)
      if (m.camera == s.camera && m.utime < s.utime) m.camera = earlier;
  }
}

namespace {

// Removes the camera named `name` from the map; returns it (name empty when absent).
MapCamera TakeCamera(const std::string& name, RigMap* map) {
  MapCamera taken;
  for (auto it = map->cameras.begin(); it != map->cameras.end(); ++it)
    if (it->name == name) {
      taken = *it;
      map->cameras.erase(it);
      break;
    }
  return taken;
}

}  // namespace

void MergeCameraEpochs(const std::vector<EpochSplit>& splits, const std::vector<std::string>& camera_names,
                       MapResult* result) {
  MapReport& report = result->report;
  for (const EpochSplit& s : splits) {
    const std::string& name = camera_names[s.camera];
    const MapCamera earlier = TakeCamera(EarlierEpochName(name), &result->map);
    TakeCamera(EarlierEpochName(name), &result->initial_map);
    const MapCamera* latest = result->map.FindCamera(name);
    if (earlier.name.empty() || !latest) continue;  // an epoch dropped (--allow-partial): nothing to merge
    MovedCamera m;
    m.camera = name;
    m.seq = s.seq;
    m.utime = s.utime;
    m.rig_from_cam_before = earlier.rig_from_cam;
    m.observations_before = earlier.observations;
    m.rotation_deg = RotationAngle(earlier.rig_from_cam, latest->rig_from_cam) * 180.0 / kPi;
    m.translation_mm = 1000.0 * TranslationDistance(earlier.rig_from_cam, latest->rig_from_cam);
    report.moved_cameras.push_back(m);
    std::ostringstream w;
    w.setf(std::ios::fixed);
    w.precision(2);
    w << "camera '" << name << "' moved at seq " << s.seq << " (utime " << s.utime << "): turned "
      << m.rotation_deg << " deg, shifted " << m.translation_mm << " mm; solved with one pose before and one "
      << "after (" << earlier.observations << " + " << latest->observations
      << " observations), the map holds the pose after";
    report.warnings.push_back(w.str());
    auto& d = result->detections;
    d.erase(std::remove_if(d.begin(), d.end(),
                           [&](const detections_t& x) { return x.camera == name && x.utime < s.utime; }),
            d.end());
  }
}

std::string CameraChangesJson(const MapReport& report) {
  std::ostringstream j;
  j << "  \"moved_cameras\": [";
  for (size_t i = 0; i < report.moved_cameras.size(); ++i) {
    const MovedCamera& m = report.moved_cameras[i];
    const Eigen::Vector3d& t = m.rig_from_cam_before.translation();
    const std::array<double, 4> q = QuaternionWxyz(m.rig_from_cam_before);
    j << (i ? "," : "") << "\n    {\"camera\": " << JsonString(m.camera) << ", \"seq\": " << m.seq
      << ", \"utime\": " << m.utime << ", \"translation_mm\": " << JsonNumber(m.translation_mm)
      << ", \"rotation_deg\": " << JsonNumber(m.rotation_deg)
      << ", \"observations_before\": " << m.observations_before
      << ", \"rig_from_cam_before\": {\"translation\": [" << JsonNumber(t.x()) << ", " << JsonNumber(t.y())
      << ", " << JsonNumber(t.z()) << "], \"rotation_wxyz\": [" << JsonNumber(q[0]) << ", "
      << JsonNumber(q[1]) << ", " << JsonNumber(q[2]) << ", " << JsonNumber(q[3]) << "]}}";
  }
  j << "],\n  \"added_cameras\": [";
  for (size_t i = 0; i < report.added_cameras.size(); ++i)
    j << (i ? ", " : "") << JsonString(report.added_cameras[i]);
  j << "],\n";
  return j.str();
}

}  // namespace mcmt
