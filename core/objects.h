// The rigid bodies of a rig: the `objects:` list of the rig YAML partitions the marker ids into named
// bodies (a tool, a patient's reference frame, markers fixed to the room).
//
//   objects:
//     - name: tool                 # [A-Za-z0-9_], unique: used in channel names, files and messages
//       ids: [0, 1, 2, 3, "10-19"] # ids and inclusive ranges
//       size: 0.04                 # default side of its markers (default: markers.size)
//       sizes: {12: 0.03}          # per-id overrides
//     - name: room
//       static: true               # fixed to the cameras: one pose for the whole session
//       ids: other                 # every id no other object claims (at most one object)
//   rig_frame: room                # optional: this static body's frame is the rig frame
//
// `ids: auto` (an object) or `objects: auto` (the whole list) leave the grouping of the ids no object
// claims into rigid bodies to the mapper (mapper/bodies_auto.h): an `ids: auto` object takes the largest
// body found of its kind (static or moving); `objects: auto` is one such object with no name (every body
// found is named by the mapper: static_1, body_1, ...). The bodies found are in the map's objects.
//
// A rig with only `markers:` is one object named `tracker.object` (default "object") holding
// markers.ids (none: every id), exactly as before. Errors are ConfigError naming the file and key, e.g.
//   "rig.yaml: objects[1].ids: marker id 12 is claimed by both 'tool' and 'patient'".
#pragma once

#include <set>
#include <string>
#include <vector>

#include "core/marker.h"

namespace YAML {
class Node;
}

namespace mcmt {

class YamlSection;

struct ObjectConfig {
  std::string name;
  std::set<int> ids;       // the ids it claims (ranges expanded); empty with `other`
  bool other = false;      // ids: other (every id no other object claims)
  bool auto_ids = false;   // ids: auto (found by the mapper); claims no id here
  bool is_static = false;  // static: true
  MarkerSizes sizes;       // default side and per-id overrides
};

struct ObjectsConfig {
  std::vector<ObjectConfig> objects;  // never empty after loading
  bool declared = false;              // an `objects:` list was given (false: the single markers: object)
  bool auto_objects = false;          // objects: auto (objects holds one unnamed auto_ids object)
  std::string rig_frame;              // a static object's name, or empty (the reference camera)

  // Index of the object that holds `id` (explicit ids first, then the `other` object); -1: none.
  int ObjectOf(int id) const;
  int Find(const std::string& name) const;  // -1 when absent
  bool Single() const { return objects.size() == 1; }
};

// Parses `objects:` and `rig_frame:` of the rig's top level. `markers_size` is markers.size (<= 0:
// absent), `markers_sizes` markers.sizes, `markers_ids` markers.ids, `single_name` the name of the one
// object of a rig without `objects:`. `dictionary_size` (< 0: unknown) bounds the ids.
ObjectsConfig ParseObjects(const YamlSection& top, double markers_size, const MarkerSizes& markers_sizes,
                           const std::vector<int>& markers_ids, const std::string& single_name,
                           int dictionary_size);

// "0-3, 7, 10-19" (consecutive ids joined as ranges).
std::string DescribeIds(const std::set<int>& ids);

// An object name as it appears in channel names: upper-cased ("tool" -> "TOOL").
std::string ChannelSuffix(const std::string& object_name);

// The body whose poses a channel carries, for readers of every MCMT_POSE* channel (viewer, exporter,
// mcmt-eval): "" for MCMT_POSE itself (a single-object rig) and for a channel not starting with
// "MCMT_POSE_"; else the message's object field when the channel is MCMT_POSE_<ChannelSuffix(object)>,
// and otherwise the channel's suffix lower-cased ("MCMT_POSE_TOOL_IN_PATIENT" -> "tool_in_patient").
std::string BodyOfPoseChannel(const std::string& channel, const std::string& object);
// The body of a pose stream's object_pose_t: BodyOfPoseChannel on an MCMT_POSE_<X> channel, else (a
// stream renamed by tracker.channels: "NAV") the message's object field, the tracker's stream name.
std::string BodyOfPose(const std::string& channel, const std::string& object);

}  // namespace mcmt
