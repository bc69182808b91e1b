// mcmt_sim renderer: exactness of the rendered geometry, checked against the camera model directly
// (no detector): dark areas equal projected polygon areas, edges sit where the projected outline is
// (pixel centres at integer coordinates), hidden faces and occlusion, supersampling, distortion,
// determinism. Also: the box object's random marker layout is valid for every seed.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "core/camera.h"
#include "core/marker.h"
#include "sim/sim.h"

namespace sim = mcmt::sim;
using mcmt::CameraModel;
using mcmt::DistortionModel;
using mcmt::Rigid3;
using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kBackground = 200.0;
constexpr double kBlack = 25.0;

sim::SimCamera PinholeCamera(int w, int h, double f, double cx, double cy) {
  sim::SimCamera cam;
  cam.name = "cam0";
  cam.model = CameraModel::Pinhole(w, h, f, cx, cy);
  return cam;  // rig_from_cam = identity: the rig frame is the camera frame
}

// A camera from MakeRig (its intrinsics and distortion), placed at the rig origin.
sim::SimCamera RigCamera(DistortionModel distortion, int width = 640, int height = 480) {
  sim::RigOptions o;
  o.num_cameras = 1;
  o.width = width;
  o.height = height;
  o.distortion = distortion;
  sim::SimCamera cam = sim::MakeRig(o).at(0);
  cam.rig_from_cam = Rigid3::Identity();
  return cam;
}

// One marker of side `size` at the object origin, no body.
sim::SimObject SingleMarker(double size) {
  sim::SimObject obj;
  obj.name = "single";
  obj.markers.push_back({0, size, Rigid3::Identity()});
  obj.radius = size;
  return obj;
}

// Renders plain black squares (no quiet zone) on a uniform background, without noise, texture,
// lighting gradient or shading: coverage = (background - I) / (background - black).
sim::RenderOptions ExactOptions() {
  sim::RenderOptions o;
  o.solid_markers = true;
  o.noise_sigma = 0.0;
  o.textured_background = false;
  o.background_level = kBackground;
  o.lighting_gradient = 0.0;
  o.shading = 0.0;
  o.black_level = kBlack;
  o.quiet_zone_cells = 0;
  return o;
}

cv::Mat Coverage(const cv::Mat& ideal) {
  cv::Mat c;
  ideal.convertTo(c, CV_64F, -1.0 / (kBackground - kBlack), kBackground / (kBackground - kBlack));
  return c;
}

// Pose of the object (= marker frame) in the camera frame: facing the camera (marker z towards the
// camera) at `centre`, then turned by `yaw` (about the marker's y), `pitch` (x) and `roll` (z), degrees.
Rigid3 FacingPose(const Vec3& centre, double yaw_deg, double pitch_deg, double roll_deg) {
  Eigen::Matrix3d facing = Eigen::Vector3d(1, -1, -1).asDiagonal();
  Rigid3 pose = Rigid3::Identity();
  pose.linear() = facing * Eigen::AngleAxisd(yaw_deg * kPi / 180, Vec3::UnitY()).toRotationMatrix() *
                  Eigen::AngleAxisd(pitch_deg * kPi / 180, Vec3::UnitX()).toRotationMatrix() *
                  Eigen::AngleAxisd(roll_deg * kPi / 180, Vec3::UnitZ()).toRotationMatrix();
  pose.translation() = centre;
  return pose;
}

double ShoelaceArea(const std::vector<Vec2>& p) {
  double a = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec2& u = p[i];
    const Vec2& v = p[(i + 1) % p.size()];
    a += u.x() * v.y() - u.y() * v.x();
  }
  return 0.5 * std::abs(a);
}

// The marker's outline projected densely (it curves under distortion): `per_edge` points per edge,
// edge e running from corner e to corner e + 1 (ArUco order).
struct Outline {
  std::vector<Vec2> points;
  std::vector<int> edge;  // edge of the segment points[i] -> points[i + 1]
  mcmt::MarkerCorners2d corners;
};

Outline ProjectOutline(const sim::SimCamera& cam, const Rigid3& cam_from_marker, double size,
                       int per_edge = 400) {
  const mcmt::MarkerCorners3d c = mcmt::MarkerCornersInMarker(size);
  Outline out;
  for (int e = 0; e < 4; ++e) {
    out.corners[e] = cam.model.Project(cam_from_marker * c[e]);
    for (int k = 0; k < per_edge; ++k) {
      const Vec3 p = c[e] + (c[(e + 1) % 4] - c[e]) * (static_cast<double>(k) / per_edge);
      out.points.push_back(cam.model.Project(cam_from_marker * p));
      out.edge.push_back(e);
    }
  }
  return out;
}

struct EdgeSample {
  int edge;         // which marker edge
  Vec2 measured;    // boundary point measured from the image
  double expected;  // the projected outline's coordinate at the same row / column
};

