#include "viz/scene.h"

#include <mrpt/img/CImage.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/opengl/CBox.h>
#include <mrpt/opengl/CCamera.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/CFrustum.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/opengl/CText.h>
#include <mrpt/opengl/CTexturedPlane.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/dictionary.h"
#include "core/marker.h"
#include "core/math.h"
#include "mcmt/camera_health_t.hpp"

namespace mcmt::viz {
namespace {

using mrpt::opengl::CSetOfLines;
using mrpt::opengl::CSetOfObjects;

constexpr char kMainViewport[] = "main";
constexpr char kLeftViewport[] = "left";
constexpr char kLegendViewport[] = "legend";
const mrpt::img::TColorf kBackground(0.16f, 0.18f, 0.22f, 1.0f);
const Eigen::Vector3d kNeutral(0.55, 0.75, 0.95);  // cameras and markers with no residual statistics

mrpt::poses::CPose3D ToCPose(const Rigid3& t) {
  mrpt::math::CMatrixDouble44 m;
  const Eigen::Matrix4d e = t.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = e(r, c);
  return mrpt::poses::CPose3D(m);
}

mrpt::img::TColorf ToColor(const Eigen::Vector3d& rgb, double alpha = 1.0) {
  return mrpt::img::TColorf(static_cast<float>(rgb.x()), static_cast<float>(rgb.y()),
                            static_cast<float>(rgb.z()), static_cast<float>(alpha));
}

mrpt::math::TPoint3D ToPoint(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

// A "nice" grid spacing (1, 2 or 5 times a power of ten) near `approx`.
double NiceStep(double approx) {
  const double p = std::pow(10.0, std::floor(std::log10(std::max(approx, 1e-6))));
  const double f = approx / p;
  return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * p;
}

// The marker's bitmap as a texture: row 0 of an MRPT texture lands at the plane's yMin, so the
// image is flipped vertically to put the ArUco top-left corner at (-s/2, +s/2, 0).
std::optional<mrpt::img::CImage> MarkerTexture(const cv::aruco::Dictionary& dictionary, int id) {
  if (id < 0 || id >= dictionary.bytesList.rows) return std::nullopt;
  const int cells = dictionary.markerSize + 2;
  cv::Mat gray = MarkerImage(dictionary, id, cells * 16);
  cv::Mat bgr;
  if (gray.channels() == 1)
    cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
  else
    bgr = gray;
  cv::flip(bgr, bgr, 0);
  return mrpt::img::CImage(bgr, mrpt::img::DEEP_COPY);
}

// A body's markers as textured squares at object_from_marker, each framed in its residual colour (or the
// neutral colour), plus the body's axes. With body_rgb (a map with several bodies): an outline in the
// body's colour around each marker.
CSetOfObjects::Ptr BodyObject(const std::vector<MapMarker>& markers, const cv::aruco::Dictionary* dictionary,
                              const std::function<Eigen::Vector3d(const MapMarker&)>& frame_rgb,
                              const Eigen::Vector3d* body_rgb) {
  using namespace mrpt::opengl;
  auto object = CSetOfObjects::Create();
  double max_marker = 0.0;
  for (const auto& m : markers) max_marker = std::max(max_marker, m.size);
  object->insert(stock_objects::CornerXYZSimple(static_cast<float>(0.6 * std::max(max_marker, 0.01)), 2.0f));
  for (const auto& m : markers) {
    const float h = static_cast<float>(0.5 * m.size);
    auto set = CSetOfObjects::Create();
    set->setPose(ToCPose(m.object_from_marker));
    auto plane = CTexturedPlane::Create(-h, h, -h, h);
    std::optional<mrpt::img::CImage> tex;
    if (dictionary) tex = MarkerTexture(*dictionary, m.id);
    if (tex) {
      plane->assignImage(*tex);
    } else {
      cv::Mat white(8, 8, CV_8UC3, cv::Scalar(230, 230, 230));
      plane->assignImage(mrpt::img::CImage(white, mrpt::img::DEEP_COPY));
    }
    set->insert(plane);
    auto square = [&](float e, float width, const Eigen::Vector3d& rgb) {
      auto frame = CSetOfLines::Create();
      const float z = static_cast<float>(0.01 * m.size);
      frame->appendLine(-e, e, z, e, e, z);
      frame->appendLine(e, e, z, e, -e, z);
      frame->appendLine(e, -e, z, -e, -e, z);
      frame->appendLine(-e, -e, z, -e, e, z);
      frame->setLineWidth(width);
      frame->setColor(ToColor(rgb));
      set->insert(frame);
    };
    square(1.04f * h, 3.0f, frame_rgb(m));
    if (body_rgb) square(1.25f * h, 4.0f, *body_rgb);
    object->insert(set);
  }
  return object;
}

}  // namespace

Eigen::Vector3d BodyColor(size_t k) {
  static const Eigen::Vector3d kPalette[] = {
      {1.0, 0.2, 0.85},    // magenta
      {0.25, 0.4, 1.0},    // blue
      {1.0, 0.62, 0.75},   // pink
      {0.6, 0.3, 1.0},     // violet
      {0.55, 0.35, 0.15},  // brown
  };
  return kPalette[k % (sizeof(kPalette) / sizeof(kPalette[0]))];
}

cv::Vec3b BackgroundBgr() {
  auto byte = [](float v) { return static_cast<uchar>(std::lround(255.0 * v)); };
  return cv::Vec3b(byte(kBackground.B), byte(kBackground.G), byte(kBackground.R));
}

Eigen::Vector3d ResidualColor(double rms_px, double scale_px) {
  const double green_px = 0.25 * scale_px;
  double t = scale_px > 0 ? (rms_px - green_px) / (scale_px - green_px) : 0.0;
  if (!std::isfinite(t)) t = 1.0;
  t = std::clamp(t, 0.0, 1.0);
  // Green (t = 0) -> yellow (t = 1/2) -> red (t = 1), linear in each half.
  return Eigen::Vector3d(std::min(1.0, 2.0 * t), std::min(1.0, 2.0 * (1.0 - t)) * 0.85, 0.1);
}

bool CameraStateColor(int state, Eigen::Vector3d* rgb) {
  if (state == camera_health_t::STATE_SUSPECT) {
    *rgb = Eigen::Vector3d(1.0, 0.55, 0.0);  // orange
    return true;
  }
  if (state == camera_health_t::STATE_EXCLUDED) {
    *rgb = Eigen::Vector3d(0.9, 0.0, 0.0);  // red
    return true;
  }
  if (state == camera_health_t::STATE_NOT_JUDGED) {
    *rgb = Eigen::Vector3d(0.7, 0.25, 1.0);  // violet: neither a residual colour nor the neutral blue
    return true;
  }
  return false;
}

std::string CameraStateSuffix(int state) {
  if (state == camera_health_t::STATE_SUSPECT) return " (suspect)";
  if (state == camera_health_t::STATE_EXCLUDED) return " (excluded)";
  if (state == camera_health_t::STATE_NOT_JUDGED) return " (not judged)";
  return "";
}

Rigid3 CamFromFrustum() {
  Rigid3 t = Rigid3::Identity();
  Eigen::Matrix3d r;
  // Columns: the frustum's X, Y, Z axes expressed in the OpenCV camera frame.
  r << 0, -1, 0,  //
      0, 0, -1,   //
      1, 0, 0;
  t.linear() = r;
  return t;
}

Rigid3 WorldFromRig(const RigMap& map) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const auto& cam : map.cameras) up -= cam.rig_from_cam.linear().col(1);
  if (up.norm() < 0.3 * std::max<size_t>(1, map.cameras.size())) up = Eigen::Vector3d(0, -1, 0);
  up.normalize();
  // Reference camera's viewing direction (+Z of the rig), made horizontal.
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ() - up * up.z();
  if (forward.norm() < 1e-3) forward = Eigen::Vector3d::UnitX() - up * up.x();
  forward.normalize();
  const Eigen::Vector3d x = forward.cross(up);
  Eigen::Matrix3d rig_from_world_r;
  rig_from_world_r.col(0) = x;
  rig_from_world_r.col(1) = forward;
  rig_from_world_r.col(2) = up;
  Rigid3 world_from_rig = Rigid3::Identity();
  world_from_rig.linear() = rig_from_world_r.transpose();
  return world_from_rig;
}

