// Rigs, objects, trajectories and ground-truth projections of the simulator.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/math.h"
#include "sim/sim.h"
#include "sim/sim_internal.h"

namespace mcmt {
namespace sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

double Deg(double rad) { return rad * 180.0 / kPi; }
double Rad(double deg) { return deg * kPi / 180.0; }

// Rotation whose columns are the marker's x (right), y (up) and z (out of the face) axes.
Eigen::Matrix3d FrameFromNormalUp(const Eigen::Vector3d& normal, const Eigen::Vector3d& up_hint) {
  const Eigen::Vector3d z = normal.normalized();
  Eigen::Vector3d y = up_hint - up_hint.dot(z) * z;
  y.normalize();
  const Eigen::Vector3d x = y.cross(z);
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

Rigid3 MakePose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  Rigid3 pose = Rigid3::Identity();
  pose.linear() = rotation;
  pose.translation() = translation;
  return pose;
}

// Axis-aligned box faces (counter-clockwise seen from outside).
std::vector<SimFace> BoxFaces(double sx, double sy, double sz, double albedo) {
  const double hx = sx / 2, hy = sy / 2, hz = sz / 2;
  auto v = [&](double x, double y, double z) { return Eigen::Vector3d(x * hx, y * hy, z * hz); };
  std::vector<SimFace> faces = {
      {{v(1, -1, -1), v(1, 1, -1), v(1, 1, 1), v(1, -1, 1)}, albedo},      // +x
      {{v(-1, 1, -1), v(-1, -1, -1), v(-1, -1, 1), v(-1, 1, 1)}, albedo},  // -x
      {{v(1, 1, -1), v(-1, 1, -1), v(-1, 1, 1), v(1, 1, 1)}, albedo},      // +y
      {{v(-1, -1, -1), v(1, -1, -1), v(1, -1, 1), v(-1, -1, 1)}, albedo},  // -y
      {{v(-1, -1, 1), v(1, -1, 1), v(1, 1, 1), v(-1, 1, 1)}, albedo},      // +z
      {{v(-1, 1, -1), v(1, 1, -1), v(1, -1, -1), v(-1, -1, -1)}, albedo},  // -z
  };
  return faces;
}

// Regular prism with `sides` vertical sides, circumradius r, height h; side k's outward normal at
// angle 2 pi k / sides.
std::vector<SimFace> PrismFaces(int sides, double r, double h, double albedo) {
  std::vector<Eigen::Vector3d> ring;
  for (int k = 0; k < sides; ++k) {
    const double a = 2 * kPi * (k - 0.5) / sides;
    ring.emplace_back(r * std::cos(a), r * std::sin(a), 0.0);
  }
  const Eigen::Vector3d up(0, 0, h / 2);
  std::vector<SimFace> faces;
  for (int k = 0; k < sides; ++k) {
    const Eigen::Vector3d& a = ring[k];
    const Eigen::Vector3d& b = ring[(k + 1) % sides];
    faces.push_back({{a - up, b - up, b + up, a + up}, albedo});
  }
  SimFace top, bottom;
  for (int k = 0; k < sides; ++k) top.vertices.push_back(ring[k] + up);
  for (int k = sides - 1; k >= 0; --k) bottom.vertices.push_back(ring[k] - up);
  top.albedo = bottom.albedo = albedo;
  faces.push_back(top);
  faces.push_back(bottom);
  return faces;
}

double CircumRadius(const std::vector<SimFace>& faces) {
  double r = 0;
  for (const auto& f : faces)
    for (const auto& v : f.vertices) r = std::max(r, v.norm());
  return r;
}

// Marker centred at `centre` on a face with outward `normal`, its up direction `up` rotated by `roll`
// about the normal.
Rigid3 MarkerOnFace(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal, const Eigen::Vector3d& up,
                    double roll = 0.0) {
  Eigen::Matrix3d r = FrameFromNormalUp(normal, up);
  r = r * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return MakePose(r, centre);
}

// Smooth bounded random signal: sum of three sinusoids, |f| <= 1.
struct Wiggle {
  double amp[3], freq[3], phase[3];
  void Init(std::mt19937_64& rng, double min_hz, double max_hz) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double total = 0;
    for (int i = 0; i < 3; ++i) {
      amp[i] = 0.3 + 0.7 * u(rng);
      total += amp[i];
      freq[i] = min_hz + (max_hz - min_hz) * u(rng);
      phase[i] = 2 * kPi * u(rng);
    }
    for (double& a : amp) a /= total;
  }
  double operator()(double t) const {
    double s = 0;
    for (int i = 0; i < 3; ++i) s += amp[i] * std::sin(2 * kPi * freq[i] * t + phase[i]);
    return s;
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Rig

std::vector<double> DefaultDistortion(DistortionModel model) {
  switch (model) {
    case DistortionModel::kNone:
      return {};
    case DistortionModel::kRadTan:
      return {-0.12, 0.05, 0.0006, -0.0004, 0.0};
    case DistortionModel::kFisheye:
      return {0.04, -0.012, 0.003, -0.0006};
  }
  return {};
}

std::vector<SimCamera> MakeRig(const RigOptions& o) {
  if (o.num_cameras < 1 || o.num_cameras > 64)
    throw std::invalid_argument("cameras: expected 1..64, got " + std::to_string(o.num_cameras));
  if (!(o.radius > 0.05) || !(o.radius < 100))
    throw std::invalid_argument("radius: expected 0.05..100 m, got " + std::to_string(o.radius));
  if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192)
    throw std::invalid_argument("image size: expected 16..8192 pixels per side, got " +
                                std::to_string(o.width) + "x" + std::to_string(o.height));
  if (!(o.hfov_deg > 5) || !(o.hfov_deg < 170))
    throw std::invalid_argument("hfov-deg: expected 5..170, got " + std::to_string(o.hfov_deg));
  const double height = o.camera_height;
  std::mt19937_64 rng(o.seed * 7919 + 17);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Vector3d target(0, 0, o.look_at_height);
  std::vector<SimCamera> cameras;
  for (int k = 0; k < o.num_cameras; ++k) {
    SimCamera cam;
    cam.name = "cam" + std::to_string(k);
    const double a = 2 * kPi * k / o.num_cameras;
    const Eigen::Vector3d centre(o.radius * std::cos(a), o.radius * std::sin(a), height);
    cam.rig_from_cam = LookAt(centre, target);
    CameraModel& m = cam.model;
    m.width = o.width;
    m.height = o.height;
    const double f = 0.5 * o.width / std::tan(0.5 * Rad(o.hfov_deg));
    m.fx = m.fy = f;
    m.cx = 0.5 * (o.width - 1);
    m.cy = 0.5 * (o.height - 1);
    m.model = o.distortion;
    m.distortion = DefaultDistortion(o.distortion);
    if (o.intrinsics_spread > 0) {
      const double s = o.intrinsics_spread;
      m.fx *= 1 + s * gauss(rng);
      m.fy = m.fx * (1 + 0.05 * s * gauss(rng));
      m.cx += s * 0.1 * o.width * gauss(rng);
      m.cy += s * 0.1 * o.height * gauss(rng);
      for (double& d : m.distortion) d *= 1 + s * gauss(rng);
    }
    cameras.push_back(cam);
  }
  return cameras;
}

// ---------------------------------------------------------------------------------------------
// Objects

const SimMarker* SimObject::FindMarker(int id) const {
  for (const auto& m : markers)
    if (m.id == id) return &m;
  return nullptr;
}

MarkerSizes SimObject::Sizes() const {
  std::map<double, int> counts;
  for (const auto& m : markers) counts[m.size]++;
  MarkerSizes sizes;
  int best = -1;
  for (const auto& [size, n] : counts)
    if (n > best) best = n, sizes.default_size = size;
  for (const auto& m : markers)
    if (m.size != sizes.default_size) sizes.overrides[m.id] = m.size;
  return sizes;
}

const std::vector<std::string>& ObjectKindNames() {
  static const std::vector<std::string> names = {"four_sided", "box", "pentagon", "cube", "board"};
  return names;
}

ObjectKind ObjectKindFromName(const std::string& name) {
  const auto& names = ObjectKindNames();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<ObjectKind>(i);
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown object '" + name + "' (expected one of: " + list + ")");
}

namespace {

constexpr double kFaceAlbedo = 0.45;

// Four markers around a square prism (7 x 7 x 7 cm for 4 cm markers), one per side.
void FourSidedObject(const ObjectOptions& o, SimObject* obj) {
  const double s = o.marker_size > 0 ? o.marker_size : 0.04;
  const double side = s * 1.75, h = s * 1.75;
  obj->faces = PrismFaces(4, side / std::sqrt(2.0), h, kFaceAlbedo);
  int id = o.first_id;
  for (int k = 0; k < 4; ++k) {
    const double a = 2 * kPi * k / 4;
    const Eigen::Vector3d n(std::cos(a), std::sin(a), 0);
    obj->markers.push_back({id++, s, MarkerOnFace(n * side / 2, n, Eigen::Vector3d::UnitZ())});
  }
}

// A cube with face_columns x face_rows markers on each of its six faces.
void CubeObject(const ObjectOptions& o, SimObject* obj) {
  const double s = o.marker_size > 0 ? o.marker_size : 0.04;
  if (o.face_columns < 1 || o.face_rows < 1)
    throw std::invalid_argument("cube: face_columns and face_rows must be >= 1 (got " +
                                std::to_string(o.face_columns) + " x " + std::to_string(o.face_rows) + ")");
  const int n = std::max(o.face_columns, o.face_rows);
  const double pitch = s * 1.25;  // marker plus a quarter-side gap
  const double side = n * pitch - 0.25 * s + 0.02;
  obj->faces = BoxFaces(side, side, side, kFaceAlbedo);
  const Eigen::Vector3d normals[6] = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                      Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                      Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()};
  int id = o.first_id;
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector3d up = k < 4 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    const Eigen::Matrix3d face = FrameFromNormalUp(normals[k], up);
    for (int row = 0; row < o.face_rows; ++row)
      for (int col = 0; col < o.face_columns; ++col) {
        const double u = (col - 0.5 * (o.face_columns - 1)) * pitch;
        const double v = (row - 0.5 * (o.face_rows - 1)) * pitch;
        const Eigen::Vector3d c = normals[k] * side / 2 + face.col(0) * u + face.col(1) * v;
        obj->markers.push_back({id++, s, MarkerOnFace(c, normals[k], up)});
      }
  }
}