// Boundary points measured along rows (transpose = false) or columns (transpose = true). In a row
// strip [v - 0.5, v + 0.5] that holds no outline corner, the dark run is bounded by one edge on each
// side; summing the coverage from a pixel left of the left edge to a pixel m between the edges gives
// (m + 0.5) - x_left, where x_left is the edge's mean position over the strip, i.e. its position at
// row v (exact for a straight edge; a curved edge differs by under 1e-4 px at these curvatures).
std::vector<EdgeSample> MeasureEdges(const cv::Mat& coverage_in, const Outline& outline_in, bool transpose) {
  cv::Mat coverage = transpose ? cv::Mat(coverage_in.t()) : coverage_in;
  auto swap = [&](const Vec2& p) { return transpose ? Vec2(p.y(), p.x()) : p; };
  std::vector<EdgeSample> samples;
  for (int v = 1; v < coverage.rows - 1; ++v) {
    bool near_corner = false;
    for (const Vec2& c : outline_in.corners)
      if (std::abs(swap(c).y() - v) < 1.5) near_corner = true;
    if (near_corner) continue;
    // Crossings of the row's centre line and of its strip's bounds with the outline: two at each.
    double lo[3], hi[3];
    int lo_edge = -1, hi_edge = -1;
    bool two_each = true;
    const size_t n = outline_in.points.size();
    for (int level = 0; level < 3; ++level) {
      const double y = v + 0.5 * (level - 1);
      std::vector<std::pair<double, int>> xs;
      for (size_t i = 0; i < n; ++i) {
        const Vec2 a = swap(outline_in.points[i]), b = swap(outline_in.points[(i + 1) % n]);
        if ((a.y() - y) * (b.y() - y) > 0 || a.y() == b.y()) continue;
        xs.emplace_back(a.x() + (b.x() - a.x()) * (y - a.y()) / (b.y() - a.y()), outline_in.edge[i]);
      }
      if (xs.size() != 2) {
        two_each = false;
        break;
      }
      std::sort(xs.begin(), xs.end());
      lo[level] = xs[0].first, hi[level] = xs[1].first;
      if (level == 1) lo_edge = xs[0].second, hi_edge = xs[1].second;
    }
    if (!two_each) continue;
    const double xl = lo[1], xr = hi[1];
    const double left_min = std::min({lo[0], lo[1], lo[2]}), left_max = std::max({lo[0], lo[1], lo[2]});
    const double right_min = std::min({hi[0], hi[1], hi[2]}), right_max = std::max({hi[0], hi[1], hi[2]});
    const int m = static_cast<int>(std::floor(0.5 * (xl + xr)));
    // Over the strip the left edge must stay inside [a - 0.5, m + 0.5], the right one inside
    // [m + 0.5, b + 0.5].
    if (!(left_max < m + 0.5) || !(right_min > m + 0.5)) continue;
    const int a = static_cast<int>(std::floor(left_min)) - 2;
    const int b = static_cast<int>(std::ceil(right_max)) + 2;
    if (a < 0 || b >= coverage.cols) continue;
    double left = 0, right = 0;
    for (int u = a; u <= m; ++u) left += coverage.at<double>(v, u);
    for (int u = m + 1; u <= b; ++u) right += coverage.at<double>(v, u);
    const double x_left = m + 0.5 - left, x_right = m + 0.5 + right;
    const int el = lo_edge, er = hi_edge;
    samples.push_back({el, swap(Vec2(x_left, v)), xl});
    samples.push_back({er, swap(Vec2(x_right, v)), xr});
  }
  return samples;
}

double MaxEdgeError(const std::vector<EdgeSample>& samples, bool transpose) {
  double worst = 0;
  for (const EdgeSample& s : samples)
    worst = std::max(worst, std::abs((transpose ? s.measured.y() : s.measured.x()) - s.expected));
  return worst;
}

double DarkArea(const cv::Mat& coverage) { return cv::sum(coverage)[0]; }

// Copy of the simulator's box faces (counter-clockwise seen from outside).
std::vector<sim::SimFace> BoxFaces(double side, double albedo) {
  const double h = side / 2;
  auto v = [&](double x, double y, double z) { return Vec3(x * h, y * h, z * h); };
  return {
      {{v(1, -1, -1), v(1, 1, -1), v(1, 1, 1), v(1, -1, 1)}, albedo},
      {{v(-1, 1, -1), v(-1, -1, -1), v(-1, -1, 1), v(-1, 1, 1)}, albedo},
      {{v(1, 1, -1), v(-1, 1, -1), v(-1, 1, 1), v(1, 1, 1)}, albedo},
      {{v(-1, -1, -1), v(1, -1, -1), v(1, -1, 1), v(-1, -1, 1)}, albedo},
      {{v(-1, -1, 1), v(1, -1, 1), v(1, 1, 1), v(-1, 1, 1)}, albedo},
      {{v(-1, 1, -1), v(1, 1, -1), v(1, -1, -1), v(-1, -1, -1)}, albedo},
  };
}

}  // namespace

// ---------------------------------------------------------------------------------------------

TEST(ConvexPolygonRectArea, HandComputedCases) {
  const std::vector<Vec2> unit = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  EXPECT_NEAR(sim::ConvexPolygonRectArea(unit, 0.5, 0.5, 2, 2), 0.25, 1e-15);
  EXPECT_NEAR(sim::ConvexPolygonRectArea(unit, -1, -1, 2, 2), 1.0, 1e-15);          // inside the rectangle
  EXPECT_NEAR(sim::ConvexPolygonRectArea(unit, 0.25, 0.5, 0.75, 0.7), 0.1, 1e-15);  // rectangle inside
  EXPECT_EQ(sim::ConvexPolygonRectArea(unit, 1.5, 0, 2, 1), 0.0);                   // disjoint
  EXPECT_NEAR(sim::ConvexPolygonRectArea(unit, 1.0, 0, 2, 1), 0.0, 1e-15);          // touching
  // Clockwise order gives the same (unsigned) area.
  const std::vector<Vec2> unit_cw(unit.rbegin(), unit.rend());
  EXPECT_NEAR(sim::ConvexPolygonRectArea(unit_cw, 0.5, 0.5, 2, 2), 0.25, 1e-15);
  // Right triangle (0,0) (2,0) (0,2): the square [0,1]^2 lies inside (the hypotenuse passes (1,1));
  // [1,2]x[0,1] holds the triangle x + y <= 2 there: area 1/2. [0.5,1.5]^2: 1 - 1/2 * 1 * 1 = 1/2.
  const std::vector<Vec2> tri = {{0, 0}, {2, 0}, {0, 2}};
  EXPECT_NEAR(sim::ConvexPolygonRectArea(tri, 0, 0, 1, 1), 1.0, 1e-15);
  EXPECT_NEAR(sim::ConvexPolygonRectArea(tri, 1, 0, 2, 1), 0.5, 1e-15);
  EXPECT_NEAR(sim::ConvexPolygonRectArea(tri, 0.5, 0.5, 1.5, 1.5), 0.5, 1e-15);
  EXPECT_NEAR(sim::ConvexPolygonRectArea(tri, -5, -5, 5, 5), 2.0, 1e-15);
  // Diamond |x - 1| + |y - 1| <= 1: area 2; a quarter of it in [0,1]^2; a corner strip x in [1.5, 2]
  // holds a triangle of base 1 and height 0.5.
  const std::vector<Vec2> diamond = {{1, 0}, {2, 1}, {1, 2}, {0, 1}};
  EXPECT_NEAR(sim::ConvexPolygonRectArea(diamond, 0, 0, 2, 2), 2.0, 1e-15);
  EXPECT_NEAR(sim::ConvexPolygonRectArea(diamond, 0, 0, 1, 1), 0.5, 1e-15);
  EXPECT_NEAR(sim::ConvexPolygonRectArea(diamond, 1.5, -1, 3, 3), 0.25, 1e-15);
  // Regular hexagon of circumradius 1 centred at the origin: area 3 sqrt(3) / 2; the half x >= 0 is half.
  std::vector<Vec2> hex;
  for (int k = 0; k < 6; ++k) hex.emplace_back(std::cos(k * kPi / 3), std::sin(k * kPi / 3));
  EXPECT_NEAR(sim::ConvexPolygonRectArea(hex, -2, -2, 2, 2), 1.5 * std::sqrt(3.0), 1e-14);
  EXPECT_NEAR(sim::ConvexPolygonRectArea(hex, 0, -2, 2, 2), 0.75 * std::sqrt(3.0), 1e-14);
  // Degenerate inputs.
  EXPECT_EQ(sim::ConvexPolygonRectArea({{0, 0}, {1, 1}}, -1, -1, 2, 2), 0.0);
  EXPECT_EQ(sim::ConvexPolygonRectArea(unit, 0.5, 0.5, 0.5, 2), 0.0);
  EXPECT_EQ(sim::ConvexPolygonRectArea(unit, 0.5, 0.5, 0.2, 2), 0.0);
}