void SceneOptions::Validate() const {
  if (width < 16 || height < 16 || width > 16384 || height > 16384)
    throw std::invalid_argument("size: expected WIDTHxHEIGHT between 16 and 16384, got " +
                                std::to_string(width) + "x" + std::to_string(height));
  if (!(residual_scale_px >= 0)) throw std::invalid_argument("residual_scale_px: expected >= 0");
  if (trail_max < 0) throw std::invalid_argument("trail_max: expected >= 0");
  if (!(fov_deg > 1 && fov_deg < 170)) throw std::invalid_argument("fov_deg: expected in (1, 170)");
}

VizScene::VizScene(SceneOptions options) : options_(std::move(options)) {
  options_.Validate();
  scene_ = mrpt::opengl::COpenGLScene::Create();
  views_.resize(1);
  UpdateViewports();
}

VizScene::~VizScene() = default;

std::string VizScene::DictionaryName() const {
  if (!options_.dictionary.empty()) return options_.dictionary;
  return panels_.empty() ? std::string() : panels_.back().input.map.dictionary;
}

void VizScene::SetPanels(std::vector<PanelInput> inputs) {
  panels_.clear();
  scene_->clear(true);
  if (inputs.empty()) {
    views_.assign(1, views_.empty() ? ViewCamera() : views_.back());
    UpdateViewports();
    return;
  }
  const ViewCamera old_view = views_.empty() ? ViewCamera() : views_.back();
  world_from_rig_ = WorldFromRig(inputs.back().map);

  // Residual colour scale, common to all panels so that before/after compare. Maps without
  // per-camera/marker statistics (MCMT_MAP carries none) are drawn in a neutral colour, no legend.
  double worst = 0.0;
  for (const auto& in : inputs) {
    for (const auto& c : in.map.cameras) worst = std::max(worst, c.rms_px);
    for (const auto& m : in.map.markers) worst = std::max(worst, m.rms_px);
    for (const auto& o : in.map.objects)
      for (const auto& m : o.markers) worst = std::max(worst, m.rms_px);
  }
  has_residuals_ = worst > 0.0;
  residual_scale_ = options_.residual_scale_px > 0 ? options_.residual_scale_px : std::max(0.5, worst);

  // Sizes from the last panel: frustum length and floor height.
  const PanelInput& ref = inputs.back();
  std::vector<Eigen::Vector3d> centres;
  for (const auto& c : ref.map.cameras) centres.push_back(c.rig_from_cam.translation());
  std::vector<double> dists;
  if (!ref.trajectory.empty()) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& r : ref.trajectory) mean += r.rig_from_object.translation();
    mean /= static_cast<double>(ref.trajectory.size());
    for (const auto& c : centres) dists.push_back((c - mean).norm());
    frustum_length_ = 0.25 * Median(dists);
  } else {
    for (size_t i = 0; i < centres.size(); ++i)
      for (size_t j = i + 1; j < centres.size(); ++j) dists.push_back((centres[i] - centres[j]).norm());
    frustum_length_ = dists.empty() ? 0.2 : 0.3 * Median(dists);
  }
  double max_marker = 0.0;
  for (const auto& m : ref.map.markers) max_marker = std::max(max_marker, m.size);
  frustum_length_ = std::max({frustum_length_, 2.0 * max_marker, 0.02});

  for (auto& in : inputs) {
    Panel p;
    p.input = std::move(in);
    panels_.push_back(std::move(p));
  }
  views_.assign(panels_.size(), old_view);
  if (panels_.size() == 1) {
    panels_[0].viewport = kMainViewport;
  } else {
    // Every panel but the last gets its own viewport; the last is "main" (the one MRPT's window
    // moves with the mouse).
    for (size_t i = 0; i + 1 < panels_.size(); ++i)
      panels_[i].viewport = i == 0 ? std::string(kLeftViewport) : "panel" + std::to_string(i);
    panels_.back().viewport = kMainViewport;
  }
  UpdateViewports();

  // Floor: below every camera and every object position.
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : panels_) {
    for (const auto& c : p.input.map.cameras) pts.push_back(world_from_rig_ * c.rig_from_cam.translation());
    for (const auto& r : p.input.trajectory) pts.push_back(world_from_rig_ * r.rig_from_object.translation());
    for (const auto& [name, rows] : p.input.bodies)
      for (const auto& r : rows) pts.push_back(world_from_rig_ * r.rig_from_object.translation());
    for (const auto& o : p.input.map.objects)
      if (o.is_static) pts.push_back(world_from_rig_ * o.rig_from_object.translation());
  }
  Eigen::Vector3d lo = pts.empty() ? Eigen::Vector3d::Zero() : pts[0], hi = lo;
  for (const auto& q : pts) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double extent = std::max(0.2, (hi - lo).norm());
  floor_z_ = lo.z() - 0.1 * extent - max_marker;
  const double step = NiceStep(extent / 10.0);
  const double pad = 0.2 * extent;
  const auto gx0 = static_cast<float>(std::floor((lo.x() - pad) / step) * step);
  const auto gx1 = static_cast<float>(std::ceil((hi.x() + pad) / step) * step);
  const auto gy0 = static_cast<float>(std::floor((lo.y() - pad) / step) * step);
  const auto gy1 = static_cast<float>(std::ceil((hi.y() + pad) / step) * step);

  for (auto& p : panels_) {
    if (options_.grid) {
      auto grid = mrpt::opengl::CGridPlaneXY::Create(gx0, gx1, gy0, gy1, static_cast<float>(floor_z_),
                                                     static_cast<float>(step), 1.0f);
      grid->setColor(0.45f, 0.47f, 0.52f, 0.8f);
      scene_->insert(grid, p.viewport);
    }
    BuildPanel(&p);
  }
  if (options_.legend && legend_viewport_ && has_residuals_) BuildLegend();
  current_ = -1;
  SetCurrentFrame(-1);
  AutoView();
}