// A pentagonal prism with two markers stacked on each side.
void PentagonObject(const ObjectOptions& o, SimObject* obj) {
  const double s = o.marker_size > 0 ? o.marker_size : 0.025;
  const double quiet = s * 1.25;  // marker plus a one-cell quiet zone each side (6x6 + border: 8 cells)
  // Side length of the pentagon: room for one marker with margin; height: two markers stacked.
  const double side = quiet * 1.25;
  const double r = side / (2 * std::sin(kPi / 5));
  const double apothem = r * std::cos(kPi / 5);
  const double h = quiet * 2.4;
  obj->faces = PrismFaces(5, r, h, kFaceAlbedo);
  int id = o.first_id;
  for (int k = 0; k < 5; ++k) {
    const double a = 2 * kPi * k / 5;
    const Eigen::Vector3d n(std::cos(a), std::sin(a), 0);
    for (int level = 0; level < 2; ++level) {
      const Eigen::Vector3d c = n * apothem + Eigen::Vector3d(0, 0, (level == 0 ? 0.5 : -0.5) * quiet * 1.1);
      obj->markers.push_back({id++, s, MarkerOnFace(c, n, Eigen::Vector3d::UnitZ())});
    }
  }
}

// A standing printed board: 3 x 3 markers on its +x face, grid in y (columns) and z (rows), white paper
// between them as on a real printed board.
void BoardObject(const ObjectOptions& o, SimObject* obj) {
  const double s = o.marker_size > 0 ? o.marker_size : 0.04;
  const double pitch = s * 1.3;
  const double w = 3 * pitch + 0.3 * s, thick = 0.01;
  obj->faces = BoxFaces(thick, w, w, 225.0 / 255.0);
  int id = o.first_id;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) {
      const Eigen::Vector3d c(thick / 2, (col - 1) * pitch, (1 - row) * pitch);
      obj->markers.push_back({id++, s, MarkerOnFace(c, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ())});
    }
}

