// The rig file's objects: list (core/objects.h): ids with ranges and `other`, sizes, static, rig_frame,
// and the one-line errors for ids claimed twice and other bad input.
#include <gtest/gtest.h>

#include "core/config.h"
#include "core/files.h"
#include "test_util.h"

namespace mcmt {
namespace {

using testing_util::Replace;
using testing_util::TempDir;

const char kIntrinsics[] = R"(image_width: 640
image_height: 480
camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}
distortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}
)";

const char kCameras[] = "cameras:\n  - {name: cam0, intrinsics: cam0.yml}\n";

const char kObjects[] = R"(markers: {dictionary: DICT_4X4_50, size: 0.05}
objects:
  - name: tool
    ids: [0, 1, 2, 3, "10-19"]
    size: 0.04
    sizes: {12: 0.03}
  - name: patient
    ids: ["20-22"]
  - name: room
    static: true
    ids: other
    size: 0.12
rig_frame: room
)";

RigConfig Load(const TempDir& dir, const std::string& text) {
  dir.Write("cam0.yml", kIntrinsics);
  return LoadRigConfig(dir.Write("rig.yaml", text + kCameras));
}

std::string Error(const std::string& text) {
  TempDir dir;
  try {
    Load(dir, text);
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.rfind(dir.File("rig.yaml"), 0), 0u) << "does not name the file: " << what;
    return what;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

TEST(Objects, IdsRangesOtherSizesStaticAndRigFrame) {
  TempDir dir;
  const ObjectsConfig o = Load(dir, kObjects).objects;
  ASSERT_EQ(o.objects.size(), 3u);
  EXPECT_TRUE(o.declared);
  EXPECT_EQ(o.objects[0].name, "tool");
  EXPECT_EQ(DescribeIds(o.objects[0].ids), "0-3, 10-19");
  EXPECT_EQ(o.objects[0].sizes.Get(12), 0.03);
  EXPECT_EQ(o.objects[0].sizes.Get(13), 0.04);
  EXPECT_EQ(o.objects[1].sizes.Get(21), 0.05);  // markers.size
  EXPECT_FALSE(o.objects[1].is_static);
  EXPECT_TRUE(o.objects[2].is_static);
  EXPECT_TRUE(o.objects[2].other);
  EXPECT_EQ(o.objects[2].sizes.Get(40), 0.12);
  EXPECT_EQ(o.ObjectOf(15), 0);
  EXPECT_EQ(o.ObjectOf(22), 1);
  EXPECT_EQ(o.ObjectOf(9), 2);  // claimed by nobody: other
  EXPECT_EQ(o.rig_frame, "room");
  EXPECT_EQ(ChannelSuffix("tool_2"), "TOOL_2");
}

// objects: auto (one unnamed object whose ids the mapper finds) and an object with ids: auto.
TEST(Objects, AutoLeavesTheGroupingToTheMapper) {
  TempDir dir;
  const ObjectsConfig all = Load(dir, "markers: {size: 0.04}\nobjects: auto\n").objects;
  EXPECT_TRUE(all.declared);
  EXPECT_TRUE(all.auto_objects);
  ASSERT_EQ(all.objects.size(), 1u);
  EXPECT_TRUE(all.objects[0].auto_ids);
  EXPECT_TRUE(all.objects[0].name.empty());
  EXPECT_EQ(all.ObjectOf(7), -1);
  const ObjectsConfig some = Load(dir, Replace(kObjects, "ids: other", "ids: auto")).objects;
  EXPECT_FALSE(some.auto_objects);
  EXPECT_TRUE(some.objects[2].auto_ids);
  EXPECT_FALSE(some.objects[2].other);
  EXPECT_TRUE(some.objects[2].ids.empty());
  EXPECT_EQ(some.ObjectOf(9), -1);  // an auto object claims nothing
  EXPECT_EQ(some.rig_frame, "room");
}

TEST(Objects, MarkersAloneAreOneObjectNamedByTracker) {
  TempDir dir;
  const ObjectsConfig a = Load(dir, "markers: {size: 0.04, ids: [1, 2], sizes: {2: 0.03}}\n").objects;
  ASSERT_EQ(a.objects.size(), 1u);
  EXPECT_FALSE(a.declared);
  EXPECT_EQ(a.objects[0].name, "object");
  EXPECT_EQ(a.ObjectOf(2), 0);
  EXPECT_EQ(a.ObjectOf(3), -1);
  EXPECT_EQ(a.objects[0].sizes.Get(2), 0.03);
  const ObjectsConfig b = Load(dir, "markers: {size: 0.04}\ntracker: {object: wand}\n").objects;
  EXPECT_EQ(b.objects[0].name, "wand");
  EXPECT_TRUE(b.objects[0].other);
  EXPECT_EQ(b.ObjectOf(49), 0);
}

TEST(Objects, BadInputNamesFileKeyIdAndObjects) {
  EXPECT_CONTAINS(Error(Replace(kObjects, "[\"20-22\"]", "[\"18-22\"]")),
                  "rig.yaml: objects[1].ids: marker id 18 is claimed by both 'tool' and 'patient'");
  EXPECT_CONTAINS(Error(Replace(kObjects, "[\"20-22\"]", "other")),
                  "objects[2].ids: 'other' is claimed by both 'patient' and 'room'");
  EXPECT_CONTAINS(Error(Replace(kObjects, "name: patient", "name: tool")),
                  "objects[1].name: object name 'tool' is used twice");
  EXPECT_CONTAINS(Error(Replace(kObjects, "name: patient", "name: pa-tient")),
                  "objects[1].name: 'pa-tient' is not a valid");
  EXPECT_CONTAINS(Error(Replace(kObjects, "[\"20-22\"]", "[\"22-20\"]")),
                  "objects[1].ids: item 0: empty range '22-20'");
  EXPECT_CONTAINS(Error(Replace(kObjects, "[\"20-22\"]", "[\"20-x\"]")),
                  "objects[1].ids: item 0: expected a range");
  EXPECT_CONTAINS(Error(Replace(kObjects, "[\"20-22\"]", "[\"20-60\"]")),
                  "objects[1].ids: marker id 60 is not in the dictionary");
  EXPECT_CONTAINS(Error(Replace(kObjects, "[\"20-22\"]", "[20, 20]")),
                  "objects[1].ids: marker id 20 is listed twice");
  EXPECT_CONTAINS(Error(Replace(kObjects, "{12: 0.03}", "{30: 0.03}")),
                  "objects[0].sizes.30: marker id 30 is not one of 'tool'");
  EXPECT_CONTAINS(Error(Replace(kObjects, "rig_frame: room", "rig_frame: tool")),
                  "rig.yaml: rig_frame: object 'tool' is not static");
  EXPECT_CONTAINS(Error(Replace(kObjects, "rig_frame: room", "rig_frame: wall")),
                  "rig_frame: no object named 'wall'");
  EXPECT_CONTAINS(Error(Replace(kObjects, "static: true", "statc: true")), "objects[2].statc: unknown key");
  EXPECT_CONTAINS(Error(Replace(Replace(kObjects, ", size: 0.05", ""), "    size: 0.12\n", "")),
                  "objects[1].size: missing (and no markers.size");
  EXPECT_CONTAINS(Error("markers: {size: 0.04}\nobjects: auto\nrig_frame: room\n"),
                  "rig_frame: needs a static object of that name: with objects: auto");
  EXPECT_CONTAINS(Error("markers: {size: 0.04, ids: [1]}\nobjects: auto\n"),
                  "markers.ids and objects: auto exclude each other");
  EXPECT_CONTAINS(Error("markers: {size: 0.04}\nobjects: []\n"), "objects: expected a non-empty list");
  EXPECT_CONTAINS(Error("markers: {size: 0.04, ids: [1]}\nobjects: [{name: a, ids: [1]}]\n"),
                  "objects: markers.ids and objects: exclude each other");
  EXPECT_CONTAINS(Error("markers: {size: 0.04}\nrig_frame: room\n"), "rig_frame: needs an objects: list");
}

}  // namespace
}  // namespace mcmt