void VizScene::UpdateViewports() {
  const int n = std::max<int>(1, static_cast<int>(panels_.size()));
  const int w = options_.width, h = options_.height;
  for (int i = 0; i < n; ++i) {
    ViewCamera& v = views_.at(i);
    v.fov_deg = options_.fov_deg;
    // As MRPT maps viewport fractions to pixels (truncation).
    v.viewport_x = static_cast<int>(w * (static_cast<double>(i) / n));
    v.viewport_width = static_cast<int>(w * (1.0 / n));
    v.viewport_y = 0;
    v.viewport_height = h;
    v.image_height = h;
    const std::string name = panels_.empty() ? std::string(kMainViewport) : panels_[i].viewport;
    auto vp = scene_->getViewport(name);
    if (!vp) vp = scene_->createViewport(name);
    vp->setViewportPosition(static_cast<double>(i) / n, 0.0, 1.0 / n, 1.0);
    vp->setCustomBackgroundColor(kBackground);
    // More ambient light than MRPT's default: faces turned away from the light stay readable.
    vp->lightParameters().ambient = mrpt::img::TColorf(0.5f, 0.5f, 0.5f, 1.0f);
    vp->lightParameters().diffuse = mrpt::img::TColorf(0.6f, 0.6f, 0.6f, 1.0f);
  }
}