// The cells of a marker's row a footprint overlaps, including the footprints at the horizon whose extent
// does not fit an int (-3.8e10 cells in test_sim_detect at 1280x960: undefined behaviour before).
TEST(CellsOverlapping, ClampsToTheGridAndSkipsWhatAnIntCannotHold) {
  auto span = [](double from, double to) {
    const sim::CellSpan s = sim::CellsOverlapping(from, to, 8);
    return std::make_pair(s.first, s.last);
  };
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  EXPECT_EQ(span(2.5, 3.0), std::make_pair(2, 3));
  EXPECT_EQ(span(2.5, 2.7), std::make_pair(2, 2));
  EXPECT_EQ(span(-1.5, 0.5), std::make_pair(0, 0));
  EXPECT_EQ(span(6.5, 9.5), std::make_pair(6, 7));
  EXPECT_EQ(span(-3.0, 12.0), std::make_pair(0, 7));
  // Missing the grid: first > last.
  const auto before_grid = span(-3.0, -0.5), after_grid = span(8.0, 9.0);
  EXPECT_GT(before_grid.first, before_grid.second);
  EXPECT_GT(after_grid.first, after_grid.second);
  // Huge extents: the low end clamps to cell 0, an end at 2^31 cells or more gives no cell (as x86's
  // conversion did), just below it the last cell.
  EXPECT_EQ(span(-3.77449e10, 3.0), std::make_pair(0, 3));
  EXPECT_EQ(span(-inf, 3.0), std::make_pair(0, 3));
  EXPECT_EQ(span(nan, 3.0), std::make_pair(0, 3));
  EXPECT_EQ(span(2.0, 2147483647.0), std::make_pair(2, 7));
  for (double to : {2147483648.0, 3.77449e10, inf, nan}) {
    const auto none = span(2.0, to);
    EXPECT_GT(none.first, none.second) << to;
  }
  const auto reversed = span(3e10, 5.0);  // from > to: no cell
  EXPECT_GT(reversed.first, reversed.second);
}

// A fronto-parallel square at several sub-pixel positions: the dark area is the projected square's
// area and each edge sits at the projected corners' coordinate (pixel centres at integers: a
// half-pixel slip would show as a 0.5 px edge error).
TEST(RenderExact, FrontoParallelSquareAreaAndEdges) {
  const sim::SimCamera cam = PinholeCamera(160, 120, 500.0, 79.5, 59.5);
  const double size = 0.05, depth = 1.0;  // 25 px
  const sim::SimObject obj = SingleMarker(size);
  const sim::Renderer renderer(obj, "DICT_6X6_250", ExactOptions());
  double worst_area = 0, worst_edge = 0;
  const double offsets[][2] = {{0, 0}, {0.1, 0.37}, {0.25, -0.5}, {-0.43, 0.21}, {0.5, 0.5}, {0.013, -0.77}};
  for (const auto& off : offsets) {
    const Vec3 centre(off[0] / cam.model.fx * depth, off[1] / cam.model.fy * depth, depth);
    const Rigid3 pose = FacingPose(centre, 0, 0, 0);
    const cv::Mat coverage = Coverage(renderer.RenderIdeal(cam, 0, pose));
    const auto views = sim::ProjectMarkers(cam, obj, pose);
    ASSERT_EQ(views.size(), 1u);
    ASSERT_TRUE(views[0].fully_visible);
    const auto& c = views[0].corners;
    const double side = cam.model.fx * size / depth;
    EXPECT_NEAR(c[1].x() - c[0].x(), side, 1e-9);
    const double area = DarkArea(coverage);
    worst_area = std::max(worst_area, std::abs(area - side * side));
    // 0.01 px of edge shift over the perimeter.
    EXPECT_NEAR(area, side * side, 0.01 * 4 * side) << "offset " << off[0] << " " << off[1];
    // Edges: left/right from rows, top/bottom from columns, against the corners' coordinates.
    const Outline outline = ProjectOutline(cam, pose * obj.markers[0].object_from_marker, size, 4);
    const auto rows = MeasureEdges(coverage, outline, false);
    const auto cols = MeasureEdges(coverage, outline, true);
    ASSERT_GE(rows.size(), 2u * 18);
    ASSERT_GE(cols.size(), 2u * 18);
    for (const auto& s : rows) {
      const double expected = s.edge == 3 ? c[0].x() : c[1].x();  // edge 3: left, edge 1: right
      EXPECT_NEAR(s.measured.x(), expected, 0.01) << "edge " << s.edge << " row " << s.measured.y();
    }
    for (const auto& s : cols) {
      const double expected = s.edge == 0 ? c[0].y() : c[2].y();  // edge 0: top, edge 2: bottom
      EXPECT_NEAR(s.measured.y(), expected, 0.01) << "edge " << s.edge << " column " << s.measured.x();
    }
    worst_edge = std::max({worst_edge, MaxEdgeError(rows, false), MaxEdgeError(cols, true)});
  }
  std::cout << "fronto-parallel: max |dark area - projected area| " << worst_area << " px^2, max edge error "
            << worst_edge << " px\n";
  RecordProperty("fronto_max_area_error_px2", std::to_string(worst_area));
  RecordProperty("fronto_max_edge_error_px", std::to_string(worst_edge));
}

