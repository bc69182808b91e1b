// mcmt-import: ROS bags of AprilTag detections and det.csv -> mcmt session folders.
#include "import/import.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <sstream>

#include "core/config.h"
#include "core/detections_csv.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_writer.h"

namespace mcmt {
namespace fs = std::filesystem;
namespace {

constexpr char kAprilTagArrayType[] = "apriltag_msgs/ApriltagArrayStamped";

// The session folder, written under a temporary sibling name and renamed when complete.
class SessionFolder {
 public:
  explicit SessionFolder(const std::string& out) : out_(fs::absolute(out).lexically_normal().string()) {
    while (out_.size() > 1 && out_.back() == '/') out_.pop_back();
    for (const char* f : {"session.lcmlog", "rig.yaml"})
      if (fs::exists(out_ + "/" + f))
        throw ImportError(out_ + "/" + f + ": exists; refusing to overwrite (choose another --out)");
    if (fs::exists(out_) && !fs::is_directory(out_)) throw ImportError(out_ + ": exists and is not a folder");
    tmp_ = out_ + ".tmp." + std::to_string(::getpid());
    fs::remove_all(tmp_);
    fs::create_directories(tmp_);
  }
  ~SessionFolder() {
    std::error_code ec;
    if (!committed_) fs::remove_all(tmp_, ec);
  }
  std::string Path(const std::string& name) const { return tmp_ + "/" + name; }
  void Commit() {
    if (fs::exists(out_)) {  // an existing folder without a session: move the files in
      for (const auto& e : fs::directory_iterator(tmp_)) fs::rename(e.path(), out_ / e.path().filename());
      fs::remove(tmp_);
    } else {
      fs::rename(tmp_, out_);
    }
    committed_ = true;
  }
  const std::string& out() const { return out_; }