void VizScene::BuildPanel(Panel* panel) {
  using namespace mrpt::opengl;
  const RigMap& map = panel->input.map;
  panel->root = CSetOfObjects::Create();
  panel->root->setPose(ToCPose(world_from_rig_));

  // Rig axes (x red, y green, z blue) at the reference camera.
  panel->root->insert(stock_objects::CornerXYZSimple(static_cast<float>(0.6 * frustum_length_), 3.0f));

  // Cameras: a wireframe frustum sized by the field of view (no faces: the object, inside several
  // frustums, stays visible), a small body and the name, coloured by residual.
  for (const auto& cam : map.cameras) {
    auto set = CSetOfObjects::Create();
    set->setPose(ToCPose(cam.rig_from_cam));
    Eigen::Vector3d color = has_residuals_ ? ResidualColor(cam.rms_px, residual_scale_) : kNeutral;
    const auto state = camera_states_.find(cam.name);
    const bool flagged = state != camera_states_.end() && CameraStateColor(state->second, &color);
    const double hfov = cam.model.fx > 0 ? 2.0 * std::atan2(0.5 * cam.model.width, cam.model.fx) : 1.0;
    const double vfov = cam.model.fy > 0 ? 2.0 * std::atan2(0.5 * cam.model.height, cam.model.fy) : 0.75;
    auto frustum =
        CFrustum::Create(static_cast<float>(0.05 * frustum_length_), static_cast<float>(frustum_length_),
                         static_cast<float>(std::min(179.0, hfov * 180.0 / M_PI)),
                         static_cast<float>(std::min(179.0, vfov * 180.0 / M_PI)), 2.0f, true, false);
    frustum->setPose(ToCPose(CamFromFrustum()));
    frustum->setColor(ToColor(color));
    set->insert(frustum);
    const float b = static_cast<float>(0.08 * frustum_length_);
    auto body = CBox::Create(mrpt::math::TPoint3D(-b, -b, -b), mrpt::math::TPoint3D(b, b, b));
    body->setColor(ToColor(color));
    set->insert(body);
    auto label = CText::Create(flagged ? cam.name + CameraStateSuffix(state->second) : cam.name);
    label->setLocation(0, -2.5 * b, 0);  // above the camera (its -Y)
    label->setColor(1, 1, 1);
    set->insert(label);
    panel->root->insert(set);
  }

  // The object: its markers as textured squares at object_from_marker, framed in their residual
  // colour, plus the object's axes. Several bodies: each in its own colour, with its name.
  cv::Ptr<cv::aruco::Dictionary> dictionary;
  const std::string dict_name = DictionaryName();
  if (!dict_name.empty()) {
    try {
      dictionary = LoadDictionary(dict_name);
    } catch (const std::exception& e) {
      if (!options_.dictionary.empty()) throw;  // asked for explicitly: a real error
      std::cerr << "mcmt-viz: warning: markers drawn without bitmaps: " << e.what() << "\n";
    }
  }
  const auto frame_rgb = [&](const MapMarker& m) {
    return has_residuals_ ? ResidualColor(m.rms_px, residual_scale_) : kNeutral;
  };
  const bool several = map.objects.size() > 1;
  const size_t main_body = FirstMovingObject(map);
  Eigen::Vector3d main_rgb(1.0f, 0.6f, 0.15f);  // a single object's trail
  if (several) main_rgb = BodyColor(main_body);
  auto reach_of = [](const std::vector<MapMarker>& markers) {
    double r = 0.0;
    for (const auto& m : markers) r = std::max(r, m.object_from_marker.translation().norm() + m.size);
    return r;
  };
  panel->object = BodyObject(map.markers, dictionary.get(), frame_rgb, several ? &main_rgb : nullptr);
  panel->reach = reach_of(map.markers);
  panel->label = nullptr;
  if (several) {
    panel->label = MakeLabel(map.objects[main_body].name, main_rgb);
    panel->label->setVisibility(false);
  }
  panel->object->setVisibility(false);
  panel->bodies.clear();
  for (size_t k = 0; several && k < map.objects.size(); ++k) {
    if (k == main_body) continue;
    const MapObject& o = map.objects[k];
    Panel::Body b;
    b.name = o.name;
    b.is_static = o.is_static;
    b.rig_from_object = o.rig_from_object;
    b.object_index = k;
    const Eigen::Vector3d rgb = BodyColor(k);
    b.object = BodyObject(o.markers, dictionary.get(), frame_rgb, &rgb);
    b.reach = reach_of(o.markers);
    b.label = MakeLabel(o.name, rgb);
    if (o.is_static) {
      b.object->setPose(ToCPose(world_from_rig_ * o.rig_from_object));
      const Eigen::Vector3d at = LabelPoint(o.rig_from_object, b.reach);
      b.label->setLocation(at.x(), at.y(), at.z());
    } else {
      b.object->setVisibility(false);
      b.label->setVisibility(false);
      b.trail = CSetOfLines::Create();
      b.trail->setColor(ToColor(rgb));
      b.trail->setLineWidth(2.0f);
      panel->root->insert(b.trail);
    }
    panel->bodies.push_back(std::move(b));
  }

  panel->trail = CSetOfLines::Create();
  panel->trail->setColor(ToColor(main_rgb));
  panel->trail->setLineWidth(2.0f);
  panel->root->insert(panel->trail);
  panel->rays = CSetOfLines::Create();
  panel->rays->setColor(0.3f, 0.85f, 1.0f, 0.8f);
  panel->rays->setLineWidth(1.5f);
  panel->rays->setVisibility(options_.rays);
  panel->root->insert(panel->rays);
  scene_->insert(panel->root, panel->viewport);
  scene_->insert(panel->object, panel->viewport);  // after the rig: drawn last; posed in the world frame
  for (const Panel::Body& b : panel->bodies) {
    scene_->insert(b.object, panel->viewport);
    scene_->insert(b.label, panel->viewport);
  }
  if (panel->label) scene_->insert(panel->label, panel->viewport);

  char title[160];
  size_t markers = map.markers.size();
  if (several) {
    markers = 0;
    for (const auto& o : map.objects) markers += o.markers.size();
  }
  if (several)
    std::snprintf(title, sizeof(title), "%s: %zu cameras, %zu bodies, %zu markers, RMS %.3f px",
                  panel->input.title.c_str(), map.cameras.size(), map.objects.size(), markers, map.rms_px);
  else
    std::snprintf(title, sizeof(title), "%s: %zu cameras, %zu markers, RMS %.3f px",
                  panel->input.title.c_str(), map.cameras.size(), markers, map.rms_px);
  mrpt::opengl::TFontParams font;
  font.vfont_scale = 8;
  font.color = mrpt::img::TColorf(1, 1, 1, 1);
  font.draw_shadow = true;
  scene_->getViewport(panel->viewport)->addTextMessage(8, -18, title, 0, font);
}

