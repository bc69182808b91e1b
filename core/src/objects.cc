#include "core/objects.h"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cmath>
#include <map>

#include "core/config.h"
#include "core/lcm_util.h"

namespace mcmt {
namespace {

constexpr double kMaxMarkerSize_m = 10.0;

std::string NodeText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  return node.IsSequence() ? "a list" : node.IsMap() ? "a mapping" : "nothing";
}

bool ValidName(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

// An id must be in the dictionary.
void CheckId(const YamlSection& s, const std::string& key, int id, int dictionary_size) {
  if (id < 0) s.Fail(key, "marker ids must be non-negative, got " + std::to_string(id));
  if (dictionary_size >= 0 && id >= dictionary_size)
    s.Fail(key, "marker id " + std::to_string(id) + " is not in the dictionary (ids 0-" +
                    std::to_string(dictionary_size - 1) + ")");
}

// One item of `ids:`: an integer or an inclusive range "A-B".
void AddIdItem(const YamlSection& s, const YAML::Node& item, size_t index, int dictionary_size,
               std::set<int>* ids) {
  const std::string where = "item " + std::to_string(index) + ": ";
  if (!item.IsScalar()) s.Fail("ids", where + "expected an id or a range \"A-B\", got " + NodeText(item));
  int first = 0, last = 0;
  const std::string text = item.Scalar();
  const size_t dash = text.find('-', 1);
  if (dash == std::string::npos) {
    if (!YAML::convert<int>::decode(item, first))
      s.Fail("ids", where + "expected an id or a range \"A-B\", got '" + text + "'");
    last = first;
  } else {
    try {
      size_t end_a = 0, end_b = 0;
      first = std::stoi(text.substr(0, dash), &end_a);
      last = std::stoi(text.substr(dash + 1), &end_b);
      if (end_a != dash || end_b != text.size() - dash - 1) throw std::invalid_argument(text);
    } catch (const std::exception&) {
      s.Fail("ids", where + "expected a range \"A-B\" of ids, got '" + text + "'");
    }
    if (last < first) s.Fail("ids", where + "empty range '" + text + "' (A-B needs A <= B)");
  }
  CheckId(s, "ids", first, dictionary_size);
  CheckId(s, "ids", last, dictionary_size);
  for (int id = first; id <= last; ++id)
    if (!ids->insert(id).second) s.Fail("ids", "marker id " + std::to_string(id) + " is listed twice");
}

double ReadSize(const YamlSection& s, const std::string& key, const YAML::Node& node) {
  double v = 0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || !(v > 0) || !std::isfinite(v))
    s.Fail(key, "expected a positive number, got '" + NodeText(node) + "'");
  if (v > kMaxMarkerSize_m) s.Fail(key, "absurd marker side length " + node.Scalar() + " m (at most 10 m)");
  return v;
}

// One entry of the list (its ids not yet checked against the other objects').
ObjectConfig ParseObject(const YamlSection& s, double markers_size, const MarkerSizes& markers_sizes,
                         int dictionary_size) {
  s.CheckKnownKeys({"name", "ids", "size", "sizes", "static"});
  ObjectConfig object;
  object.name = s.RequireString("name");
  if (!ValidName(object.name))
    s.Fail("name", "'" + object.name + "' is not a valid object name (letters, digits and _ only)");
  if (!s.Has("ids")) s.Fail("ids", "missing (a list of ids and ranges \"A-B\", other or auto)");
  const YAML::Node ids = s.node()["ids"];
  if (ids.IsScalar() && ids.Scalar() == "other") {
    object.other = true;
  } else if (ids.IsScalar() && ids.Scalar() == "auto") {
    object.auto_ids = true;
  } else if (ids.IsSequence() && ids.size() > 0) {
    for (size_t i = 0; i < ids.size(); ++i) AddIdItem(s, ids[i], i, dictionary_size, &object.ids);
  } else {
    s.Fail("ids",
           "expected a non-empty list of ids and ranges \"A-B\", other or auto, got '" + NodeText(ids) + "'");
  }
  object.is_static = s.GetBool("static", false);
  object.sizes = markers_sizes;
  object.sizes.default_size = s.Has("size") ? ReadSize(s, "size", s.node()["size"]) : markers_size;
  if (!(object.sizes.default_size > 0)) s.Fail("size", "missing (and no markers.size to default to)");
  if (s.Has("sizes")) {
    const YAML::Node sizes = s.node()["sizes"];
    if (!sizes.IsMap()) s.Fail("sizes", "expected a mapping id: size, got '" + NodeText(sizes) + "'");
    for (auto it = sizes.begin(); it != sizes.end(); ++it) {
      int id = -1;
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : "?";
      if (!it->first.IsScalar() || !YAML::convert<int>::decode(it->first, id) || id < 0)
        s.Fail("sizes", "expected a non-negative marker id as key, got '" + key + "'");
      if (!object.other && !object.auto_ids && !object.ids.count(id))
        s.Fail("sizes." + key, "marker id " + key + " is not one of '" + object.name + "' ids");
      object.sizes.overrides[id] = ReadSize(s, "sizes." + key, it->second);
    }
  }
  return object;
}

// The object without `objects:`: markers.ids (or every id), named `single_name`.
ObjectsConfig SingleObject(double markers_size, const MarkerSizes& sizes, const std::vector<int>& ids,
                           const std::string& single_name) {
  ObjectsConfig out;
  ObjectConfig object;
  object.name = single_name;
  object.ids.insert(ids.begin(), ids.end());
  object.other = ids.empty();
  object.sizes = sizes;
  object.sizes.default_size = markers_size;
  out.objects.push_back(object);
  return out;
}

}  // namespace