// Tilted and rolled squares (general quadrilaterals under perspective): area and edge positions
// along rows and columns against the projected outline.
TEST(RenderExact, PerspectiveQuadrilateralAreaAndEdges) {
  const sim::SimCamera cam = PinholeCamera(200, 160, 420.0, 101.3, 77.8);
  const double size = 0.06;
  const sim::SimObject obj = SingleMarker(size);
  const sim::Renderer renderer(obj, "DICT_6X6_250", ExactOptions());
  struct Case {
    Vec3 centre;
    double yaw, pitch, roll;
  };
  const Case cases[] = {{{0.0, 0.0, 0.5}, 40, 0, 0},
                        {{0.013, -0.02, 0.45}, 35, -25, 0},
                        {{-0.03, 0.01, 0.55}, -50, 20, 17},
                        {{0.02, 0.03, 0.4}, 10, 55, -35},
                        {{-0.004, 0.006, 0.6}, 0, 0, 30}};
  double worst_area_shift = 0, worst_edge = 0;
  size_t total_samples = 0;
  for (const Case& k : cases) {
    const Rigid3 pose = FacingPose(k.centre, k.yaw, k.pitch, k.roll);
    const auto views = sim::ProjectMarkers(cam, obj, pose);
    ASSERT_TRUE(views[0].fully_visible);
    const cv::Mat coverage = Coverage(renderer.RenderIdeal(cam, 0, pose));
    const std::vector<Vec2> quad(views[0].corners.begin(), views[0].corners.end());
    double perimeter = 0;
    for (int i = 0; i < 4; ++i) perimeter += (quad[(i + 1) % 4] - quad[i]).norm();
    const double area = DarkArea(coverage), expected = ShoelaceArea(quad);
    EXPECT_NEAR(area, expected, 0.01 * perimeter) << "yaw " << k.yaw << " pitch " << k.pitch;
    worst_area_shift = std::max(worst_area_shift, std::abs(area - expected) / perimeter);
    const Outline outline = ProjectOutline(cam, pose, size);
    for (bool transpose : {false, true}) {
      const auto samples = MeasureEdges(coverage, outline, transpose);
      EXPECT_GE(samples.size(), 20u);
      total_samples += samples.size();
      for (const auto& s : samples)
        EXPECT_NEAR(transpose ? s.measured.y() : s.measured.x(), s.expected, 0.01)
            << "edge " << s.edge << " at " << s.measured.transpose() << (transpose ? " (column)" : " (row)");
      worst_edge = std::max(worst_edge, MaxEdgeError(samples, transpose));
    }
  }
  std::cout << "perspective: max area error / perimeter " << worst_area_shift << " px, max edge error "
            << worst_edge << " px over " << total_samples << " edge samples\n";
  RecordProperty("perspective_max_edge_error_px", std::to_string(worst_edge));
}

// Distorted cameras: the rendered outline follows CameraModel::Project (edges along rows/columns
// against the densely projected outline), and the corners found by fitting the measured edges
// land on the projected corners.
TEST(RenderExact, DistortedEdgesAndCornersFollowTheCameraModel) {
  for (DistortionModel model : {DistortionModel::kRadTan, DistortionModel::kFisheye}) {
    const sim::SimCamera cam = RigCamera(model);
    const double size = 0.05;
    const sim::SimObject obj = SingleMarker(size);
    const sim::Renderer renderer(obj, "DICT_6X6_250", ExactOptions());
    double worst_edge = 0, worst_corner = 0, largest_bend = 0;
    // Off-centre, where the distortion moves points by several pixels.
    const Vec2 targets[] = {{470.3, 350.6}, {560.0, 80.2}, {95.7, 400.1}};
    for (const Vec2& target : targets) {
      const Vec2 ray = cam.model.Unproject(target);
      const double depth = 0.5;
      const Rigid3 pose = FacingPose(Vec3(ray.x() * depth, ray.y() * depth, depth), 15, -10, 20);
      const auto views = sim::ProjectMarkers(cam, obj, pose);
      ASSERT_TRUE(views[0].fully_visible) << mcmt::DistortionModelName(model);
      const cv::Mat coverage = Coverage(renderer.RenderIdeal(cam, 0, pose));
      const Outline outline = ProjectOutline(cam, pose, size);
      // How far the outline bends away from the chord between its corners (so the test sees distortion).
      for (size_t i = 0; i < outline.points.size(); ++i) {
        const int e = outline.edge[i];
        const Vec2 a = outline.corners[e], b = outline.corners[(e + 1) % 4];
        const Vec2 d = (b - a).normalized();
        const Vec2 r = outline.points[i] - a;
        largest_bend = std::max(largest_bend, std::abs(d.x() * r.y() - d.y() * r.x()));
      }
      std::vector<EdgeSample> all;
      for (bool transpose : {false, true}) {
        const auto samples = MeasureEdges(coverage, outline, transpose);
        EXPECT_GE(samples.size(), 20u);
        for (const auto& s : samples)
          EXPECT_NEAR(transpose ? s.measured.y() : s.measured.x(), s.expected, 0.02)
              << mcmt::DistortionModelName(model) << " edge " << s.edge << " at " << s.measured.transpose();
        worst_edge = std::max(worst_edge, MaxEdgeError(samples, transpose));
        all.insert(all.end(), samples.begin(), samples.end());
      }
      // Corners: fit each edge near the corner with a quadratic (in the edge's own direction) through
      // the measured points 2..14 px away and intersect the two fits.
      for (int k = 0; k < 4; ++k) {
        const Vec2 corner = outline.corners[k];
        struct Fit {
          Vec2 origin, dir, normal;
          Eigen::Vector3d coef;  // offset along normal = c0 + c1 t + c2 t^2, t along dir
        };
        Fit fits[2];
        bool ok = true;
        const int edges[2] = {(k + 3) % 4, k};  // edge ending at corner k, edge starting at corner k
        for (int j = 0; j < 2; ++j) {
          const int e = edges[j];
          const Vec2 other = outline.corners[j == 0 ? (k + 3) % 4 : (k + 1) % 4];
          Fit& fit = fits[j];
          fit.origin = corner;
          fit.dir = (other - corner).normalized();
          fit.normal = Vec2(-fit.dir.y(), fit.dir.x());
          std::vector<Eigen::Vector3d> rows;
          std::vector<double> rhs;
          for (const auto& s : all) {
            if (s.edge != e) continue;
            const Vec2 r = s.measured - corner;
            const double t = r.dot(fit.dir);
            if (t < 2.0 || t > 14.0) continue;
            rows.emplace_back(1.0, t, t * t);
            rhs.push_back(r.dot(fit.normal));
          }
          if (rows.size() < 6) {
            ok = false;
            break;
          }
          Eigen::MatrixXd a(rows.size(), 3);
          Eigen::VectorXd b(rows.size());
          for (size_t i = 0; i < rows.size(); ++i) a.row(i) = rows[i].transpose(), b(i) = rhs[i];
          fit.coef = a.colPivHouseholderQr().solve(b);
        }
        ASSERT_TRUE(ok) << "too few edge samples near corner " << k;
        // Intersect: point p with normal offsets matching both fits (fixed point from the corner).
        Vec2 p = corner;
        for (int it = 0; it < 50; ++it) {
          Eigen::Matrix2d m;
          Eigen::Vector2d r;
          for (int j = 0; j < 2; ++j) {
            const Fit& f = fits[j];
            const double t = (p - f.origin).dot(f.dir);
            const double slope = f.coef(1) + 2 * f.coef(2) * t;
            // g(p) = n . (p - o) - poly(d . (p - o)) = 0
            m.row(j) = (f.normal - slope * f.dir).transpose();
            r(j) = f.normal.dot(p - f.origin) - (f.coef(0) + f.coef(1) * t + f.coef(2) * t * t);
          }
          p -= m.inverse() * r;
        }
        const double error = (p - corner).norm();
        EXPECT_LT(error, 0.05) << mcmt::DistortionModelName(model) << " corner " << k << " at "
                               << corner.transpose() << " measured " << p.transpose();
        worst_corner = std::max(worst_corner, error);
      }
    }
    EXPECT_GT(largest_bend, 0.05) << "the test square should show the distortion's curvature";
    std::cout << mcmt::DistortionModelName(model) << ": max edge error " << worst_edge
              << " px, max corner error " << worst_corner << " px (edges bend up to " << largest_bend
              << " px from their chords)\n";
    RecordProperty(mcmt::DistortionModelName(model) + "_max_corner_error_px", std::to_string(worst_corner));
  }
}