void VizScene::BuildLegend() {
  using namespace mrpt::opengl;
  const int lw = 280, lh = 70;
  auto vp = scene_->createViewport(kLegendViewport);
  // Absolute pixels from the right edge (negative x), so it stays bottom-right when the window
  // is resized.
  vp->setViewportPosition(-(lw + 10), 10, lw, lh);
  vp->setTransparent(true);
  auto bar = CSetOfTriangles::Create();
  const int n = 24;
  for (int i = 0; i < n; ++i) {
    const float x0 = static_cast<float>(i) / n, x1 = static_cast<float>(i + 1) / n;
    const auto c0 = ToColor(ResidualColor(residual_scale_ * x0, residual_scale_));
    const auto c1 = ToColor(ResidualColor(residual_scale_ * x1, residual_scale_));
    const float y0 = 0.0f, y1 = 0.08f;
    TTriangle a(mrpt::math::TPoint3Df(x0, y0, 0), mrpt::math::TPoint3Df(x1, y0, 0),
                mrpt::math::TPoint3Df(x1, y1, 0));
    TTriangle b(mrpt::math::TPoint3Df(x0, y0, 0), mrpt::math::TPoint3Df(x1, y1, 0),
                mrpt::math::TPoint3Df(x0, y1, 0));
    for (TTriangle* t : {&a, &b}) {
      t->computeNormals();
      for (int k = 0; k < 3; ++k) {
        const auto& c = t->x(k) > 0.5f * (x0 + x1) ? c1 : c0;
        t->r(k) = static_cast<uint8_t>(255 * c.R);
        t->g(k) = static_cast<uint8_t>(255 * c.G);
        t->b(k) = static_cast<uint8_t>(255 * c.B);
        t->a(k) = 255;
      }
    }
    bar->insertTriangle(a);
    bar->insertTriangle(b);
  }
  vp->insert(bar);
  char text[64];
  auto lo = CText::Create("0");
  lo->setLocation(-0.01, -0.09, 0);
  vp->insert(lo);
  std::snprintf(text, sizeof(text), "%.2f", 0.25 * residual_scale_);  // green up to here
  auto green = CText::Create(text);
  green->setLocation(0.2, -0.09, 0);
  vp->insert(green);
  std::snprintf(text, sizeof(text), ">= %.2f px", residual_scale_);
  auto hi = CText::Create(text);
  hi->setLocation(0.78, -0.09, 0);
  vp->insert(hi);
  auto title = CText::Create("residual RMS (px)");
  title->setLocation(0.0, 0.12, 0);
  vp->insert(title);
  ViewCamera cam;
  cam.pointing = Eigen::Vector3d(0.5, 0.02, 0);
  cam.azimuth_deg = -90;
  cam.elevation_deg = 90;
  cam.fov_deg = 45;
  cam.distance = 0.4;
  // A camera object inside the viewport takes precedence over the viewport's camera, which
  // CFBORender replaces by its own when rendering offscreen.
  auto legend_camera = CCamera::Create();
  cam.ApplyTo(legend_camera.get());
  vp->insert(legend_camera);
  cam.ApplyTo(&vp->getCamera());
}

const std::vector<TrajectoryRow>& VizScene::trajectory() const {
  static const std::vector<TrajectoryRow> kEmpty;
  return panels_.empty() ? kEmpty : panels_.back().input.trajectory;
}

void VizScene::AddPose(const TrajectoryRow& row) {
  if (panels_.empty()) return;
  Panel& p = panels_.back();
  auto& rows = p.input.trajectory;
  rows.push_back(row);
  // Bounded memory over a long live session: the oldest rows go in chunks (the trail only shows
  // the newest trail_max), and the trail is rebuilt on the shifted indices.
  const size_t keep = std::max<size_t>(5000, static_cast<size_t>(options_.trail_max));
  if (rows.size() >= 2 * keep) {
    rows.erase(rows.begin(), rows.end() - static_cast<std::ptrdiff_t>(keep));
    p.trail_first = 0;
    p.trail_last = -1;
  }
  SetCurrentFrame(-1);
}