namespace mcmt {
namespace {

RigMap TwoBodyMap() {
  RigMap map;
  map.dictionary = "DICT_6X6_250";
  map.reference_camera = "cam0";
  MapCamera cam;
  cam.name = "cam0";
  cam.model = CameraModel::Pinhole(640, 480, 500, 320, 240);
  cam.rig_from_cam.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
  map.cameras.push_back(cam);
  MapObject tool, floor;
  tool.name = "tool";
  tool.reference_marker = 1;
  tool.markers.push_back({1, 0.04, Rigid3::Identity(), 10, 0.2, 0.5});
  tool.markers.push_back({2, 0.04, Rigid3(Eigen::Translation3d(0.05, 0, 0)), 8, 0.3, 0.6});
  floor.name = "floor";
  floor.is_static = true;
  floor.reference_marker = 20;
  floor.rig_from_object = Rigid3(Eigen::Translation3d(0, 0, -0.25));
  floor.markers.push_back({20, 0.08, Rigid3::Identity(), 30, 0.1, 0.2});
  map.objects = {tool, floor};
  map.rig_frame = "floor";
  return map;
}

TEST(Objects, MapVersion2RoundTripsAndNamesBadObjects) {
  TempDir dir;
  const RigMap map = TwoBodyMap();
  WriteMap(dir.File("map.yaml"), map);
  const std::string text = ReadFile(dir.File("map.yaml"));
  EXPECT_CONTAINS(text, "version: 2\n");
  const RigMap back = ReadMap(dir.File("map.yaml"));
  ASSERT_EQ(back.objects.size(), 2u);
  EXPECT_EQ(back.rig_frame, "floor");
  EXPECT_EQ(back.objects[1].name, "floor");
  EXPECT_TRUE(back.objects[1].is_static);
  EXPECT_EQ(back.objects[1].rig_from_object.translation().z(), -0.25);
  EXPECT_EQ(back.objects[0].markers[1].object_from_marker.translation().x(), 0.05);
  EXPECT_EQ(back.markers.size(), 2u);  // the first body's, for single-object readers
  EXPECT_EQ(back.reference_marker, 1);
  const RigMap floor_alone = back.ObjectMap(1);
  EXPECT_EQ(floor_alone.version, kMapVersion);
  EXPECT_TRUE(floor_alone.objects.empty());
  EXPECT_EQ(floor_alone.reference_marker, 20);
  // A version 1 map (no objects) is still written and read as before.
  WriteMap(dir.File("v1.yaml"), floor_alone);
  EXPECT_CONTAINS(ReadFile(dir.File("v1.yaml")), "version: 1\n");
  EXPECT_TRUE(ReadMap(dir.File("v1.yaml")).objects.empty());
  // Bad version 2 maps name the key.
  auto error = [&](const std::string& from, const std::string& to) {
    dir.Write("bad.yaml", Replace(text, from, to));
    try {
      ReadMap(dir.File("bad.yaml"));
    } catch (const FileFormatError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_CONTAINS(error("  - id: 20", "  - id: 2"),
                  "objects[1].markers: marker id 2 is in both 'tool' and 'floor'");
  EXPECT_CONTAINS(error("name: \"floor\"", "name: \"tool\""), "objects[1].name: duplicated object 'tool'");
  EXPECT_CONTAINS(error("rig_frame: \"floor\"", "rig_frame: \"wall\""), "rig_frame: no object named 'wall'");
  EXPECT_CONTAINS(error("static: true", "static: maybe"), "objects[1].static: expected true or false");
}

}  // namespace
}  // namespace mcmt