int ObjectsConfig::ObjectOf(int id) const {
  int other = -1;
  for (size_t k = 0; k < objects.size(); ++k) {
    if (objects[k].ids.count(id)) return static_cast<int>(k);
    if (objects[k].other) other = static_cast<int>(k);
  }
  return other;
}

int ObjectsConfig::Find(const std::string& name) const {
  for (size_t k = 0; k < objects.size(); ++k)
    if (objects[k].name == name) return static_cast<int>(k);
  return -1;
}

ObjectsConfig ParseObjects(const YamlSection& top, double markers_size, const MarkerSizes& markers_sizes,
                           const std::vector<int>& markers_ids, const std::string& single_name,
                           int dictionary_size) {
  if (!top.Has("objects")) {
    if (top.Has("rig_frame"))
      top.Fail("rig_frame", "needs an objects: list with a static object of that name");
    return SingleObject(markers_size, markers_sizes, markers_ids, single_name);
  }
  const YAML::Node list = top.node()["objects"];
  if (list.IsScalar() && list.Scalar() == "auto") {
    if (!markers_ids.empty())
      top.Fail("objects", "markers.ids and objects: auto exclude each other (auto groups every id seen)");
    if (top.Has("rig_frame"))
      top.Fail("rig_frame",
               "needs a static object of that name: with objects: auto the bodies have no "
               "names yet (declare the static one with ids: auto)");
    ObjectsConfig out = SingleObject(markers_size, markers_sizes, {}, "");
    out.declared = true;
    out.auto_objects = true;
    out.objects[0].other = false;
    out.objects[0].auto_ids = true;
    if (!(markers_size > 0)) top.Fail("objects", "auto needs markers.size (the side of the markers)");
    return out;
  }
  if (!list.IsSequence() || list.size() == 0)
    top.Fail("objects", "expected a non-empty list of objects (name, ids, size, static)");
  if (!markers_ids.empty())
    top.Fail("objects", "markers.ids and objects: exclude each other (ids per object)");
  ObjectsConfig out;
  out.declared = true;
  std::map<int, size_t> claimed;  // id -> object index
  int other = -1;
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string prefix = "objects[" + std::to_string(k) + "]";
    if (!list[k].IsMap())
      throw ConfigError(top.file() + ": " + prefix + ": expected a mapping with name and ids, got '" +
                        NodeText(list[k]) + "'");
    const YamlSection entry(list[k], top.file(), prefix);
    ObjectConfig object = ParseObject(entry, markers_size, markers_sizes, dictionary_size);
    if (out.Find(object.name) >= 0) entry.Fail("name", "object name '" + object.name + "' is used twice");
    if (object.other) {
      if (other >= 0)
        entry.Fail("ids", "'other' is claimed by both '" + out.objects[other].name + "' and '" + object.name +
                              "' (at most one object holds every unclaimed id)");
      other = static_cast<int>(k);
    }
    for (int id : object.ids) {
      const auto [it, inserted] = claimed.emplace(id, k);
      if (!inserted)
        entry.Fail("ids", "marker id " + std::to_string(id) + " is claimed by both '" +
                              out.objects[it->second].name + "' and '" + object.name + "'");
    }
    out.objects.push_back(std::move(object));
  }
  out.rig_frame = top.GetString("rig_frame", "");
  if (!out.rig_frame.empty()) {
    const int k = out.Find(out.rig_frame);
    if (k < 0) top.Fail("rig_frame", "no object named '" + out.rig_frame + "'");
    if (!out.objects[k].is_static)
      top.Fail("rig_frame",
               "object '" + out.rig_frame + "' is not static (static: true): it cannot be the rig frame");
  }
  return out;
}

std::string DescribeIds(const std::set<int>& ids) {
  std::string out;
  for (auto it = ids.begin(); it != ids.end();) {
    const int first = *it;
    int last = first;
    for (++it; it != ids.end() && *it == last + 1; ++it) last = *it;
    out +=
        (out.empty() ? "" : ", ") + std::to_string(first) + (last > first ? "-" + std::to_string(last) : "");
  }
  return out;
}

std::string ChannelSuffix(const std::string& object_name) {
  std::string out = object_name;
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

std::string BodyOfPoseChannel(const std::string& channel, const std::string& object) {
  static const std::string kPrefix = std::string(kPoseChannel) + "_";
  if (channel.size() <= kPrefix.size() || channel.compare(0, kPrefix.size(), kPrefix) != 0) return "";
  const std::string suffix = channel.substr(kPrefix.size());
  if (!object.empty() && ChannelSuffix(object) == suffix) return object;
  std::string out = suffix;
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string BodyOfPose(const std::string& channel, const std::string& object) {
  const std::string by_channel = BodyOfPoseChannel(channel, object);
  return by_channel.empty() ? object : by_channel;
}

}  // namespace mcmt