void VizScene::SetCurrentFrame(int index) {
  if (panels_.empty()) return;
  const auto& rows = panels_.back().input.trajectory;
  if (rows.empty()) {
    current_ = -1;
  } else {
    if (index < 0 || index >= static_cast<int>(rows.size())) index = static_cast<int>(rows.size()) - 1;
    current_ = index;
  }
  for (size_t i = 0; i < panels_.size(); ++i) {
    Panel& p = panels_[i];
    int row = -1;
    if (current_ >= 0) {
      if (i + 1 == panels_.size()) {
        row = current_;
      } else {
        const int64_t seq = rows[current_].seq;
        const auto& own = p.input.trajectory;
        auto it = std::lower_bound(own.begin(), own.end(), seq,
                                   [](const TrajectoryRow& r, int64_t s) { return r.seq < s; });
        if (it != own.end() && it->seq == seq) row = static_cast<int>(it - own.begin());
      }
    }
    UpdatePanelFrame(&p, row);
  }
}

namespace {

// Trail: about the newest `keep` rows up to `row`. Grows in place one row at a time and is rebuilt only
// when it is a quarter too long (amortised O(1) per live pose) or the row jumps.
void UpdateTrail(const std::vector<TrajectoryRow>& rows, int row, int keep, CSetOfLines* trail, int* first,
                 int* last) {
  if (row >= 0 && row == *last + 1 && *last >= *first && row - *first < keep + keep / 4) {
    trail->appendLine(ToPoint(rows[row - 1].rig_from_object.translation()),
                      ToPoint(rows[row].rig_from_object.translation()));
    *last = row;
    return;
  }
  *first = row < 0 ? 0 : std::max(0, row + 1 - keep);
  *last = row;
  trail->clear();
  for (int i = *first + 1; i <= *last; ++i)
    trail->appendLine(ToPoint(rows[i - 1].rig_from_object.translation()),
                      ToPoint(rows[i].rig_from_object.translation()));
}

// The newest row at or before `utime` (1 ms tolerance) and at most kBodyPoseMaxAgeUs older; -1: none.
int RowAt(const std::vector<TrajectoryRow>& rows, int64_t utime) {
  auto it = std::upper_bound(rows.begin(), rows.end(), utime + 1000,
                             [](int64_t t, const TrajectoryRow& r) { return t < r.utime; });
  if (it == rows.begin()) return -1;
  --it;
  return utime - it->utime <= kBodyPoseMaxAgeUs ? static_cast<int>(it - rows.begin()) : -1;
}

}  // namespace

void VizScene::UpdatePanelFrame(Panel* panel, int row) {
  panel->current = row;
  if (row < 0) {
    panel->object->setVisibility(false);
    if (panel->label) panel->label->setVisibility(false);
  } else {
    const Rigid3& rig_from_object = panel->input.trajectory[row].rig_from_object;
    panel->object->setVisibility(true);
    panel->object->setPose(ToCPose(world_from_rig_ * rig_from_object));
    if (panel->label) {
      const Eigen::Vector3d at = LabelPoint(rig_from_object, panel->reach);
      panel->label->setLocation(at.x(), at.y(), at.z());
      panel->label->setVisibility(true);
    }
  }
  const int keep = std::max(1, options_.trail_max);
  UpdateTrail(panel->input.trajectory, row, keep, panel->trail.get(), &panel->trail_first,
              &panel->trail_last);
  // The other moving bodies at their rows of this frame's time.
  for (Panel::Body& b : panel->bodies) {
    if (b.is_static) continue;
    const auto it = panel->input.bodies.find(b.name);
    const int body_row = row < 0 || it == panel->input.bodies.end()
                             ? -1
                             : RowAt(it->second, panel->input.trajectory[row].utime);
    UpdateBodyFrame(panel, &b, body_row);
  }
  UpdateRays(panel);
}

void VizScene::UpdateBodyFrame(Panel* panel, Panel::Body* body, int row) {
  body->current = row;
  const auto it = panel->input.bodies.find(body->name);
  if (row < 0 || it == panel->input.bodies.end()) {
    body->current = -1;
    body->object->setVisibility(false);
    body->label->setVisibility(false);
    body->trail->clear();
    body->trail_first = 0;
    body->trail_last = -1;
    return;
  }
  body->object->setVisibility(true);
  body->object->setPose(ToCPose(world_from_rig_ * it->second[row].rig_from_object));
  const Eigen::Vector3d at = LabelPoint(it->second[row].rig_from_object, body->reach);
  body->label->setLocation(at.x(), at.y(), at.z());
  body->label->setVisibility(true);
  UpdateTrail(it->second, row, std::max(1, options_.trail_max), body->trail.get(), &body->trail_first,
              &body->trail_last);
}

Eigen::Vector3d VizScene::LabelPoint(const Rigid3& rig_from_object, double reach) const {
  return world_from_rig_ * rig_from_object.translation() +
         Eigen::Vector3d(0, 0, reach + 0.25 * frustum_length_);
}

mrpt::opengl::CText::Ptr VizScene::MakeLabel(const std::string& name, const Eigen::Vector3d& rgb) const {
  auto label = mrpt::opengl::CText::Create(name);
  label->setColor(ToColor(rgb));
  return label;
}