// Plain SxS point supersampling converges to the exact mode: per pixel within the sampling error of a
// straight edge (half a sample row per sample row: <= 1/(2S) of the pixel per edge, two edges at a
// corner pixel), and the error shrinks as S grows.
TEST(RenderExact, SupersamplingAgreesWithExactMode) {
  const sim::SimCamera cam = PinholeCamera(200, 160, 420.0, 101.3, 77.8);
  const double size = 0.06;
  const sim::SimObject obj = SingleMarker(size);
  const Rigid3 pose = FacingPose(Vec3(0.011, -0.007, 0.5), 35, -20, 12);
  const cv::Mat exact = sim::Renderer(obj, "DICT_6X6_250", ExactOptions()).RenderIdeal(cam, 0, pose);
  const auto views = sim::ProjectMarkers(cam, obj, pose);
  double perimeter = 0;
  for (int i = 0; i < 4; ++i) perimeter += (views[0].corners[(i + 1) % 4] - views[0].corners[i]).norm();
  double previous_mean = 1e300;
  for (int s : {2, 4, 16}) {
    sim::RenderOptions o = ExactOptions();
    o.supersampling = s;
    const cv::Mat ss = sim::Renderer(obj, "DICT_6X6_250", o).RenderIdeal(cam, 0, pose);
    cv::Mat diff;
    cv::absdiff(Coverage(ss), Coverage(exact), diff);
    double max_diff = 0;
    cv::minMaxLoc(diff, nullptr, &max_diff);
    const int edge_pixels = cv::countNonZero(diff > 1e-9);
    const double mean_diff = cv::sum(diff)[0] / std::max(1, edge_pixels);
    const double area_diff = std::abs(DarkArea(Coverage(ss)) - DarkArea(Coverage(exact)));
    std::cout << "supersampling " << s << "x" << s << ": max coverage difference " << max_diff
              << ", mean over " << edge_pixels << " differing pixels " << mean_diff << ", area difference "
              << area_diff << " px^2\n";
    EXPECT_LE(max_diff, 1.0 / s + 0.5 / (s * s)) << s;
    EXPECT_LE(area_diff, 0.5 / s * perimeter) << s;
    EXPECT_LT(mean_diff, previous_mean) << s;
    // Interior and far background agree exactly (only edge pixels differ).
    EXPECT_LE(edge_pixels, static_cast<int>(3 * perimeter)) << s;
    previous_mean = mean_diff;
  }
}

// A marker facing away from the camera renders nothing; the same marker turned towards it does.
TEST(RenderExact, HiddenFacesRenderNothing) {
  const sim::SimCamera cam = PinholeCamera(160, 120, 300.0, 79.5, 59.5);
  const sim::SimObject obj = SingleMarker(0.05);
  const sim::Renderer renderer(obj, "DICT_6X6_250", ExactOptions());
  for (double yaw : {180.0, 120.0, -100.0}) {
    const Rigid3 away = FacingPose(Vec3(0.01, 0, 0.4), yaw, 0, 0);
    const auto views = sim::ProjectMarkers(cam, obj, away);
    EXPECT_FALSE(views[0].front_facing);
    EXPECT_FALSE(views[0].fully_visible);
    const cv::Mat image = renderer.RenderIdeal(cam, 0, away);
    double lo, hi;
    cv::minMaxLoc(image, &lo, &hi);
    EXPECT_EQ(lo, kBackground) << "yaw " << yaw;
    EXPECT_EQ(hi, kBackground) << "yaw " << yaw;
  }
  const Rigid3 facing = FacingPose(Vec3(0.01, 0, 0.4), 60, 0, 0);
  EXPECT_TRUE(sim::ProjectMarkers(cam, obj, facing)[0].fully_visible);
  EXPECT_GT(DarkArea(Coverage(renderer.RenderIdeal(cam, 0, facing))), 100.0);
}