 private:
  std::string out_, tmp_;
  bool committed_ = false;
};

// The bag's connection for each camera, checked: present, of the one type we read, fields where we
// expect them. Unknown types and topics are listed, not guessed.
const BagConnection& CameraConnection(const RosBag& bag, const KalibrCamera& cam,
                                      const std::string& cameras) {
  const BagConnection* c = bag.FindTopic(cam.topic);
  if (!c)
    throw ImportError(bag.path() + ": no topic " + cam.topic + " (" + cameras + ": " + cam.name +
                      ".tagtopic); topics found: " + bag.TopicList());
  if (c->type != kAprilTagArrayType)
    throw ImportError(bag.path() + ": topic " + cam.topic + " (" + cam.name + ") has type " + c->type +
                      ", which mcmt-import does not read (it reads " + kAprilTagArrayType +
                      "); topics found: " + bag.TopicList());
  const RosSchema schema(c->type, c->definition);
  const RosMessageType& top = schema.Get(c->type);
  auto field = [&](const RosMessageType& t, const std::string& name) -> const RosField& {
    for (const RosField& f : t.fields)
      if (f.name == name) return f;
    throw ImportError(bag.path() + ": topic " + cam.topic + ": " + t.name + " has no field '" + name +
                      "' in its message_definition");
  };
  field(schema.Get(field(top, "header").type), "stamp");
  const RosField& tags = field(top, "apriltags");
  const RosMessageType& tag = schema.Get(tags.type);
  field(tag, "id");
  const RosField& corners = field(tag, "corners");
  if (corners.array_size != 4)
    throw ImportError(bag.path() + ": topic " + cam.topic + ": " + tag.name + ".corners is not a [4] array");
  return *c;
}

struct StampedDetections {
  int64_t stamp_ns = 0;
  size_t camera = 0;
  detections_t msg;
};

detections_t ToDetections(const RosValue& v, const KalibrCamera& cam, std::set<std::string>* families) {
  detections_t d;
  d.camera = cam.name;
  d.camera_model = ToCameraModelMsg(cam.model);
  d.detection_ms = 0.0;
  for (const RosValue& t : v.At("apriltags").items) {
    marker_t m;
    m.id = static_cast<int32_t>(t.At("id").AsInt());
    if (const RosValue* f = t.Find("family")) families->insert(f->text);
    const std::vector<RosValue>& c = t.At("corners").items;
    for (int i = 0; i < 4; ++i) {
      m.corners[i][0] = c[kAprilTagToAruco[i]].At("x").AsDouble();
      m.corners[i][1] = c[kAprilTagToAruco[i]].At("y").AsDouble();
    }
    d.markers.push_back(m);
  }
  d.num_markers = static_cast<int32_t>(d.markers.size());
  return d;
}

int64_t StampNs(const RosValue& v) {
  const RosValue& stamp = v.At("header.stamp");
  return stamp.At("secs").AsInt() * 1000000000LL + stamp.At("nsecs").AsInt();
}

// Reads every camera's messages; fills summary counts and families.
std::vector<StampedDetections> ReadCameraMessages(const RosBag& bag, const std::vector<KalibrCamera>& cams,
                                                  const std::string& cameras_path, ImportSummary* summary,
                                                  std::set<std::string>* families) {
  std::map<uint32_t, size_t> camera_of_connection;
  for (size_t i = 0; i < cams.size(); ++i) {
    camera_of_connection[CameraConnection(bag, cams[i], cameras_path).id] = i;
    summary->cameras.push_back({cams[i].name, cams[i].topic, 0, 0});
  }
  for (const BagConnection& c : bag.connections())
    if (!camera_of_connection.count(c.id))
      summary->notes.push_back("ignored topic " + c.topic + " (" + c.type + "): no camera in " +
                               cameras_path);
  std::vector<StampedDetections> out;
  for (const BagMessage& m : bag.messages()) {
    auto it = camera_of_connection.find(m.connection);
    if (it == camera_of_connection.end()) continue;
    const RosValue v = bag.Decode(m);
    StampedDetections s;
    s.camera = it->second;
    s.stamp_ns = StampNs(v);
    s.msg = ToDetections(v, cams[s.camera], families);
    summary->cameras[s.camera].messages++;
    summary->cameras[s.camera].tags += s.msg.num_markers;
    out.push_back(std::move(s));
  }
  return out;
}

// Sorts by stamp then camera, gives each distinct stamp a seq, drops repeated (camera, stamp) messages.
void AssignFrames(std::vector<StampedDetections>* all, ImportSummary* summary) {
  std::stable_sort(all->begin(), all->end(), [](const StampedDetections& a, const StampedDetections& b) {
    return a.stamp_ns != b.stamp_ns ? a.stamp_ns < b.stamp_ns : a.camera < b.camera;
  });
  std::vector<StampedDetections> kept;
  int64_t seq = -1;
  for (size_t i = 0; i < all->size(); ++i) {
    StampedDetections& s = (*all)[i];
    if (i == 0 || s.stamp_ns != (*all)[i - 1].stamp_ns) {
      ++seq;
    } else if (s.camera == (*all)[i - 1].camera) {
      ++summary->duplicate_messages;
      continue;
    }
    s.msg.seq = seq;
    s.msg.utime = s.stamp_ns / 1000;
    kept.push_back(std::move(s));
  }
  summary->frames = static_cast<int>(seq + 1);
  *all = std::move(kept);
}

void ChooseSizes(const RosbagImportOptions& o, ImportSummary* summary) {
  std::string tagslam = o.tagslam;
  if (tagslam.empty()) {
    const fs::path beside = fs::path(o.cameras).parent_path() / "tagslam.yaml";
    if (fs::exists(beside)) tagslam = beside.string();
  }
  if (!tagslam.empty()) {
    const TagSizes t = LoadTagslamSizes(tagslam);
    summary->tag_size = t.default_size;
    summary->sizes = t.sizes;
    summary->sizes_from = tagslam;
  }
  if (o.tag_size > 0) {
    summary->tag_size = o.tag_size;
    summary->sizes_from = tagslam.empty() ? "--tag-size" : "--tag-size, per-tag sizes from " + tagslam;
  }
  if (!(summary->tag_size > 0))
    throw ImportError("--tag-size M is required (no default_tag_size in a tagslam.yaml beside " + o.cameras +
                      ")");
}

std::string ChooseDictionary(const RosbagImportOptions& o, const std::set<std::string>& families,
                             const std::string& bag) {
  if (!o.dictionary.empty()) return o.dictionary;
  std::set<std::string> dictionaries;
  for (const std::string& f : families) {
    if (f.empty()) continue;  // not given: the dictionary only names the ids (mapping needs no decoding)
    const std::string d = DictionaryForFamily(f);
    if (d.empty())
      throw ImportError(bag + ": tag family '" + f +
                        "' unknown; give --dictionary (e.g. DICT_APRILTAG_36h11)");
    dictionaries.insert(d);
  }
  if (dictionaries.size() > 1) throw ImportError(bag + ": several tag families; give --dictionary");
  return dictionaries.empty() ? "DICT_APRILTAG_36h11" : *dictionaries.begin();
}

void WriteLog(const std::string& path, const std::vector<StampedDetections>& all) {
  EventLogWriter writer(path);
  for (const StampedDetections& s : all) {
    const std::vector<uint8_t> data = Encode(s.msg);
    writer.Write(s.msg.utime, DetectionsChannel(s.msg.camera), data.data(), data.size());
  }
  writer.Close();
}

std::string EmitYaml(const YAML::Node& node, const std::string& comment) {
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << node;
  return "# " + comment + "\n" + e.c_str() + "\n";
}

}  // namespace

ImportSummary ImportRosbag(const RosbagImportOptions& o) {
  ImportSummary summary;
  const std::vector<KalibrCamera> cams = LoadKalibrCameras(o.cameras);
  ChooseSizes(o, &summary);
  const RosBag bag = RosBag::Open(o.bag);
  std::set<std::string> families;
  std::vector<StampedDetections> all = ReadCameraMessages(bag, cams, o.cameras, &summary, &families);
  AssignFrames(&all, &summary);
  summary.dictionary = ChooseDictionary(o, families, o.bag);
  for (const auto& [compression, n] : bag.chunk_compressions())
    summary.notes.push_back(std::to_string(n) + " chunk(s) " + compression);
  for (const std::string& f : families)
    summary.notes.push_back("tag family in the messages: " + (f.empty() ? std::string("(empty)") : f));
  if (o.dictionary.empty() && (families.empty() || families == std::set<std::string>{""}))
    summary.notes.push_back("no tag family in the messages: " + summary.dictionary +
                            " assumed (--dictionary)");

  SessionFolder folder(o.out);
  summary.out = folder.out();
  WriteLog(folder.Path("session.lcmlog"), all);
  YAML::Node rig;
  rig["markers"]["dictionary"] = summary.dictionary;
  rig["markers"]["size"] = summary.tag_size;
  for (const auto& [id, size] : summary.sizes) rig["markers"]["sizes"][id] = size;
  for (const KalibrCamera& c : cams) {
    WriteIntrinsicsOpenCv(folder.Path(c.name + ".yml"), c.model);
    YAML::Node cam;
    cam["name"] = c.name;
    cam["intrinsics"] = c.name + ".yml";
    rig["cameras"].push_back(cam);
  }
  rig["mapper"]["reference_camera"] = cams.front().name;  // TagSLAM's and Kalibr's cam0 = rig frame
  WriteFileAtomic(folder.Path("rig.yaml"),
                  EmitYaml(rig, "made by mcmt-import from " + o.bag + " and " + o.cameras));
  folder.Commit();
  return summary;
}

ImportSummary ImportCsv(const std::string& csv, const std::string& config, const std::string& out) {
  const RigConfig rig = LoadRigConfig(config);
  ImportSummary summary;
  SessionFolder folder(out);
  summary.out = folder.out();
  const CsvToLogResult r = DetectionsCsvToLog(csv, rig, folder.Path("session.lcmlog"));
  YAML::Node root = YAML::Clone(rig.root);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const CameraConfig& c = rig.cameras[i];
    WriteIntrinsicsOpenCv(folder.Path(c.name + ".yml"), c.model);
    root["cameras"][i]["intrinsics"] = c.name + ".yml";
    root["cameras"][i].remove("source");
    root["cameras"][i].remove("timestamps");
    summary.cameras.push_back({c.name, "", 0, 0});
  }
  if (fs::exists(rig.markers.dictionary)) root["markers"]["dictionary"] = rig.markers.dictionary;
  WriteFileAtomic(folder.Path("rig.yaml"),
                  EmitYaml(root, "made by mcmt-import from " + csv + " and " + config));
  folder.Commit();
  summary.dictionary = rig.markers.dictionary;
  summary.tag_size = rig.markers.size;
  summary.sizes = rig.markers.sizes;
  summary.sizes_from = config;
  summary.notes.push_back(std::to_string(r.rows) + " rows, " + std::to_string(r.messages) +
                          " detections messages (frames without markers have no rows)");
  return summary;
}

std::string FormatImportSummary(const ImportSummary& s) {
  std::ostringstream o;
  o << "mcmt-import: wrote " << s.out << "/session.lcmlog and " << s.out << "/rig.yaml\n";
  if (s.frames) o << "  frames: " << s.frames << " (distinct header stamps)\n";
  for (const ImportedCamera& c : s.cameras)
    if (!c.topic.empty())
      o << "  " << c.name << ": " << c.topic << ", " << c.messages << " messages, " << c.tags << " tags\n";
  o << "  dictionary: " << s.dictionary << ", tag size " << s.tag_size << " m";
  if (!s.sizes.empty()) o << " (" << s.sizes.size() << " per-tag sizes)";
  o << " from " << s.sizes_from << "\n";
  if (s.duplicate_messages)
    o << "  dropped " << s.duplicate_messages << " repeated (camera, stamp) messages\n";
  for (const std::string& n : s.notes) o << "  " << n << "\n";
  return o.str();
}

}  // namespace mcmt