void VizScene::AddBodyPose(const std::string& name, const TrajectoryRow& row, bool newest) {
  if (panels_.empty()) return;
  Panel& p = panels_.back();
  for (Panel::Body& b : p.bodies) {
    if (b.name != name || b.is_static) continue;
    auto& rows = p.input.bodies[name];
    rows.push_back(row);
    const size_t keep = std::max<size_t>(5000, static_cast<size_t>(options_.trail_max));
    if (rows.size() >= 2 * keep) {
      rows.erase(rows.begin(), rows.end() - static_cast<std::ptrdiff_t>(keep));
      b.trail_first = 0;
      b.trail_last = -1;
    }
    const int shown = newest ? static_cast<int>(rows.size()) - 1
                             : (p.current < 0 ? -1 : RowAt(rows, p.input.trajectory[p.current].utime));
    UpdateBodyFrame(&p, &b, shown);
    UpdateRays(&p);
  }
}

std::optional<Rigid3> VizScene::BodyPose(int panel, const std::string& name) const {
  const Panel& p = panels_.at(panel);
  const auto& objects = p.input.map.objects;
  if (objects.size() > 1 && objects[FirstMovingObject(p.input.map)].name == name) return CurrentPose(panel);
  for (const Panel::Body& b : p.bodies) {
    if (b.name != name) continue;
    if (b.is_static) return b.rig_from_object;
    if (b.current < 0) return std::nullopt;
    return p.input.bodies.at(name)[b.current].rig_from_object;
  }
  return std::nullopt;
}

void VizScene::SetDetections(const std::map<std::string, std::vector<int>>& ids_by_camera) {
  detections_ = ids_by_camera;
  for (auto& p : panels_) UpdateRays(&p);
}

void VizScene::UpdateRays(Panel* panel) {
  panel->rays->clear();
  // Every marker shown: id -> its position in the rig frame (the bodies partition the ids).
  std::map<int, Eigen::Vector3d> shown;
  if (panel->current >= 0) {
    const Rigid3& rig_from_object = panel->input.trajectory[panel->current].rig_from_object;
    for (const MapMarker& m : panel->input.map.markers)
      shown[m.id] = (rig_from_object * m.object_from_marker).translation();
  }
  for (const Panel::Body& b : panel->bodies) {
    if (!b.is_static && b.current < 0) continue;
    const Rigid3 rig_from_object =
        b.is_static ? b.rig_from_object : panel->input.bodies.at(b.name)[b.current].rig_from_object;
    for (const MapMarker& m : panel->input.map.objects[b.object_index].markers)
      shown[m.id] = (rig_from_object * m.object_from_marker).translation();
  }
  for (const auto& [camera, ids] : detections_) {
    const MapCamera* cam = panel->input.map.FindCamera(camera);
    if (!cam) continue;
    for (int id : ids) {
      const auto m = shown.find(id);
      if (m == shown.end()) continue;
      panel->rays->appendLine(ToPoint(cam->rig_from_cam.translation()), ToPoint(m->second));
    }
  }
}

void VizScene::SetRaysVisible(bool visible) {
  options_.rays = visible;
  for (auto& p : panels_) p.rays->setVisibility(visible);
}

void VizScene::SetOverlay(const std::vector<std::string>& lines) {
  auto vp = scene_->getViewport(panels_.empty() ? std::string(kMainViewport) : panels_.back().viewport);
  mrpt::opengl::TFontParams font;
  font.vfont_scale = 7;
  font.color = mrpt::img::TColorf(0.9f, 0.95f, 1.0f, 1.0f);
  font.draw_shadow = true;
  for (size_t i = 0; i < std::max(lines.size(), overlay_.size()); ++i) {
    const std::string text = i < lines.size() ? lines[i] : std::string();
    vp->addTextMessage(8, -36.0 - 15.0 * static_cast<double>(i), text, 100 + i, font);
  }
  overlay_ = lines;
}

std::vector<Eigen::Vector3d> VizScene::FramingPoints() const {
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : panels_) {
    for (const auto& c : p.input.map.cameras) {
      // The camera and the end of its frustum's axis.
      pts.push_back(world_from_rig_ * c.rig_from_cam.translation());
      pts.push_back(world_from_rig_ * (c.rig_from_cam * Eigen::Vector3d(0, 0, frustum_length_)));
    }
    double reach = 0.0;
    for (const auto& m : p.input.map.markers)
      reach = std::max(reach, m.object_from_marker.translation().norm() + m.size);
    auto add_track = [&](const std::vector<TrajectoryRow>& rows, double r) {
      const size_t stride = std::max<size_t>(1, rows.size() / 2000);
      for (size_t i = 0; i < rows.size(); i += stride) {
        const Eigen::Vector3d c = world_from_rig_ * rows[i].rig_from_object.translation();
        pts.push_back(c);
        for (int k = 0; k < 3; ++k) {
          pts.push_back(c + r * Eigen::Vector3d::Unit(k));
          pts.push_back(c - r * Eigen::Vector3d::Unit(k));
        }
      }
    };
    add_track(p.input.trajectory, reach);
    for (const auto& o : p.input.map.objects) {  // the other bodies: their tracks, a static one's pose
      double r = 0.0;
      for (const auto& m : o.markers) r = std::max(r, m.object_from_marker.translation().norm() + m.size);
      if (o.is_static) {
        TrajectoryRow row;
        row.rig_from_object = o.rig_from_object;
        add_track({row}, r);
      } else if (p.input.bodies.count(o.name)) {
        add_track(p.input.bodies.at(o.name), r);
      }
    }
  }
  return pts;
}

