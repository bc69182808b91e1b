// One camera's view of an mcmt-sim session (its rig, object and pose) drawn by the independent reference
// renderer (tests/detector/reference_renderer.h) instead of mcmt-sim's: the body's faces and each
// marker's print (margin, black square, white cells) as quadrilaterals under the camera's homography of
// their plane, point-sampled in linear light, then the reference camera pipeline of one imaging condition.
// Only the scene's geometry (camera poses and intrinsics, the body, the markers' poses) comes from sim;
// none of its drawing does. So the maps of bench_imaging_maps (MCMT_IMAGING_RENDERER=reference) and of
// MapperReferenceRenders do not rest on the renderer the detector was built with.
//   - Pinhole cameras only (the homographies are exact there); a camera with distortion throws.
//   - The body is convex: faces turned away are not drawn, and what is drawn does not overlap.
//   - A face's light: 1 - face_shading * (1 - cos) / 2 of its normal to a fixed light direction in the rig;
//     the print on it shares it. The face's reflectance is the condition's surface (its grain too).
#pragma once

#include <opencv2/aruco.hpp>
#include <random>
#include <stdexcept>
#include <vector>

#include "sim/sim.h"
#include "tests/detector/reference_renderer.h"

namespace mcmt::testing {

namespace reference {

// image_from_plane of a plane through `origin` spanned by `u_axis`, `v_axis` (camera frame, metres per
// plane unit), for a pinhole camera.
inline cv::Matx33d ImageFromPlane(const CameraModel& model, const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& u_axis, const Eigen::Vector3d& v_axis) {
  const cv::Matx33d K(model.fx, 0, model.cx, 0, model.fy, model.cy, 0, 0, 1);
  const cv::Matx33d cam_from_plane(u_axis.x(), v_axis.x(), origin.x(), u_axis.y(), v_axis.y(), origin.y(),
                                   u_axis.z(), v_axis.z(), origin.z());
  return K * cam_from_plane;
}

// The pixel box (inside the image, one pixel of room) of points seen through image_from_plane; empty
// when outside.
inline cv::Rect PaintBox(const std::vector<cv::Point2d>& points, const CameraModel& model) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const cv::Point2d& p : points)
    x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
  const cv::Rect box(cv::Point(static_cast<int>(std::floor(x0)) - 1, static_cast<int>(std::floor(y0)) - 1),
                     cv::Point(static_cast<int>(std::ceil(x1)) + 2, static_cast<int>(std::ceil(y1)) + 2));
  return box & cv::Rect(0, 0, model.width, model.height);
}

}  // namespace reference

inline cv::Mat RenderReferenceRigView(const cv::aruco::Dictionary& dict, const sim::SimObject& object,
                                      const sim::SimCamera& camera, const Rigid3& rig_from_object,
                                      const Imaging& im, uint64_t seed) {
  using reference::Apply;
  const CameraModel& model = camera.model;
  if (model.model != DistortionModel::kNone)
    throw std::invalid_argument("RenderReferenceRigView: camera " + camera.name + " has distortion");
  std::mt19937_64 rng(seed);
  cv::Mat linear = reference::Clutter(model.width, model.height, im, rng);
  const Rigid3 cam_from_object = camera.rig_from_cam.inverse() * rig_from_object;
  const Eigen::Vector3d light_in_rig = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const int cells = dict.markerSize + 2;
  // The faces turned towards the camera: their normals, first vertices and light; all their quads are
  // painted in one call, so that a pixel on the edge between two faces is their samples' mean (faces
  // painted one by one let the background's level into that pixel: mcmt-sim's exact render of the same
  // views differed there by -6.4 gray levels on average, up to 27, on a 200-level ink-paper step,
  // bench/sim/diag_render_compare.cc).
  struct SeenFace {
    Eigen::Vector3d normal, v0;
    double light;
  };
  std::vector<SeenFace> seen;
  std::vector<cv::Matx33d> face_planes;
  face_planes.reserve(object.faces.size());
  std::vector<reference::Quad> face_quads;
  std::vector<cv::Point2d> face_corners;
  for (const sim::SimFace& face : object.faces) {
    std::vector<Eigen::Vector3d> v;
    for (const Eigen::Vector3d& p : face.vertices) v.push_back(cam_from_object * p);
    if (v.size() < 3) continue;
    const Eigen::Vector3d normal = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
    if (normal.dot(v[0]) >= 0) continue;  // turned away
    const Eigen::Vector3d normal_in_rig = camera.rig_from_cam.linear() * normal;
    const double light = 1.0 - im.face_shading * 0.5 * (1.0 - normal_in_rig.dot(light_in_rig));
    seen.push_back({normal, v[0], light});
    // The face's plane in cells of the object's first marker (grain coordinates), the fan of its polygon.
    const double cell_m = object.markers.empty() ? 0.005 : object.markers[0].size / cells;
    const Eigen::Vector3d u_axis = (v[1] - v[0]).normalized() * cell_m, v_axis = normal.cross(u_axis);
    face_planes.push_back(reference::ImageFromPlane(model, v[0], u_axis, v_axis).inv());
    std::vector<cv::Point2d> corners;
    for (const Eigen::Vector3d& p : v)
      corners.push_back({model.fx * p.x() / p.z() + model.cx, model.fy * p.y() / p.z() + model.cy});
    for (size_t k = 1; k + 1 < corners.size(); k += 2) {
      reference::Quad q;
      q.p = {corners[0], corners[k], corners[k + 1], corners[std::min(k + 2, corners.size() - 1)]};
      q.level = im.surface * light * im.exposure, q.grain = im.surface_texture;
      q.plane_from_image = &face_planes.back();
      face_quads.push_back(q);
    }
    face_corners.insert(face_corners.end(), corners.begin(), corners.end());
  }
  const cv::Rect faces_box = reference::PaintBox(face_corners, model);
  if (faces_box.area() > 0 && !face_quads.empty())
    reference::Paint(face_quads, faces_box, face_planes.front(), &linear);
  for (const SeenFace& face : seen) {
    // The prints on this face: (0, 0) of a marker's plane is its top-left corner (-s/2, s/2), v downward.
    for (const sim::SimMarker& m : object.markers) {
      const Rigid3 cam_from_marker = cam_from_object * m.object_from_marker;
      if (cam_from_marker.linear().col(2).dot(face.normal) < 0.999) continue;
      if (std::abs(face.normal.dot(cam_from_marker.translation() - face.v0)) > 1e-4) continue;
      const double c = m.size / cells;
      const Eigen::Vector3d origin = cam_from_marker * Eigen::Vector3d(-m.size / 2, m.size / 2, 0);
      const cv::Matx33d image_from_plane = reference::ImageFromPlane(
          model, origin, cam_from_marker.linear().col(0) * c, -cam_from_marker.linear().col(1) * c);
      const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(dict.bytesList.rowRange(m.id, m.id + 1),
                                                                      dict.markerSize);
      const double e = im.margin_cells;
      std::vector<cv::Point2d> extent;
      for (double x : {-e, cells + e})
        for (double y : {-e, cells + e}) extent.push_back(Apply(image_from_plane, x, y));
      const cv::Rect box = reference::PaintBox(extent, model);
      if (box.area() > 0)
        reference::Paint(reference::MarkerQuads(bits, cells, image_from_plane, im, face.light, false), box,
                         image_from_plane.inv(), &linear);
    }
  }
  return reference::CameraPipeline(linear, im, rng);
}

}  // namespace mcmt::testing