// A box (4.5 x 3.5 x 2.5 marker sides) with eight markers at random places and rolls: two on the top
// face and one or two on every side, spread by rejection sampling (seeded by o.seed).
class BoxLayout {
 public:
  BoxLayout(const ObjectOptions& o, SimObject* obj)
      : o_(o), obj_(obj), s_(o.marker_size > 0 ? o.marker_size : 0.04), half_quiet_(0.5 * s_ * 1.25) {
    half_[0] = 4.5 * s_ / 2, half_[1] = 3.5 * s_ / 2, half_[2] = 2.5 * s_ / 2;
    obj_->faces = BoxFaces(2 * half_[0], 2 * half_[1], 2 * half_[2], kFaceAlbedo);
  }

  // A marker placed early can leave no room for the second one on its face (a second marker on a side
  // needs the first near an end): then the whole layout is drawn again, the random stream continuing. A
  // layout that succeeds at the first try is what earlier versions produced. Deterministic fallback (only
  // reached for odd marker sizes): upright markers spread evenly along each face's longer axis.
  void Place() {
    std::mt19937_64 rng(o_.seed * 104729 + 3);
    const int max_layouts = 200;
    for (int layout = 0; layout < max_layouts; ++layout)
      if (PlaceAtRandom(&rng)) return;
    PlaceEvenly();
  }