void VizScene::AutoView() {
  ViewCamera v = views_.back();
  v.azimuth_deg = options_.azimuth_deg;
  v.elevation_deg = options_.elevation_deg;
  v.fov_deg = options_.fov_deg;
  const auto pts = FramingPoints();
  if (pts.empty()) {
    v.pointing = Eigen::Vector3d::Zero();
    v.distance = 3.0;
  } else {
    FramePoints(pts, 0.06, &v);
  }
  SetView(v);
}

void VizScene::FollowObject() {
  if (panels_.empty() || panels_.back().current < 0) return;
  ViewCamera v = views_.back();
  v.pointing =
      world_from_rig_ * panels_.back().input.trajectory[panels_.back().current].rig_from_object.translation();
  SetView(v);
}

void VizScene::FrameObject() {
  if (panels_.empty() || panels_.back().current < 0) return;
  const Panel& p = panels_.back();
  const Rigid3 world_from_object = world_from_rig_ * p.input.trajectory[p.current].rig_from_object;
  std::vector<Eigen::Vector3d> pts = {world_from_object.translation()};
  for (const auto& m : p.input.map.markers)
    for (const auto& corner : MarkerCornersInMarker(m.size))
      pts.push_back(world_from_object * (m.object_from_marker * corner));
  ViewCamera v = views_.back();
  FramePoints(pts, 0.15, &v);
  SetView(v);
}

void VizScene::SetView(const ViewCamera& view) {
  for (auto& v : views_) {
    v.pointing = view.pointing;
    v.azimuth_deg = view.azimuth_deg;
    v.elevation_deg = view.elevation_deg;
    v.distance = view.distance;
    v.fov_deg = view.fov_deg;
  }
}

void VizScene::Resize(int width, int height) {
  options_.width = width;
  options_.height = height;
  options_.Validate();
  UpdateViewports();
}

bool VizScene::ProjectRigPoint(int panel, const Eigen::Vector3d& p_rig, Eigen::Vector2d* pixel) const {
  return views_.at(panel).Project(world_from_rig_ * p_rig, pixel);
}

std::optional<Rigid3> VizScene::CurrentPose(int panel) const {
  const Panel& p = panels_.at(panel);
  if (p.current < 0) return std::nullopt;
  return p.input.trajectory[p.current].rig_from_object;
}

void VizScene::ApplyViews() {
  const int n = static_cast<int>(views_.size());
  for (int i = 0; i < n; ++i) {
    const std::string name = panels_.empty() ? std::string(kMainViewport) : panels_[i].viewport;
    views_[i].ApplyTo(&scene_->getViewport(name)->getCamera());
  }
}

cv::Mat VizScene::Render(mrpt::opengl::CFBORender* render) {
  ApplyViews();
  // CFBORender renders the main viewport through its own camera: the last panel's view.
  views_.back().ApplyTo(&render->getCamera(*scene_));
  mrpt::img::CImage image;
  render->render_RGB(*scene_, image);
  cv::Mat bgr = image.asCvMat<cv::Mat>(mrpt::img::DEEP_COPY);
  if (bgr.channels() == 1) cv::cvtColor(bgr, bgr, cv::COLOR_GRAY2BGR);
  if (options_.legend && has_residuals_ && !panels_.empty()) DrawLegend(&bgr);
  return bgr;
}

void VizScene::EnableLegendViewport() {
  legend_viewport_ = true;
  if (options_.legend && has_residuals_ && !panels_.empty() && !scene_->getViewport(kLegendViewport))
    BuildLegend();
}

void VizScene::DrawLegend(cv::Mat* bgr) const {
  // Offscreen, CFBORender renders every viewport through one camera, so the legend is drawn on
  // the image: a green -> red bar, its range and a caption, at the bottom right.
  const int bar_w = 200, bar_h = 12, margin = 12;
  const int x0 = bgr->cols - bar_w - margin - 40, y0 = bgr->rows - margin - 18 - bar_h;
  if (x0 < 0 || y0 < 20) return;
  for (int i = 0; i < bar_w; ++i) {
    const Eigen::Vector3d c = ResidualColor(residual_scale_ * i / (bar_w - 1), residual_scale_);
    cv::line(*bgr, {x0 + i, y0}, {x0 + i, y0 + bar_h - 1}, cv::Scalar(255 * c.z(), 255 * c.y(), 255 * c.x()));
  }
  cv::rectangle(*bgr, {x0 - 1, y0 - 1}, {x0 + bar_w, y0 + bar_h}, cv::Scalar(200, 200, 200));
  const cv::Scalar white(235, 235, 235);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(*bgr, "residual RMS (px)", {x0, y0 - 6}, font, 0.4, white, 1, cv::LINE_AA);
  cv::putText(*bgr, "0", {x0 - 3, y0 + bar_h + 14}, font, 0.4, white, 1, cv::LINE_AA);
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f", 0.25 * residual_scale_);  // green up to here
  cv::putText(*bgr, text, {x0 + bar_w / 4 - 12, y0 + bar_h + 14}, font, 0.4, white, 1, cv::LINE_AA);
  std::snprintf(text, sizeof(text), ">= %.2f", residual_scale_);
  cv::putText(*bgr, text, {x0 + bar_w - 30, y0 + bar_h + 14}, font, 0.4, white, 1, cv::LINE_AA);
}

}  // namespace mcmt::viz