// Occlusion by depth: a marker behind the opaque body is not drawn (the body's face shows over its
// whole projection), a marker beside the body and one on the body's front face are.
TEST(RenderExact, OcclusionByDepth) {
  const sim::SimCamera cam = PinholeCamera(320, 240, 400.0, 159.5, 119.5);
  const double albedo = 0.45;
  sim::SimObject obj;
  obj.name = "occlusion";
  obj.faces = BoxFaces(0.06, albedo);  // cube of 6 cm at the object origin
  auto marker_at = [](int id, double size, const Vec3& centre) {
    Rigid3 pose = Rigid3::Identity();
    pose.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();  // facing -z, towards the camera
    pose.translation() = centre;
    return sim::SimMarker{id, size, pose};
  };
  obj.markers.push_back(marker_at(0, 0.03, Vec3(0, 0, 0.06)));         // behind the cube
  obj.markers.push_back(marker_at(1, 0.03, Vec3(0.09, 0, 0.06)));      // beside it, same depth
  obj.markers.push_back(marker_at(2, 0.01, Vec3(0.02, 0.02, -0.03)));  // on the cube's front face
  obj.radius = 0.15;
  Rigid3 pose = Rigid3::Identity();  // object axes = camera axes, 0.5 m ahead
  pose.translation() = Vec3(0, 0, 0.5);
  const auto views = sim::ProjectMarkers(cam, obj, pose);
  ASSERT_EQ(views.size(), 3u);
  EXPECT_TRUE(views[0].front_facing);
  EXPECT_TRUE(views[0].occluded);
  EXPECT_FALSE(views[0].fully_visible);
  EXPECT_TRUE(views[1].fully_visible);
  EXPECT_TRUE(views[2].fully_visible);

  const cv::Mat image = sim::Renderer(obj, "DICT_6X6_250", ExactOptions()).RenderIdeal(cam, 0, pose);
  const double face = 255.0 * albedo;
  auto centre_pixel = [&](const sim::MarkerView& v) {
    Vec2 c(0, 0);
    for (const auto& p : v.corners) c += 0.25 * p;
    return cv::Point(static_cast<int>(std::lround(c.x())), static_cast<int>(std::lround(c.y())));
  };
  // Every pixel inside the hidden marker's projection shows the face.
  std::vector<cv::Point> quad;
  for (const auto& p : views[0].corners) quad.emplace_back(static_cast<int>(p.x()), static_cast<int>(p.y()));
  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8U);
  cv::fillConvexPoly(mask, quad, cv::Scalar(255));
  int inside = 0;
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u) {
      if (!mask.at<uint8_t>(v, u)) continue;
      ++inside;
      EXPECT_NEAR(image.at<float>(v, u), face, 1e-3) << "pixel " << u << "," << v;
    }
  EXPECT_GT(inside, 300);
  EXPECT_NEAR(image.at<float>(centre_pixel(views[0])), face, 1e-3);
  EXPECT_NEAR(image.at<float>(centre_pixel(views[1])), kBlack, 1e-3);
  EXPECT_NEAR(image.at<float>(centre_pixel(views[2])), kBlack, 1e-3);
  // Without the body the hidden marker is drawn: the check above can see it.
  sim::SimObject bare = obj;
  bare.faces.clear();
  const cv::Mat bare_image = sim::Renderer(bare, "DICT_6X6_250", ExactOptions()).RenderIdeal(cam, 0, pose);
  EXPECT_NEAR(bare_image.at<float>(centre_pixel(views[0])), kBlack, 1e-3);
  // The face itself has the exact expected area-weighted value along its edges: dark area of the cube
  // (face value vs background) equals its projected front face.
  sim::SimObject body = obj;
  body.markers.clear();
  const cv::Mat body_image = sim::Renderer(body, "DICT_6X6_250", ExactOptions()).RenderIdeal(cam, 0, pose);
  const double side_px = cam.model.fx * 0.06 / 0.47;
  const double covered = cv::sum((kBackground - body_image) / (kBackground - face))[0];
  EXPECT_NEAR(covered, side_px * side_px, 0.01 * 4 * side_px);
}

// Motion blur: the exposure ends at the frame's pose and spans exposure_fraction of the motion from
// the previous frame. A square translating parallel to the image plane keeps its dark area, its
// coverage centroid sits where the square is at the middle of the exposure, and its edges become
// ramps as long as the motion during the exposure.
TEST(RenderExact, MotionBlurAveragesOverTheExposure) {
  const sim::SimCamera cam = PinholeCamera(200, 160, 400.0, 99.5, 79.5);
  const double size = 0.04, depth = 0.5;  // 32 px
  const sim::SimObject obj = SingleMarker(size);
  sim::RenderOptions o = ExactOptions();
  o.motion_blur_samples = 41;
  o.exposure_fraction = 0.5;
  const sim::Renderer renderer(obj, "DICT_6X6_250", o);
  const Rigid3 previous = FacingPose(Vec3(-0.01, 0.002, depth), 0, 0, 0);
  const Rigid3 current = FacingPose(Vec3(0.015, 0.002, depth), 0, 0, 0);  // 20 px to the right
  auto centroid = [](const cv::Mat& coverage) {
    double sum = 0, su = 0, sv = 0;
    for (int v = 0; v < coverage.rows; ++v)
      for (int u = 0; u < coverage.cols; ++u) {
        const double c = coverage.at<double>(v, u);
        sum += c, su += c * u, sv += c * v;
      }
    return Vec2(su / sum, sv / sum);
  };
  auto coverage8 = [](const cv::Mat& image) {
    cv::Mat f;
    image.convertTo(f, CV_64F);
    return Coverage(f);
  };
  const double side = cam.model.fx * size / depth;
  // Without the previous pose: no blur, the square at the frame's pose.
  const cv::Mat sharp = coverage8(renderer.Render(cam, 0, 1, current));
  const Vec2 at_frame(cam.model.cx + cam.model.fx * 0.015 / depth,
                      cam.model.cy + cam.model.fy * 0.002 / depth);
  EXPECT_NEAR(DarkArea(sharp), side * side, 0.5);
  EXPECT_NEAR((centroid(sharp) - at_frame).norm(), 0.0, 0.02);
  // With it: the exposure covers the last half of the motion, centred at 3/4 of the way.
  const cv::Mat blurred = coverage8(renderer.Render(cam, 0, 1, current, &previous));
  const double x_mid = -0.01 + 0.75 * 0.025;
  const Vec2 at_mid(cam.model.cx + cam.model.fx * x_mid / depth, at_frame.y());
  EXPECT_NEAR(DarkArea(blurred), side * side, 0.5);
  const Vec2 c = centroid(blurred);
  EXPECT_NEAR(c.x(), at_mid.x(), 0.02);
  EXPECT_NEAR(c.y(), at_mid.y(), 0.02);
  // Each vertical edge becomes a ramp 10 px long (half of the 20 px motion): count partial pixels
  // along the middle row.
  const int row = static_cast<int>(std::lround(at_mid.y()));
  int partial = 0;
  for (int u = 0; u < blurred.cols; ++u) {
    const double cov = blurred.at<double>(row, u);
    if (cov > 0.02 && cov < 0.98) ++partial;
  }
  EXPECT_GE(partial, 2 * 9);
  EXPECT_LE(partial, 2 * 11);
  std::cout << "motion blur: centroid " << c.transpose() << " (expected " << at_mid.transpose() << "), area "
            << DarkArea(blurred) << " px^2 (expected " << side * side << "), " << partial
            << " partial pixels in the middle row\n";
}