 private:
  static constexpr int kWanted = 8;
  static constexpr int kFacePlan[kWanted] = {4, 0, 1, 2, 3, 4, 0, 2};  // faces +x, -x, +y, -y, +z: 0..4

  Eigen::Vector3d Normal(int f) const {
    const Eigen::Vector3d normals[5] = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                        Eigen::Vector3d::UnitZ()};
    return normals[f];
  }

  // Marker on face f at in-face coordinates c (along the two other coordinate axes), rolled by `roll`;
  // `ext`: half the extent of its rotated quiet square's bounding box.
  void Add(int f, const Eigen::Vector2d& c, double roll, double ext) {
    const Eigen::Vector3d n = Normal(f);
    const int axis = f / 2, a0 = (axis + 1) % 3, a1 = (axis + 2) % 3;
    Eigen::Vector3d centre = n * half_[axis];
    centre[a0] = c[0];
    centre[a1] = c[1];
    const Eigen::Vector3d up = f == 4 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    obj_->markers.push_back(
        {o_.first_id + static_cast<int>(obj_->markers.size()), s_, MarkerOnFace(centre, n, up, roll)});
    placed_.push_back({f, c, ext});
  }

  bool PlaceAtRandom(std::mt19937_64* rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int max_attempts_per_marker = 20000;
    const double gap = 0.002;
    obj_->markers.clear();
    placed_.clear();
    for (int k = 0; k < kWanted; ++k) {
      const int f = kFacePlan[k];
      const int axis = f / 2, a0 = (axis + 1) % 3, a1 = (axis + 2) % 3;
      bool ok = false;
      for (int attempts = 0; attempts < max_attempts_per_marker && !ok; ++attempts) {
        const double roll = 2 * kPi * u(*rng);
        const double ext = half_quiet_ * (std::abs(std::cos(roll)) + std::abs(std::sin(roll)));
        if (ext > half_[a0] || ext > half_[a1]) continue;
        const Eigen::Vector2d c((2 * u(*rng) - 1) * (half_[a0] - ext), (2 * u(*rng) - 1) * (half_[a1] - ext));
        bool clash = false;
        for (const auto& p : placed_)
          if (p.face == f && std::abs(p.centre[0] - c[0]) < p.ext + ext + gap &&
              std::abs(p.centre[1] - c[1]) < p.ext + ext + gap)
            clash = true;
        if (clash) continue;
        Add(f, c, roll, ext);
        ok = true;
      }
      if (!ok) return false;
    }
    return true;
  }

  void PlaceEvenly() {
    obj_->markers.clear();
    placed_.clear();
    for (int k = 0; k < kWanted; ++k) {
      const int f = kFacePlan[k];
      const int axis = f / 2, a0 = (axis + 1) % 3, a1 = (axis + 2) % 3;
      int count = 0, index = 0;
      for (int j = 0; j < kWanted; ++j) {
        if (kFacePlan[j] != f) continue;
        if (j < k) ++index;
        ++count;
      }
      const int along = half_[a0] >= half_[a1] ? 0 : 1;
      Eigen::Vector2d c(0, 0);
      c[along] = (count > 1 ? (2.0 * index / (count - 1) - 1) : 0.0) * half_[along == 0 ? a0 : a1] / 2;
      Add(f, c, 0.0, half_quiet_);
    }
  }

  struct Placed {
    int face;
    Eigen::Vector2d centre;
    double ext;
  };
  const ObjectOptions& o_;
  SimObject* obj_;
  const double s_, half_quiet_;
  double half_[3];
  std::vector<Placed> placed_;
};

}  // namespace

