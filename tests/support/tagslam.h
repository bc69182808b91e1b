// TagSLAM's own results for the sessions of ../shared/data/tagslam_test (reference.bag, /tf), for the
// tests that compare mcmt against them (tests/import, tests/mapper). Links mcmt_import (the bag reader).
#pragma once

#include <array>
#include <map>
#include <string>

#include "core/se3.h"
#include "import/rosbag.h"

namespace mcmt::test {

// The last rig->camN (rig_from_cam) and perch->tag_N (perch_from_tag) of the session
// (geometry_msgs/Transform: translation, then rotation as x, y, z, w).
struct TagslamResult {
  std::map<std::string, Rigid3> rig_from_cam;
  std::map<int, Rigid3> perch_from_tag;
};

inline TagslamResult ReadTagslam(const std::string& reference_bag) {
  const RosBag bag = RosBag::Open(reference_bag);
  TagslamResult out;
  for (const BagMessage& m : bag.messages()) {
    if (bag.Connection(m.connection).topic != "/tf") continue;
    const RosValue tf = bag.Decode(m);  // (a temporary's member would dangle in the range-for)
    for (const RosValue& t : tf.At("transforms").items) {
      const std::string parent = t.At("header.frame_id").text, child = t.At("child_frame_id").text;
      const RosValue& tr = t.At("transform");
      const Eigen::Vector3d p(tr.At("translation.x").AsDouble(), tr.At("translation.y").AsDouble(),
                              tr.At("translation.z").AsDouble());
      const std::array<double, 4> wxyz = {tr.At("rotation.w").AsDouble(), tr.At("rotation.x").AsDouble(),
                                          tr.At("rotation.y").AsDouble(), tr.At("rotation.z").AsDouble()};
      if (parent == "rig") out.rig_from_cam[child] = RigidFromQuaternion(wxyz, p);
      if (parent == "perch" && child.rfind("tag_", 0) == 0)
        out.perch_from_tag[std::stoi(child.substr(4))] = RigidFromQuaternion(wxyz, p);
    }
  }
  return out;
}

}  // namespace mcmt::test