// Same options and seed: identical bytes (also from a second renderer); another frame: new noise of
// the configured sigma around the same noise-free image.
TEST(RenderDeterminism, SameSeedSameBytesOtherFrameOtherNoise) {
  sim::ObjectOptions oo;
  oo.kind = sim::ObjectKind::kFourSided;
  const sim::SimObject obj = sim::MakeObject(oo);
  const auto cameras = sim::MakeRig(sim::RigOptions());
  sim::TrajectoryOptions to;
  to.frames = 3;
  const auto frames = sim::MakeTrajectory(to);
  sim::RenderOptions ro;  // defaults: noise, texture, gradient, shading
  ASSERT_GT(ro.noise_sigma, 0);
  const sim::Renderer a(obj, "DICT_6X6_250", ro), b(obj, "DICT_6X6_250", ro);
  const Rigid3& pose = frames[1].rig_from_object;
  const cv::Mat a5 = a.Render(cameras[2], 2, 5, pose);
  const cv::Mat a5_again = a.Render(cameras[2], 2, 5, pose);
  const cv::Mat b5 = b.Render(cameras[2], 2, 5, pose);
  ASSERT_EQ(a5.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero(a5 != a5_again), 0);
  EXPECT_EQ(cv::countNonZero(a5 != b5), 0);
  const cv::Mat a6 = a.Render(cameras[2], 2, 6, pose);
  const cv::Mat other_camera_index = a.Render(cameras[2], 3, 5, pose);
  EXPECT_GT(cv::countNonZero(a5 != a6), a5.total() / 2);
  EXPECT_GT(cv::countNonZero(a5 != other_camera_index), a5.total() / 2);
  // Noise statistics over pixels away from saturation.
  const cv::Mat ideal = a.RenderIdeal(cameras[2], 2, pose);
  const cv::Mat usable = (ideal > 15) & (ideal < 240);
  ASSERT_GT(cv::countNonZero(usable), static_cast<int>(a5.total() / 2));
  cv::Mat f5, f6;
  a5.convertTo(f5, CV_64F);
  a6.convertTo(f6, CV_64F);
  cv::Mat ideal64;
  ideal.convertTo(ideal64, CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(f5 - f6, mean, stddev, usable);
  // Difference of two independent N(0, sigma^2) draws, each rounded (+1/12 variance).
  const double expected_diff = std::sqrt(2 * (ro.noise_sigma * ro.noise_sigma + 1.0 / 12));
  EXPECT_NEAR(mean[0], 0.0, 0.05);
  EXPECT_NEAR(stddev[0], expected_diff, 0.05 * expected_diff);
  cv::Scalar mean_noise, std_noise;
  cv::meanStdDev(f5 - ideal64, mean_noise, std_noise, usable);
  EXPECT_NEAR(mean_noise[0], 0.0, 0.05);
  EXPECT_NEAR(std_noise[0], std::sqrt(ro.noise_sigma * ro.noise_sigma + 1.0 / 12), 0.1);
  std::cout << "noise: frame-to-frame difference std " << stddev[0] << " (expected " << expected_diff
            << "), image - ideal std " << std_noise[0] << " mean " << mean_noise[0] << "\n";
}

// ---------------------------------------------------------------------------------------------
// Box layout

namespace {

// Separation of two convex polygons (> 0: apart by that much along the best separating axis).
double Separation(const std::vector<Vec2>& p, const std::vector<Vec2>& q) {
  double best = -1e300;
  for (const auto* poly : {&p, &q})
    for (size_t i = 0; i < poly->size(); ++i) {
      const Vec2 e = (*poly)[(i + 1) % poly->size()] - (*poly)[i];
      const Vec2 n = Vec2(-e.y(), e.x()).normalized();
      double pmin = 1e300, pmax = -1e300, qmin = 1e300, qmax = -1e300;
      for (const Vec2& x : p) pmin = std::min(pmin, n.dot(x)), pmax = std::max(pmax, n.dot(x));
      for (const Vec2& x : q) qmin = std::min(qmin, n.dot(x)), qmax = std::max(qmax, n.dot(x));
      best = std::max(best, std::max(qmin - pmax, pmin - qmax));
    }
  return best;
}

// Builds the box for a marker size and seed and checks its layout: 8 markers with consecutive ids,
// each (with the one-cell quiet zone of a 6x6 dictionary) inside one face, facing out, and not
// overlapping another marker's quiet square on that face.
void CheckBoxLayout(double size, uint64_t seed) {
  sim::ObjectOptions o;
  o.kind = sim::ObjectKind::kBox;
  o.marker_size = size;
  o.seed = seed;
  o.first_id = 10;
  sim::SimObject obj;
  ASSERT_NO_THROW(obj = sim::MakeObject(o)) << "seed " << seed;
  ASSERT_EQ(obj.markers.size(), 8u) << "seed " << seed;
  const double half_quiet = 0.5 * size * (6 + 2 + 2) / (6 + 2);  // 8 cells + 1 each side
  std::vector<int> face_of(8, -1);
  std::vector<std::vector<Vec2>> squares(8);  // quiet squares in their face's 2D basis
  for (size_t i = 0; i < obj.markers.size(); ++i) {
    const sim::SimMarker& m = obj.markers[i];
    EXPECT_EQ(m.id, 10 + static_cast<int>(i));
    EXPECT_DOUBLE_EQ(m.size, size);
    const Eigen::Matrix3d r = m.object_from_marker.linear();
    EXPECT_NEAR((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    const Vec3 c = m.object_from_marker.translation();
    for (size_t f = 0; f < obj.faces.size(); ++f) {
      const auto& v = obj.faces[f].vertices;
      const Vec3 n = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
      if (std::abs(n.dot(c - v[0])) < 1e-12 && r.col(2).dot(n) > 1 - 1e-12) face_of[i] = static_cast<int>(f);
    }
    ASSERT_GE(face_of[i], 0) << "seed " << seed << ": marker " << m.id << " is not on a face, facing out";
    const auto& v = obj.faces[face_of[i]].vertices;
    const Vec3 n = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
    const Vec3 e1 = (v[1] - v[0]).normalized(), e2 = n.cross(e1);
    for (int sx : {-1, 1})
      for (int sy : {-1, 1}) {
        const Vec3 corner = m.object_from_marker * Vec3(sx * half_quiet, sy * half_quiet, 0);
        for (size_t k = 0; k < v.size(); ++k)
          EXPECT_GE((v[(k + 1) % v.size()] - v[k]).cross(corner - v[k]).dot(n), -1e-12)
              << "seed " << seed << ": marker " << m.id << "'s quiet zone leaves its face";
      }
    for (const Vec2& s : {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)}) {
      const Vec3 corner = m.object_from_marker * Vec3(s.x() * half_quiet, s.y() * half_quiet, 0);
      squares[i].emplace_back(e1.dot(corner - v[0]), e2.dot(corner - v[0]));
    }
  }
  for (int i = 0; i < 8; ++i)
    for (int j = i + 1; j < 8; ++j)
      if (face_of[i] == face_of[j]) {
        EXPECT_GT(Separation(squares[i], squares[j]), 0.0)
            << "seed " << seed << ": markers " << obj.markers[i].id << " and " << obj.markers[j].id
            << " overlap";
      }
  // Markers on at least four different faces (the layout spreads them).
  std::sort(face_of.begin(), face_of.end());
  EXPECT_GE(std::unique(face_of.begin(), face_of.end()) - face_of.begin(), 4) << "seed " << seed;
}

}  // namespace

// Every seed builds the box with 8 markers, each (with its one-cell quiet zone of a 6x6 dictionary)
// inside one face and not overlapping any other marker's quiet square on that face. (Seeds 9, 10 and
// 12 used to throw "cannot place marker 6".)
TEST(BoxLayout, EverySeedPlacesEightMarkersWithoutOverlap) {
  for (double size : {0.04, 0.03})
    for (uint64_t seed = 1; seed <= 50; ++seed) CheckBoxLayout(size, seed);
  // Markers so small that the fixed 2 mm gap leaves no random layout: the deterministic fallback.
  CheckBoxLayout(0.002, 1);
  // Deterministic for a seed, different between seeds.
  sim::ObjectOptions o;
  o.kind = sim::ObjectKind::kBox;
  o.seed = 7;
  const auto a = sim::MakeObject(o), b = sim::MakeObject(o);
  o.seed = 8;
  const auto c = sim::MakeObject(o);
  EXPECT_TRUE(a.markers[3].object_from_marker.isApprox(b.markers[3].object_from_marker, 0.0));
  EXPECT_FALSE(a.markers[3].object_from_marker.isApprox(c.markers[3].object_from_marker, 1e-6));
}

namespace mcmt {
namespace {

// The camera pipeline on the scene's linear image: gamma encodes every level as 255 (v / 255)^(1 / g),
// vignetting darkens the corners by its fraction, shot noise grows with the level, JPEG changes the
// bytes by a few levels, sharpening overshoots at edges; --imaging random draws per camera, reproducibly.
TEST(RenderPipeline, EachImagingParameterActsAsDocumented) {
  const sim::SimCamera cam = PinholeCamera(160, 120, 150, 79.5, 59.5);
  const sim::SimObject obj = SingleMarker(0.04);
  const Rigid3 pose = FacingPose(Vec3(0, 0, 0.5), 0, 0, 0);
  sim::RenderOptions base = ExactOptions();
  auto render = [&](const sim::RenderOptions& o) {
    cv::Mat f;
    sim::Renderer(obj, "DICT_6X6_250", o).Render(cam, 0, 0, pose).convertTo(f, CV_64F);
    return f;
  };
  const cv::Mat linear = render(base);
  sim::RenderOptions g = base;
  g.gamma = 2.2;
  const cv::Mat encoded = render(g);
  const double bg = linear.at<double>(2, 2), bg_encoded = encoded.at<double>(2, 2);
  EXPECT_NEAR(bg_encoded, 255.0 * std::pow(bg / 255.0, 1.0 / 2.2), 1.0);
  sim::RenderOptions v = base;
  v.vignetting = 0.3;
  const cv::Mat vignetted = render(v);
  EXPECT_NEAR(vignetted.at<double>(0, 0), 0.7 * linear.at<double>(0, 0), 1.0);
  EXPECT_NEAR(vignetted.at<double>(60, 2),
              linear.at<double>(60, 2) * (1 - 0.3 * (77.5 * 77.5 + 0.25) / (79.5 * 79.5 + 59.5 * 59.5)), 1.0);
  sim::RenderOptions s = base;
  s.shot_noise = 0.5;
  const cv::Mat shot = render(s);
  cv::Mat diff = shot - linear;
  const cv::Rect corner(0, 0, 20, 20);  // background, level kBackground
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff(corner), mean, stddev);
  EXPECT_NEAR(stddev[0], std::sqrt(0.5 * bg), 0.25 * std::sqrt(0.5 * bg));
  sim::RenderOptions j = base;
  j.jpeg_quality = 70;
  const cv::Mat jpeg = render(j);
  const double jpeg_change = cv::norm(jpeg, linear, cv::NORM_L1) / linear.total();
  EXPECT_GT(jpeg_change, 0.05);
  EXPECT_LT(jpeg_change, 4.0);
  sim::RenderOptions sh = base;
  sh.sharpen = 0.8;
  double min_sharp, max_sharp, min_plain, max_plain;
  cv::minMaxLoc(render(sh), &min_sharp, &max_sharp);
  cv::minMaxLoc(linear, &min_plain, &max_plain);
  EXPECT_LT(min_sharp, min_plain - 5);  // undershoot on the dark side of the marker's edges

  std::vector<std::string> a_lines, b_lines;
  const sim::RenderOptions a = sim::RandomImaging(sim::RenderOptions(), 5, 7, &a_lines);
  const sim::RenderOptions b = sim::RandomImaging(sim::RenderOptions(), 5, 7, &b_lines);
  ASSERT_EQ(a.cameras.size(), 5u);
  EXPECT_EQ(a_lines, b_lines);
  std::set<std::string> distinct(a_lines.begin(), a_lines.end());
  EXPECT_EQ(distinct.size(), 5u);
  for (const auto& c : a.cameras) {
    EXPECT_EQ(c.quiet_zone_cells, a.quiet_zone_cells);  // the print is the session's
    EXPECT_GE(c.quiet_zone_cells, 0);
    EXPECT_LE(c.quiet_zone_cells, 2);
    EXPECT_TRUE(c.gamma == 1.0 || (c.gamma >= 1.8 && c.gamma <= 2.4));
    EXPECT_TRUE(c.jpeg_quality == 0 || (c.jpeg_quality >= 60 && c.jpeg_quality <= 95));
  }
  EXPECT_NE(sim::RandomImaging(sim::RenderOptions(), 5, 8).cameras[0].noise_sigma, a.cameras[0].noise_sigma);
}

}  // namespace
}  // namespace mcmt