SimObject MakeObject(const ObjectOptions& o) {
  SimObject obj;
  obj.name = ObjectKindNames().at(static_cast<int>(o.kind));
  if (o.first_id < 0) throw std::invalid_argument("first marker id must be >= 0");
  switch (o.kind) {
    case ObjectKind::kFourSided:
      FourSidedObject(o, &obj);
      break;
    case ObjectKind::kCube:
      CubeObject(o, &obj);
      break;
    case ObjectKind::kPentagon:
      PentagonObject(o, &obj);
      break;
    case ObjectKind::kBoard:
      BoardObject(o, &obj);
      break;
    case ObjectKind::kBox:
      BoxLayout(o, &obj).Place();
      break;
  }
  obj.radius = CircumRadius(obj.faces);
  return obj;
}

// ---------------------------------------------------------------------------------------------
// Trajectory

int64_t FrameUtime(int64_t frame, double fps) {
  return kStartUtime + static_cast<int64_t>(std::llround(static_cast<double>(frame) * 1e6 / fps));
}

namespace {

// The random motion of MakeTrajectory: the wiggles and the yaw drawn from the seed.
struct Motion {
  explicit Motion(const TrajectoryOptions& o) : o(o) {
    std::mt19937_64 rng(o.seed * 6364136223846793005ULL + 1442695040888963407ULL);
    rho = o.position_radius > 0 ? o.position_radius : 0.15;
    vert = o.vertical_range > 0 ? o.vertical_range : 0.08;
    wx.Init(rng, 0.04, 0.25);
    wy.Init(rng, 0.04, 0.25);
    wz.Init(rng, 0.05, 0.3);
    tx.Init(rng, 0.05, 0.35);
    ty.Init(rng, 0.05, 0.35);
    yaw_wiggle.Init(rng, 0.05, 0.3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    yaw0 = 2 * kPi * u(rng);
    direction = u(rng) < 0.5 ? -1.0 : 1.0;
  }
  // The centre at motion time t (seconds).
  Eigen::Vector3d Position(double t) const {
    return Eigen::Vector3d(rho * wx(t), rho * wy(t), o.look_at_height + vert * wz(t));
  }
  // The pose at motion time t and progress s (0..1 over the moving frames).
  Rigid3 Pose(double t, double s) const {
    const double yaw = yaw0 + direction * (2 * kPi * o.turns * s) + 0.4 * yaw_wiggle(t);
    Eigen::Vector2d tilt(tx(t), ty(t));
    tilt *= Rad(o.max_tilt_deg) / std::sqrt(2.0);
    Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    if (tilt.norm() > 0) {
      const Eigen::Vector3d axis(tilt[0], tilt[1], 0);
      r = Eigen::AngleAxisd(tilt.norm(), axis.normalized()).toRotationMatrix() * r;
    }
    return MakePose(r, Position(t));
  }
  const TrajectoryOptions& o;
  double rho = 0, vert = 0, yaw0 = 0, direction = 1;
  Wiggle wx, wy, wz, tx, ty, yaw_wiggle;
};

void CheckTrajectoryOptions(const TrajectoryOptions& o) {
  if (o.frames < 1) throw std::invalid_argument("frames: expected >= 1, got " + std::to_string(o.frames));
  if (!(o.fps > 0) || !(o.fps <= 10000)) throw std::invalid_argument("fps: expected 0..10000");
  if (o.still_frames < 0) throw std::invalid_argument("still-frames: expected >= 0");
  if (!(o.time_scale > 0 && o.time_scale <= 1000))
    throw std::invalid_argument("time_scale: expected 0..1000, got " + std::to_string(o.time_scale));
}

// Frames of the motion (still segments excluded): the motion time does not advance inside them.
int MovingFrames(const TrajectoryOptions& o, std::vector<bool>* still_out) {
  std::vector<bool> still(o.frames, false);
  const int segments = o.still_frames > 0 ? std::max(0, o.still_segments) : 0;
  for (int j = 0; j < segments; ++j) {
    const int centre = static_cast<int>((j + 1) * static_cast<int64_t>(o.frames) / (segments + 1));
    for (int k = centre - o.still_frames / 2; k < centre - o.still_frames / 2 + o.still_frames; ++k)
      if (k >= 0 && k < o.frames) still[k] = true;
  }
  int moving = 0;
  for (bool s : still) moving += s ? 0 : 1;
  if (still_out) *still_out = still;
  return moving;
}

}  // namespace

double TrajectoryMaxSpeed(const TrajectoryOptions& o) {
  CheckTrajectoryOptions(o);
  const Motion motion(o);
  const int moving = MovingFrames(o, nullptr);
  constexpr int kSamples = 20;  // per frame interval
  const double dt_frame = 1.0 / o.fps;
  const double dt = dt_frame / kSamples;
  double top = 0.0;
  Eigen::Vector3d last = motion.Position(0.0);
  for (int i = 1; i <= (moving - 1) * kSamples; ++i) {
    const Eigen::Vector3d p = motion.Position(o.time_scale * i * dt);
    top = std::max(top, (p - last).norm() / dt);
    last = p;
  }
  return top;
}

double TimeScaleForMaxSpeed(TrajectoryOptions o, double max_speed_m_s) {
  if (!(max_speed_m_s > 0 && max_speed_m_s <= 100))
    throw std::invalid_argument("--max-speed-m-s: expected 0..100 m/s, got " + std::to_string(max_speed_m_s));
  // The top speed grows with the scale (faster, and over a longer stretch of the motion): bisection.
  double lo = 1e-3, hi = 1000.0;
  o.time_scale = hi;
  if (TrajectoryMaxSpeed(o) < max_speed_m_s)
    throw std::invalid_argument("--max-speed-m-s: " + std::to_string(max_speed_m_s) +
                                " m/s is beyond the motion's reach (a larger --radius moves faster)");
  for (int i = 0; i < 60; ++i) {
    o.time_scale = std::sqrt(lo * hi);
    (TrajectoryMaxSpeed(o) < max_speed_m_s ? lo : hi) = o.time_scale;
  }
  return std::sqrt(lo * hi);
}

std::vector<SimFrame> MakeTrajectory(const TrajectoryOptions& options) {
  CheckTrajectoryOptions(options);
  TrajectoryOptions o = options;
  if (o.max_speed_m_s > 0) o.time_scale = TimeScaleForMaxSpeed(o, o.max_speed_m_s);
  const Motion motion(o);
  std::vector<bool> still;
  const int moving = MovingFrames(o, &still);
  std::vector<SimFrame> frames(o.frames);
  int tau = 0;
  for (int k = 0; k < o.frames; ++k) {
    if (k > 0 && !still[k]) ++tau;
    const double t = o.time_scale * tau / o.fps;
    const double s = std::max(1, moving - 1) > 0 ? static_cast<double>(tau) / std::max(1, moving - 1) : 0.0;
    frames[k].seq = k;
    frames[k].utime = FrameUtime(k, o.fps);
    frames[k].rig_from_object = motion.Pose(t, s);
  }
  return frames;
}

// ---------------------------------------------------------------------------------------------
// Projections

std::vector<MarkerView> ProjectMarkers(const SimCamera& camera, const SimObject& object,
                                       const Rigid3& rig_from_object) {
  const Rigid3 cam_from_object = Inverse(camera.rig_from_cam) * rig_from_object;
  const Rigid3 object_from_cam = Inverse(cam_from_object);
  const Eigen::Vector3d cam_in_object = object_from_cam.translation();
  const internal::ValidRegion region(camera.model);
  std::vector<MarkerView> views;
  views.reserve(object.markers.size());
  for (const SimMarker& m : object.markers) {
    MarkerView v;
    v.id = m.id;
    v.cam_from_marker = cam_from_object * m.object_from_marker;
    const Eigen::Matrix3d& r = v.cam_from_marker.linear();
    const Eigen::Vector3d& t = v.cam_from_marker.translation();
    v.depth = t.z();
    const Eigen::Vector3d normal = r.col(2);
    v.view_angle_deg = Deg(std::acos(std::clamp(-normal.dot(t) / std::max(t.norm(), 1e-300), -1.0, 1.0)));
    v.front_facing = normal.dot(t) < 0;
    const MarkerCorners3d corners = MarkerCornersInMarker(m.size);
    v.in_front = true;
    v.in_image = true;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d p = v.cam_from_marker * corners[i];
      if (!(p.z() > 1e-9)) {
        v.in_front = false;
        v.in_image = false;
        v.corners[i] = Eigen::Vector2d(NAN, NAN);
        continue;
      }
      double px[2] = {0, 0};
      camera.model.Project(p.data(), px);
      v.corners[i] = Eigen::Vector2d(px[0], px[1]);
      if (!region.Contains(p.x() / p.z(), p.y() / p.z()) || !(px[0] >= 0) || !(px[1] >= 0) ||
          !(px[0] <= camera.model.width - 1) || !(px[1] <= camera.model.height - 1))
        v.in_image = false;
    }
    if (v.in_front) {
      double area = 0;
      for (int i = 0; i < 4; ++i) {
        const Eigen::Vector2d& a = v.corners[i];
        const Eigen::Vector2d& b = v.corners[(i + 1) % 4];
        area += a.x() * b.y() - a.y() * b.x();
      }
      v.size_px = std::sqrt(std::abs(0.5 * area));
    }
    // Occlusion by the body: rays from the camera to sample points of the marker (corners slightly
    // inset, edge midpoints, centre) must not cross any body face before reaching the marker.
    if (v.front_facing && v.in_front) {
      const double h = 0.5 * m.size * (1 - 1e-6);
      const Eigen::Vector3d samples[9] = {{-h, h, 0}, {h, h, 0},  {h, -h, 0}, {-h, -h, 0}, {0, h, 0},
                                          {h, 0, 0},  {0, -h, 0}, {-h, 0, 0}, {0, 0, 0}};
      for (const auto& s : samples) {
        const Eigen::Vector3d target = m.object_from_marker * s;
        if (internal::SegmentHitsBody(object, cam_in_object, target)) {
          v.occluded = true;
          break;
        }
      }
    }
    v.fully_visible = v.in_front && v.in_image && v.front_facing && !v.occluded;
    views.push_back(v);
  }
  return views;
}

// ---------------------------------------------------------------------------------------------
// Internal helpers

namespace internal {

ValidRegion::ValidRegion(const CameraModel& model) {
  // The distortion must be monotonic in the radius up to where a point may still land in the image;
  // beyond the first turning point a far-off point could fold back into the image.
  max_r2 = 1e30;
  if (model.model == DistortionModel::kNone) return;
  thread_local std::map<std::pair<int, std::vector<double>>, double> cache;
  const auto key = std::make_pair(static_cast<int>(model.model), model.distortion);
  auto it = cache.find(key);
  if (it != cache.end()) {
    max_r2 = it->second;
    return;
  }
  double prev = 0;
  const double step = 2e-3;
  for (double r = step; r < 20; r += step) {
    double xd, yd;
    model.Distort(r, 0.0, &xd, &yd);
    if (!(xd > prev)) {
      max_r2 = (r - step) * (r - step);
      break;
    }
    prev = xd;
  }
  if (cache.size() > 64) cache.clear();
  cache[key] = max_r2;
}

bool SegmentHitsBody(const SimObject& object, const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const Eigen::Vector3d d = to - from;
  for (const SimFace& f : object.faces) {
    const size_t n = f.vertices.size();
    if (n < 3) continue;
    const Eigen::Vector3d normal =
        (f.vertices[1] - f.vertices[0]).cross(f.vertices[2] - f.vertices[0]).normalized();
    const double denom = normal.dot(d);
    if (std::abs(denom) < 1e-15) continue;
    const double t = normal.dot(f.vertices[0] - from) / denom;
    if (!(t > 1e-9) || !(t < 1 - 1e-7)) continue;
    const Eigen::Vector3d p = from + t * d;
    bool inside = true;
    for (size_t i = 0; i < n && inside; ++i) {
      const Eigen::Vector3d& a = f.vertices[i];
      const Eigen::Vector3d& b = f.vertices[(i + 1) % n];
      if ((b - a).cross(p - a).dot(normal) < 0) inside = false;
    }
    if (inside) return true;
  }
  return false;
}

}  // namespace internal

}  // namespace sim
}  // namespace mcmt
