// The real programs: mcmt-sim (determinism, files, video, detections log, option errors), mcmt-eval
// (figures, mismatches, missing files) and mcmt-markers (help, bad ids).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <opencv2/aruco.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "core/config.h"
#include "core/dictionary.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/marker.h"
#include "mcmt/detections_t.hpp"
#include "sim/eval.h"
#include "sim/sim.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"

namespace fs = std::filesystem;
using namespace mcmt;

namespace {

const std::string kSim = MCMT_BIN_DIR "/mcmt-sim";
const std::string kEval = MCMT_BIN_DIR "/mcmt-eval";
const std::string kMarkers = MCMT_BIN_DIR "/mcmt-markers";

using mcmt::test::TempDir;

TempDir& Tmp() {
  static TempDir dir("process");
  return dir;
}

struct Result {
  int code = -1;
  std::string out, err;
};

// Runs `program args` with stdout and stderr captured.
Result RunProgram(const std::string& program, const std::string& args) {
  static int counter = 0;
  const std::string base = Tmp() / ("run" + std::to_string(counter++));
  Result r;
  r.code = mcmt::test::Child({"/bin/sh", "-c", program + " " + args}, base + ".out", base + ".err").Wait(600);
  r.out = mcmt::test::ReadText(base + ".out");
  r.err = mcmt::test::ReadText(base + ".err");
  fs::remove(base + ".out");
  fs::remove(base + ".err");
  return r;
}

int Lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

// Every regular file under `dir`, relative path -> bytes.
std::map<std::string, std::string> Files(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file())
      files[fs::relative(e.path(), dir).string()] = mcmt::test::ReadText(e.path().string());
  return files;
}

// A rendered short session (cached: several tests look at it).
const std::string& Rendered() {
  static const std::string dir = [] {
    const std::string d = Tmp() / "rendered_a";
    const Result r = RunProgram(kSim, "--out " + d + " --frames 5 --cameras 2 --seed 5 --quiet");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    return d;
  }();
  return dir;
}

struct LogMessage {
  std::string channel;
  int64_t timestamp = 0;
  detections_t msg;
};

std::vector<LogMessage> ReadDetectionsLog(const std::string& path) {
  std::vector<LogMessage> out;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  if (!log.good()) return out;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev; ev = log.readNextEvent()) {
    LogMessage m;
    m.channel = ev->channel;
    m.timestamp = ev->timestamp;
    std::string error;
    EXPECT_TRUE(Decode(ev->data, static_cast<size_t>(ev->datalen), &m.msg, &error)) << error;
    out.push_back(m);
  }
  return out;
}

// The numbers after "key": in a JSON text, in order.
std::vector<double> JsonNumbers(const std::string& json, const std::string& key) {
  std::vector<double> v;
  const std::regex re("\"" + key + "\": (-?[0-9.eE+-]+)");
  for (auto it = std::sregex_iterator(json.begin(), json.end(), re); it != std::sregex_iterator(); ++it)
    v.push_back(std::stod((*it)[1].str()));
  return v;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// mcmt-sim

TEST(SimProcess, HelpDocumentsEveryOption) {
  const Result r = RunProgram(kSim, "--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.err, "");
  // Every option the program declares (read from its source) appears in --help.
  const std::string source = mcmt::test::ReadText(MCMT_SOURCE_DIR "/sim/sim_main.cc");
  const std::regex re("args\\.Add(String|Int|Int64|Double|Flag|List)\\(\\s*\"([a-z0-9-]+)\"");
  int count = 0;
  for (auto it = std::sregex_iterator(source.begin(), source.end(), re); it != std::sregex_iterator(); ++it) {
    ++count;
    const std::string name = "--" + (*it)[2].str();
    EXPECT_NE(r.out.find("  " + name + " "), std::string::npos) << name << " not in --help:\n" << r.out;
  }
  EXPECT_GE(count, 30);
  for (const char* name :
       {"--out", "--object", "--cameras", "--frames", "--seed", "--image-size", "--dictionary", "--video",
        "--detections-only", "--motion-blur", "--threads", "--drop-rate"})
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
  for (const char* object : {"four_sided", "box", "pentagon", "cube", "board"})
    EXPECT_NE(r.out.find(object), std::string::npos) << object;
}

TEST(SimProcess, SameSeedSameBytesOtherSeedOtherBytes) {
  const std::string& a = Rendered();
  const std::string b = Tmp() / "rendered_b", c = Tmp() / "rendered_c";
  // Same seed, rendered on 2 threads: byte-identical.
  Result r = RunProgram(kSim, "--out " + b + " --frames 5 --cameras 2 --seed 5 --quiet --threads 2");
  ASSERT_EQ(r.code, 0) << r.err;
  r = RunProgram(kSim, "--out " + c + " --frames 5 --cameras 2 --seed 6 --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto fa = Files(a), fb = Files(b), fc = Files(c);
  ASSERT_EQ(fa.size(), 1u + 2u + 1u + 10u);  // rig.yaml, 2 intrinsics, ground truth, 10 PNGs
  for (const char* name : {"rig.yaml", "cam0.yml", "cam1.yml", "ground_truth.yaml", "cam0/000000.png",
                           "cam0/000004.png", "cam1/000002.png"})
    EXPECT_EQ(fa.count(name), 1u) << name;
  ASSERT_EQ(fb.size(), fa.size());
  for (const auto& [name, bytes] : fa) {
    ASSERT_EQ(fb.count(name), 1u) << name;
    EXPECT_TRUE(fb.at(name) == bytes) << name << " differs for the same seed";
  }
  // Another seed: another trajectory and other images (the intrinsics do not depend on it).
  ASSERT_EQ(fc.size(), fa.size());
  EXPECT_NE(fc.at("ground_truth.yaml"), fa.at("ground_truth.yaml"));
  for (const auto& [name, bytes] : fa) {
    if (name.size() > 4 && name.substr(name.size() - 4) == ".png") {
      EXPECT_NE(fc.at(name), bytes) << name << " equal for different seeds";
    }
  }

  // Detections-only, with every random option on.
  const std::string opts =
      " --frames 30 --cameras 3 --detections-only --quiet --corner-noise-px 0.3 "
      "--miss-rate 0.1 --false-rate 0.2 --drop-rate 0.1 --object box";
  const std::string d1 = Tmp() / "det_1", d2 = Tmp() / "det_2", d3 = Tmp() / "det_3";
  ASSERT_EQ(RunProgram(kSim, "--out " + d1 + " --seed 9" + opts).code, 0);
  ASSERT_EQ(RunProgram(kSim, "--out " + d2 + " --seed 9" + opts).code, 0);
  ASSERT_EQ(RunProgram(kSim, "--out " + d3 + " --seed 10" + opts).code, 0);
  const auto g1 = Files(d1), g2 = Files(d2), g3 = Files(d3);
  ASSERT_EQ(g1.count("detections.lcmlog"), 1u);
  EXPECT_EQ(g1.size(), 1u + 3u + 1u + 1u);  // rig.yaml, 3 intrinsics, ground truth, log
  EXPECT_TRUE(g1 == g2) << "detections-only output differs for the same seed";
  EXPECT_NE(g1.at("detections.lcmlog"), g3.at("detections.lcmlog"));
  EXPECT_NE(g1.at("ground_truth.yaml"), g3.at("ground_truth.yaml"));
}

TEST(SimProcess, RenderedModeWritesWhatRigYamlSays) {
  const std::string& dir = Rendered();
  const sim::GroundTruth truth = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
  ASSERT_EQ(truth.cameras.size(), 2u);
  ASSERT_EQ(truth.frames.size(), 5u);
  const YAML::Node rig = YAML::LoadFile(dir + "/rig.yaml");
  EXPECT_EQ(rig["markers"]["dictionary"].as<std::string>(), truth.dictionary);
  EXPECT_DOUBLE_EQ(rig["markers"]["size"].as<double>(), truth.marker_size);
  std::set<int> ids;
  for (const auto& id : rig["markers"]["ids"]) ids.insert(id.as<int>());
  std::set<int> truth_ids;
  for (const auto& m : truth.markers) truth_ids.insert(m.id);
  EXPECT_EQ(ids, truth_ids);
  ASSERT_EQ(rig["cameras"].size(), 2u);
  auto dictionary = LoadDictionary(truth.dictionary);
  int detected = 0;
  for (size_t k = 0; k < 2; ++k) {
    const YAML::Node cam = rig["cameras"][k];
    const sim::SimCamera& gt = truth.cameras[k];
    EXPECT_EQ(cam["name"].as<std::string>(), gt.name);
    // Intrinsics: OpenCV's FileStorage reads them; they are the ground truth's.
    cv::FileStorage fs_in(dir + "/" + cam["intrinsics"].as<std::string>(), cv::FileStorage::READ);
    ASSERT_TRUE(fs_in.isOpened()) << cam["intrinsics"].as<std::string>();
    cv::Mat k_mat;
    fs_in["camera_matrix"] >> k_mat;
    ASSERT_EQ(k_mat.rows, 3);
    EXPECT_DOUBLE_EQ(k_mat.at<double>(0, 0), gt.model.fx);
    EXPECT_DOUBLE_EQ(k_mat.at<double>(1, 1), gt.model.fy);
    EXPECT_DOUBLE_EQ(k_mat.at<double>(0, 2), gt.model.cx);
    EXPECT_DOUBLE_EQ(k_mat.at<double>(1, 2), gt.model.cy);
    EXPECT_EQ(static_cast<int>(fs_in["image_width"]), gt.model.width);
    EXPECT_EQ(static_cast<int>(fs_in["image_height"]), gt.model.height);
    // Images: one PNG per frame in the source folder, named by seq, of the camera's size.
    const std::string source = cam["source"].as<std::string>();
    EXPECT_EQ(source, gt.name + "/");
    for (const auto& f : truth.frames) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06lld.png", static_cast<long long>(f.seq));
      const cv::Mat image = cv::imread(dir + "/" + source + name, cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(image.empty()) << source << name;
      EXPECT_EQ(image.cols, 640);
      EXPECT_EQ(image.rows, 480);
      EXPECT_EQ(image.type(), CV_8UC1);
      // The markers in view are real markers of the object.
      std::vector<int> found;
      std::vector<std::vector<cv::Point2f>> corners;
      cv::aruco::detectMarkers(image, dictionary, corners, found);
      for (int id : found) EXPECT_EQ(truth_ids.count(id), 1u) << "id " << id << " in " << source << name;
      detected += static_cast<int>(found.size());
    }
  }
  EXPECT_GE(detected, 10);  // about 2 of the 4 sides face each camera
}

// The rig file is what the other processes load: LoadRigConfig reads it and the intrinsics it names,
// which are the ground truth's exactly (distortion and per-camera differences included).
TEST(SimProcess, RigYamlLoadsWithTheGroundTruthIntrinsics) {
  const std::string dir = Tmp() / "rig_check";
  const Result r =
      RunProgram(kSim, "--out " + dir +
                           " --frames 3 --cameras 3 --seed 2 --detections-only --quiet --object pentagon "
                           "--distortion radtan --intrinsics-spread 0.05 --image-size 800x600");
  ASSERT_EQ(r.code, 0) << r.err;
  const sim::GroundTruth truth = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
  const RigConfig rig = LoadRigConfig(dir + "/rig.yaml");
  EXPECT_EQ(rig.markers.dictionary, truth.dictionary);
  ASSERT_EQ(rig.cameras.size(), 3u);
  for (const auto& m : truth.markers) {
    EXPECT_TRUE(rig.markers.Accepts(m.id)) << m.id;
    EXPECT_EQ(rig.markers.Sizes().Get(m.id), m.size) << m.id;
  }
  EXPECT_FALSE(rig.markers.Accepts(truth.markers.back().id + 1));
  for (size_t k = 0; k < 3; ++k) {
    const CameraModel& a = rig.cameras[k].model;
    const CameraModel& b = truth.cameras[k].model;
    SCOPED_TRACE(truth.cameras[k].name);
    EXPECT_EQ(rig.cameras[k].name, truth.cameras[k].name);
    EXPECT_EQ(a.width, 800);
    EXPECT_EQ(a.height, 600);
    EXPECT_EQ(a.fx, b.fx);
    EXPECT_EQ(a.fy, b.fy);
    EXPECT_EQ(a.cx, b.cx);
    EXPECT_EQ(a.cy, b.cy);
    EXPECT_EQ(a.model, DistortionModel::kRadTan);
    EXPECT_EQ(a.distortion, b.distortion);
  }
  // Per-camera spread: the cameras differ.
  EXPECT_NE(truth.cameras[0].model.fx, truth.cameras[1].model.fx);
  EXPECT_NE(truth.cameras[0].model.distortion, truth.cameras[1].model.distortion);
}

// A shorter session into the folder of a longer one: the camera folders hold this session's frames only
// (the detector reads a folder whole); other files there are left alone.
TEST(SimProcess, RerunIntoTheSameFolderLeavesNoStaleFrames) {
  const std::string dir = Tmp() / "rerun";
  ASSERT_EQ(RunProgram(kSim, "--out " + dir + " --frames 6 --cameras 2 --quiet --image-size 160x120").code,
            0);
  std::ofstream(dir + "/cam0/notes.txt") << "mine";
  std::ofstream(dir + "/cam0/12.png.bak") << "mine";
  ASSERT_EQ(RunProgram(kSim, "--out " + dir + " --frames 3 --cameras 2 --quiet --image-size 160x120").code,
            0);
  for (const char* cam : {"cam0", "cam1"}) {
    std::set<std::string> pngs;
    for (const auto& e : fs::directory_iterator(dir + "/" + cam))
      if (e.path().extension() == ".png") pngs.insert(e.path().filename().string());
    EXPECT_EQ(pngs, (std::set<std::string>{"000000.png", "000001.png", "000002.png"})) << cam;
  }
  EXPECT_TRUE(fs::exists(dir + "/cam0/notes.txt"));
  EXPECT_TRUE(fs::exists(dir + "/cam0/12.png.bak"));
  EXPECT_EQ(sim::ReadGroundTruth(dir + "/ground_truth.yaml").frames.size(), 3u);
}

TEST(SimProcess, VideoIsDecodableWithEveryFrame) {
  const std::string dir = Tmp() / "video";
  const Result r = RunProgram(kSim, "--out " + dir + " --frames 7 --cameras 2 --seed 5 --video --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  const YAML::Node rig = YAML::LoadFile(dir + "/rig.yaml");
  const std::string& png_dir = Rendered();  // same seed and options, 5 frames, PNG
  for (int k = 0; k < 2; ++k) {
    const std::string source = rig["cameras"][k]["source"].as<std::string>();
    EXPECT_EQ(source, "cam" + std::to_string(k) + ".mp4");
    EXPECT_FALSE(fs::exists(dir + "/cam" + std::to_string(k))) << "PNG folder written with --video";
    cv::VideoCapture video(dir + "/" + source);
    ASSERT_TRUE(video.isOpened()) << source;
    int frames = 0;
    cv::Mat frame;
    while (video.read(frame)) {
      ASSERT_EQ(frame.cols, 640);
      ASSERT_EQ(frame.rows, 480);
      if (frames < 5) {
        // The frame is the rendered image (up to compression).
        char name[32];
        std::snprintf(name, sizeof(name), "/cam%d/%06d.png", k, frames);
        const cv::Mat png = cv::imread(png_dir + name, cv::IMREAD_GRAYSCALE);
        cv::Mat gray;
        cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
        const double diff = cv::norm(gray, png, cv::NORM_L1) / gray.total();
        EXPECT_LT(diff, 8.0) << source << " frame " << frames;
      }
      ++frames;
    }
    EXPECT_EQ(frames, 7) << source;
  }
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(SimProcess, DetectionsLogHasOneMessagePerCameraFrameWithCornersNearTruth) {
  const double sigma = 0.3;
  for (double drop : {0.0, 0.3}) {
    SCOPED_TRACE("drop rate " + std::to_string(drop));
    const std::string dir = Tmp() / ("det_drop" + std::to_string(static_cast<int>(drop * 10)));
    const int frames = 40, cameras = 3;
    const Result r =
        RunProgram(kSim, "--out " + dir + " --frames 40 --cameras 3 --seed 4 --detections-only --quiet " +
                             "--corner-noise-px 0.3 --drop-rate " + std::to_string(drop));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out, "");
    const sim::GroundTruth truth = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
    const std::vector<LogMessage> log = ReadDetectionsLog(dir + "/detections.lcmlog");
    std::map<int64_t, const sim::SimFrame*> by_seq;
    for (const auto& f : truth.frames) by_seq[f.seq] = &f;
    std::set<std::pair<std::string, int64_t>> seen;
    double sq = 0, max_err = 0;
    int n_corners = 0, with_markers = 0;
    for (const LogMessage& m : log) {
      const detections_t& d = m.msg;
      EXPECT_EQ(m.channel, DetectionsChannel(d.camera));
      EXPECT_EQ(m.timestamp, d.utime);
      EXPECT_TRUE(seen.insert({d.camera, d.seq}).second) << "duplicate " << d.camera << " " << d.seq;
      ASSERT_EQ(by_seq.count(d.seq), 1u) << d.seq;
      const sim::SimFrame& f = *by_seq.at(d.seq);
      EXPECT_EQ(d.utime, f.utime);
      EXPECT_EQ(d.dictionary, truth.dictionary);
      const sim::SimCamera* cam = truth.FindCamera(d.camera);
      ASSERT_NE(cam, nullptr) << d.camera;
      EXPECT_EQ(d.camera_model.fx, cam->model.fx);
      EXPECT_EQ(d.camera_model.width, cam->model.width);
      EXPECT_EQ(d.num_markers, static_cast<int>(d.markers.size()));
      if (!d.markers.empty()) ++with_markers;
      for (const marker_t& mk : d.markers) {
        const sim::SimMarker* gm = truth.FindMarker(mk.id);
        ASSERT_NE(gm, nullptr) << "id " << mk.id;
        // Independent projection of the true corners.
        const Rigid3 cam_from_marker =
            Inverse(cam->rig_from_cam) * f.rig_from_object * gm->object_from_marker;
        const MarkerCorners3d corners = MarkerCornersInMarker(gm->size);
        for (int i = 0; i < 4; ++i) {
          const Eigen::Vector2d px = cam->model.Project(cam_from_marker * corners[i]);
          const double ex = mk.corners[i][0] - px.x(), ey = mk.corners[i][1] - px.y();
          sq += ex * ex + ey * ey;
          max_err = std::max({max_err, std::abs(ex), std::abs(ey)});
          n_corners += 2;
        }
      }
    }
    const int expected = frames * cameras;
    if (drop == 0.0) {
      EXPECT_EQ(static_cast<int>(log.size()), expected);
    } else {
      // 120 Bernoulli(0.7) trials: mean 84, sd 5.
      EXPECT_GT(static_cast<int>(log.size()), 60);
      EXPECT_LT(static_cast<int>(log.size()), 108);
    }
    EXPECT_GE(with_markers, static_cast<int>(0.9 * log.size()));
    ASSERT_GT(n_corners, 200);
    const double rms = std::sqrt(sq / n_corners);
    EXPECT_NEAR(rms, sigma, 0.15 * sigma) << n_corners << " corner coordinates";
    EXPECT_LT(max_err, 5.5 * sigma);
  }
}

// Misses, false detections and drops each change only their own outcome (the random numbers drawn do
// not depend on them): with the same seed, a run with misses reports a subset of the markers of a run
// without, with identical corners; drops remove whole messages; false detections add ids not on the
// object. Rates match the options. Every reported marker is truly detectable.
TEST(SimProcess, DetectionOptionsChangeOnlyTheirOwnOutcome) {
  const std::string base = " --frames 40 --cameras 3 --seed 12 --object box --detections-only --quiet";
  std::map<std::string, std::vector<LogMessage>> logs;
  for (const std::string& extra : {std::string(""), std::string(" --miss-rate 0.3"),
                                   std::string(" --false-rate 0.5"), std::string(" --drop-rate 0.25")}) {
    const std::string dir = Tmp() / ("opts" + std::to_string(logs.size()));
    const Result r = RunProgram(kSim, "--out " + dir + base + extra);
    ASSERT_EQ(r.code, 0) << r.err;
    logs[extra] = ReadDetectionsLog(dir + "/detections.lcmlog");
  }
  const sim::GroundTruth truth = sim::ReadGroundTruth(Tmp() / "opts0/ground_truth.yaml");
  using Key = std::pair<std::string, int64_t>;
  auto index = [](const std::vector<LogMessage>& log) {
    std::map<Key, const detections_t*> m;
    for (const auto& e : log) m[{e.msg.camera, e.msg.seq}] = &e.msg;
    return m;
  };
  auto same_marker = [](const marker_t& a, const marker_t& b) {
    if (a.id != b.id) return false;
    for (int i = 0; i < 4; ++i)
      if (a.corners[i][0] != b.corners[i][0] || a.corners[i][1] != b.corners[i][1]) return false;
    return true;
  };
  const auto all = index(logs[""]);
  ASSERT_EQ(all.size(), 120u);

  // Every reported marker is detectable: all true corners in the image, facing the camera within 80
  // degrees (computed here independently of the simulator).
  std::map<int64_t, const sim::SimFrame*> by_seq;
  for (const auto& f : truth.frames) by_seq[f.seq] = &f;
  int total = 0;
  for (const auto& [key, d] : all) {
    const sim::SimCamera& cam = *truth.FindCamera(key.first);
    for (const marker_t& mk : d->markers) {
      const sim::SimMarker* gm = truth.FindMarker(mk.id);
      ASSERT_NE(gm, nullptr);
      const Rigid3 cam_from_marker =
          Inverse(cam.rig_from_cam) * by_seq.at(key.second)->rig_from_object * gm->object_from_marker;
      const Eigen::Vector3d normal = cam_from_marker.linear().col(2);
      const Eigen::Vector3d to_camera = -cam_from_marker.translation().normalized();
      EXPECT_LE(std::acos(std::clamp(normal.dot(to_camera), -1.0, 1.0)) * 180 / M_PI, 80.0 + 1e-9);
      for (const auto& c : MarkerCornersInMarker(gm->size)) {
        const Eigen::Vector2d px = cam.model.Project(cam_from_marker * c);
        EXPECT_TRUE(px.x() >= 0 && px.y() >= 0 && px.x() <= cam.model.width - 1 &&
                    px.y() <= cam.model.height - 1)
            << key.first << " seq " << key.second << " id " << mk.id << ": " << px.transpose();
      }
      ++total;
    }
  }
  ASSERT_GT(total, 200);

  // Misses: a subset, corners unchanged, about 30 % missing.
  {
    const auto missed = index(logs[" --miss-rate 0.3"]);
    ASSERT_EQ(missed.size(), all.size());
    int kept = 0;
    for (const auto& [key, d] : missed) {
      const detections_t& full = *all.at(key);
      size_t j = 0;
      for (const marker_t& mk : d->markers) {
        while (j < full.markers.size() && full.markers[j].id != mk.id) ++j;
        ASSERT_LT(j, full.markers.size()) << "marker " << mk.id << " not in the run without misses";
        EXPECT_TRUE(same_marker(mk, full.markers[j])) << "marker " << mk.id;
        ++kept;
      }
    }
    EXPECT_NEAR(1.0 - double(kept) / total, 0.3, 0.07) << kept << " of " << total;
  }
  // False detections: the object's markers unchanged, extra ids not on the object, 0.5 per message.
  {
    const auto with_false = index(logs[" --false-rate 0.5"]);
    ASSERT_EQ(with_false.size(), all.size());
    int extra = 0;
    for (const auto& [key, d] : with_false) {
      const detections_t& full = *all.at(key);
      std::vector<marker_t> own;
      for (const marker_t& mk : d->markers) {
        if (truth.FindMarker(mk.id)) {
          own.push_back(mk);
        } else {
          ++extra;
          EXPECT_GE(mk.id, 0);
          EXPECT_LT(mk.id, 250);
          for (const auto& c : mk.corners) {
            EXPECT_GE(c[0], 0);
            EXPECT_LE(c[0], d->camera_model.width - 1);
          }
        }
      }
      ASSERT_EQ(own.size(), full.markers.size());
      for (size_t i = 0; i < own.size(); ++i) EXPECT_TRUE(same_marker(own[i], full.markers[i]));
    }
    // Poisson(0.5) over 120 messages: mean 60, sd 7.7.
    EXPECT_GT(extra, 35);
    EXPECT_LT(extra, 85);
  }
  // Drops: whole messages gone, the others unchanged, about 25 % dropped.
  {
    const auto dropped = index(logs[" --drop-rate 0.25"]);
    for (const auto& [key, d] : dropped) {
      const detections_t& full = *all.at(key);
      ASSERT_EQ(d->markers.size(), full.markers.size());
      for (size_t i = 0; i < full.markers.size(); ++i)
        EXPECT_TRUE(same_marker(d->markers[i], full.markers[i]));
    }
    EXPECT_NEAR(1.0 - dropped.size() / 120.0, 0.25, 0.1) << dropped.size();
  }
}

// The documented -1 defaults mean the same given explicitly as omitted; other values take effect.
// --intrinsics-error and --clock (issue 18) change what the rig is told, not the truth: the written
// intrinsics are off by exactly what was asked, the corners, the ground-truth cameras and frames are
// those of the same session without them, and each camera's utimes are its clock's readings (event times
// too, the log in time order).
TEST(SimProcess, IntrinsicsErrorAndClockChangeTheWrittenRigNotTheTruth) {
  const std::string base =
      " --frames 30 --cameras 3 --seed 7 --distortion radtan --object box --detections-only --quiet";
  const std::string plain = Tmp() / "selfcal_plain", wrong = Tmp() / "selfcal_wrong";
  Result r = RunProgram(kSim, "--out " + plain + base);
  ASSERT_EQ(r.code, 0) << r.err;
  r = RunProgram(kSim, "--out " + wrong + base +
                           " --intrinsics-error cam1,3,8,-6,0.03 --clock cam2,12,500 --clock cam0,-20.5");
  ASSERT_EQ(r.code, 0) << r.err;
  const sim::GroundTruth t_plain = sim::ReadGroundTruth(plain + "/ground_truth.yaml");
  const sim::GroundTruth t_wrong = sim::ReadGroundTruth(wrong + "/ground_truth.yaml");
  ASSERT_EQ(t_plain.cameras.size(), t_wrong.cameras.size());
  for (size_t k = 0; k < t_plain.cameras.size(); ++k) {
    const CameraModel& a = t_plain.cameras[k].model;
    const CameraModel& b = t_wrong.cameras[k].model;
    EXPECT_EQ(a.fx, b.fx);
    EXPECT_EQ(a.cx, b.cx);
    EXPECT_EQ(a.distortion, b.distortion);
    EXPECT_TRUE(t_plain.cameras[k].rig_from_cam.isApprox(t_wrong.cameras[k].rig_from_cam, 0));
  }
  ASSERT_EQ(t_plain.frames.size(), t_wrong.frames.size());
  for (size_t f = 0; f < t_plain.frames.size(); ++f)
    EXPECT_EQ(t_plain.frames[f].utime, t_wrong.frames[f].utime);
  EXPECT_TRUE(t_plain.clocks.empty());
  ASSERT_EQ(t_wrong.clocks.size(), 2u);
  EXPECT_EQ(t_wrong.clocks.at("cam2").offset_ms, 12.0);
  EXPECT_EQ(t_wrong.clocks.at("cam2").drift_ppm, 500.0);
  EXPECT_EQ(t_wrong.clocks.at("cam0").offset_ms, -20.5);
  // The written intrinsics: cam1 off as asked, the others true.
  const CameraModel truth1 = t_plain.FindCamera("cam1")->model;
  const CameraModel written1 = LoadIntrinsics(wrong + "/cam1.yml");
  EXPECT_NEAR(written1.fx / truth1.fx, 1.03, 1e-12);
  EXPECT_NEAR(written1.fy / truth1.fy, 1.03, 1e-12);
  EXPECT_NEAR(written1.cx - truth1.cx, 8.0, 1e-9);
  EXPECT_NEAR(written1.cy - truth1.cy, -6.0, 1e-9);
  ASSERT_EQ(written1.distortion.size(), truth1.distortion.size());
  EXPECT_NEAR(written1.distortion[0] - truth1.distortion[0], 0.03, 1e-12);
  for (size_t i = 1; i < truth1.distortion.size(); ++i)
    EXPECT_EQ(written1.distortion[i], truth1.distortion[i]);
  EXPECT_EQ(mcmt::test::ReadText(wrong + "/cam0.yml"), mcmt::test::ReadText(plain + "/cam0.yml"));
  EXPECT_NE(mcmt::test::ReadText(wrong + "/cam1.yml"), mcmt::test::ReadText(plain + "/cam1.yml"));
  // The detections: same corners, the written model, the clock's utime.
  const std::vector<LogMessage> a = ReadDetectionsLog(plain + "/detections.lcmlog");
  const std::vector<LogMessage> b = ReadDetectionsLog(wrong + "/detections.lcmlog");
  ASSERT_EQ(a.size(), b.size());
  std::map<std::pair<std::string, int64_t>, const detections_t*> by_key;
  for (const LogMessage& m : a) by_key[{m.msg.camera, m.msg.seq}] = &m.msg;
  int64_t last = 0;
  int shifted = 0;
  for (const LogMessage& m : b) {
    EXPECT_EQ(m.timestamp, m.msg.utime);
    EXPECT_GE(m.timestamp, last) << "log not in time order";
    last = m.timestamp;
    const auto it = by_key.find({m.msg.camera, m.msg.seq});
    ASSERT_NE(it, by_key.end()) << m.msg.camera << " " << m.msg.seq;
    const detections_t& p = *it->second;
    ASSERT_EQ(p.markers.size(), m.msg.markers.size());
    for (size_t i = 0; i < p.markers.size(); ++i)
      for (int c = 0; c < 4; ++c) {
        EXPECT_EQ(p.markers[i].corners[c][0], m.msg.markers[i].corners[c][0]);
        EXPECT_EQ(p.markers[i].corners[c][1], m.msg.markers[i].corners[c][1]);
      }
    const double since_start_s = 1e-6 * static_cast<double>(p.utime - sim::kStartUtime);
    int64_t expected = p.utime;
    if (m.msg.camera == "cam2") expected += std::llround(12000 + 500 * since_start_s);
    if (m.msg.camera == "cam0") expected -= 20500;
    EXPECT_EQ(m.msg.utime, expected) << m.msg.camera << " " << m.msg.seq;
    shifted += m.msg.utime != p.utime;
    EXPECT_EQ(m.msg.camera_model.fx, m.msg.camera == "cam1" ? written1.fx : p.camera_model.fx);
  }
  EXPECT_EQ(shifted, 60);
  // With images: the clock goes into CAM_timestamps.csv, named in rig.yaml.
  const std::string rendered = Tmp() / "selfcal_rendered";
  r = RunProgram(kSim, "--out " + rendered + " --frames 2 --cameras 2 --seed 7 --quiet --clock cam1,5,1000");
  ASSERT_EQ(r.code, 0) << r.err;
  const RigConfig rig = LoadRigConfig(rendered + "/rig.yaml");
  EXPECT_EQ(rig.cameras[0].timestamps_path, "");
  EXPECT_EQ(fs::path(rig.cameras[1].timestamps_path).filename(), "cam1_timestamps.csv");
  EXPECT_EQ(mcmt::test::ReadText(rendered + "/cam1_timestamps.csv"),
            "frame_index,time_s\n0,1000000.005000\n1,1000000.038366\n");
}

// --max-speed-m-s: the object's centre reaches that top speed (frame to frame differences a little
// below it: chords of the path, 2.5 % short at 2 m/s and 30 fps), along a motion otherwise the default's.
TEST(SimProcess, MaxSpeedSetsTheObjectsTopSpeed) {
  auto top_speed = [&](const std::string& name, const std::string& extra) {
    const std::string dir = Tmp() / name;
    const Result r = RunProgram(
        kSim, "--out " + dir + " --frames 300 --cameras 2 --seed 3 --detections-only --quiet" + extra);
    EXPECT_EQ(r.code, 0) << r.err;
    const sim::GroundTruth t = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
    double top = 0;
    for (size_t f = 1; f < t.frames.size(); ++f)
      top = std::max(
          top,
          (t.frames[f].rig_from_object.translation() - t.frames[f - 1].rig_from_object.translation()).norm() *
              t.fps);
    return top;
  };
  const double plain = top_speed("speed_plain", "");
  for (double v : {0.5, 1.0, 2.0}) {
    const double top = top_speed("speed_" + std::to_string(v), " --max-speed-m-s " + std::to_string(v));
    std::printf("--max-speed-m-s %.1f: top frame-to-frame speed %.4f m/s (default motion %.4f)\n", v, top,
                plain);
    EXPECT_LE(top, v * 1.0001);
    EXPECT_GT(top, 0.96 * v);
  }
  EXPECT_LT(plain, 0.4);
}

// --scene bodies takes --intrinsics-error, --clock and --max-speed-m-s as --scene object does: the
// written intrinsics off as asked, every body's ground truth naming the clocks, each camera's utimes its
// clock's readings with the corners of the plain session, and the moving bodies at the top speed asked
// (their own motion's, to within the push apart of the two bodies: +-6 cm/s over 300 frames).
TEST(SimProcess, BodiesSceneTakesTheSelfCalibrationOptions) {
  const std::string base = " --scene bodies --frames 60 --cameras 3 --seed 5 --detections-only --quiet";
  const std::string plain = Tmp() / "bodies_plain", wrong = Tmp() / "bodies_wrong";
  Result r = RunProgram(kSim, "--out " + plain + base);
  ASSERT_EQ(r.code, 0) << r.err;
  r = RunProgram(kSim, "--out " + wrong + base + " --intrinsics-error cam1,3,8,-6,0.03 --clock cam2,12,500");
  ASSERT_EQ(r.code, 0) << r.err;
  const CameraModel truth1 = sim::ReadGroundTruth(plain + "/ground_truth.yaml").FindCamera("cam1")->model;
  const CameraModel written1 = LoadIntrinsics(wrong + "/cam1.yml");
  EXPECT_NEAR(written1.fx / truth1.fx, 1.03, 1e-12);
  EXPECT_NEAR(written1.cx - truth1.cx, 8.0, 1e-9);
  EXPECT_NEAR(written1.cy - truth1.cy, -6.0, 1e-9);
  EXPECT_EQ(mcmt::test::ReadText(wrong + "/cam0.yml"), mcmt::test::ReadText(plain + "/cam0.yml"));
  for (const std::string body : {"tool", "patient", "floor"}) {
    const sim::GroundTruth t = sim::ReadGroundTruth(wrong + "/ground_truth_" + body + ".yaml");
    ASSERT_EQ(t.clocks.size(), 1u) << body;
    EXPECT_EQ(t.clocks.at("cam2").offset_ms, 12.0) << body;
    EXPECT_EQ(t.clocks.at("cam2").drift_ppm, 500.0) << body;
    EXPECT_EQ(t.FindCamera("cam1")->model.fx, truth1.fx) << body;  // the truth stays true
  }
  const std::vector<LogMessage> a = ReadDetectionsLog(plain + "/detections.lcmlog");
  const std::vector<LogMessage> b = ReadDetectionsLog(wrong + "/detections.lcmlog");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 100u);
  std::map<std::pair<std::string, int64_t>, const detections_t*> by_key;
  for (const LogMessage& m : a) by_key[{m.msg.camera, m.msg.seq}] = &m.msg;
  int64_t last = 0;
  int shifted = 0;
  for (const LogMessage& m : b) {
    EXPECT_GE(m.timestamp, last) << "log not in time order";
    last = m.timestamp;
    const auto it = by_key.find({m.msg.camera, m.msg.seq});
    ASSERT_NE(it, by_key.end()) << m.msg.camera << " " << m.msg.seq;
    const detections_t& p = *it->second;
    ASSERT_EQ(p.markers.size(), m.msg.markers.size());
    for (size_t i = 0; i < p.markers.size(); ++i)
      EXPECT_EQ(p.markers[i].corners[2][1], m.msg.markers[i].corners[2][1]);
    const double since_start_s = 1e-6 * static_cast<double>(p.utime - sim::kStartUtime);
    const int64_t expected =
        m.msg.camera == "cam2" ? p.utime + std::llround(12000 + 500 * since_start_s) : p.utime;
    EXPECT_EQ(m.msg.utime, expected) << m.msg.camera << " " << m.msg.seq;
    shifted += m.msg.utime != p.utime;
    EXPECT_EQ(m.msg.camera_model.fx, m.msg.camera == "cam1" ? written1.fx : p.camera_model.fx);
  }
  EXPECT_GT(shifted, 20);
  // The top speed of each moving body, frame to frame.
  auto top_speed = [&](const std::string& dir, const std::string& body) {
    const sim::GroundTruth t = sim::ReadGroundTruth(dir + "/ground_truth_" + body + ".yaml");
    double top = 0;
    for (size_t f = 1; f < t.frames.size(); ++f)
      top = std::max(
          top,
          (t.frames[f].rig_from_object.translation() - t.frames[f - 1].rig_from_object.translation()).norm() *
              t.fps);
    return top;
  };
  const std::string slow = Tmp() / "bodies_slow", fast = Tmp() / "bodies_fast";
  const std::string long_base = " --scene bodies --frames 300 --cameras 2 --seed 5 --detections-only --quiet";
  r = RunProgram(kSim, "--out " + slow + long_base);
  ASSERT_EQ(r.code, 0) << r.err;
  r = RunProgram(kSim, "--out " + fast + long_base + " --max-speed-m-s 1.5");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const std::string body : {"tool", "patient"}) {
    const double before = top_speed(slow, body), after = top_speed(fast, body);
    std::printf("%s: top speed %.3f m/s (default motion %.3f)\n", body.c_str(), after, before);
    EXPECT_LT(before, 0.3) << body;
    EXPECT_GT(after, 1.5 - 0.06 - 0.04) << body;  // less the push, and chords 2.5 % short
    EXPECT_LT(after, 1.5 + 0.06) << body;
  }
}

TEST(SimProcess, ExplicitDefaultsAreTheDefaults) {
  const std::string base = " --frames 2 --cameras 2 --detections-only --quiet";
  auto truth_text = [&](const std::string& name, const std::string& extra) {
    const std::string dir = Tmp() / name;
    const Result r = RunProgram(kSim, "--out " + dir + base + extra);
    EXPECT_EQ(r.code, 0) << extra << ": " << r.err;
    return mcmt::test::ReadText(dir + "/ground_truth.yaml");
  };
  const std::string plain = truth_text("defaults", "");
  EXPECT_EQ(truth_text("explicit_defaults", " --camera-height -1 --marker-size -1"), plain);
  const sim::GroundTruth t = sim::ReadGroundTruth(Tmp() / "defaults/ground_truth.yaml");
  EXPECT_NEAR(t.cameras[0].rig_from_cam.translation().z(), 0.5, 1e-12);  // half the 1 m radius
  EXPECT_EQ(t.marker_size, 0.04);
  truth_text("other", " --camera-height 0.3 --marker-size 0.05");
  const sim::GroundTruth o = sim::ReadGroundTruth(Tmp() / "other/ground_truth.yaml");
  EXPECT_NEAR(o.cameras[0].rig_from_cam.translation().z(), 0.3, 1e-12);
  EXPECT_EQ(o.marker_size, 0.05);
}

TEST(SimProcess, BadOptionsGiveOneLineNamingTheOption) {
  const std::string out = Tmp() / "bad_out";
  const std::string file = Tmp() / "a_file";
  std::ofstream(file) << "x";
  struct Case {
    std::string args, named;
  };
  const std::vector<Case> cases = {
      {"--out " + out + " --bogus 1", "--bogus"},
      {"--out " + out + " --cameras 0", "--cameras"},
      {"--out " + out + " --cameras two", "--cameras"},
      {"--out " + out + " --object blob", "blob"},
      {"--out " + out + " --object blob", "--object"},
      {"--out " + out + " --image-size 12", "--image-size"},
      {"--out " + out + " --image-size 12x8", "--image-size"},
      {"--out " + out + " --dictionary NOPE", "NOPE"},
      {"--out " + out + " --dictionary NOPE", "--dictionary"},
      {"--frames 3", "--out"},
      {"--out " + out + " --frames -1", "--frames"},
      {"--out " + out + " --frames 0", "--frames"},
      {"--out " + out + " --fps 0", "--fps"},
      {"--out " + out + " --hfov-deg 180", "--hfov-deg"},
      {"--out " + out + " --distortion wobbly", "--distortion"},
      {"--out " + out + " --miss-rate 1.5", "--miss-rate"},
      {"--out " + out + " --threads 0", "--threads"},
      {"--out " + out + " --frames", "--frames"},
      {"--out " + out + " --video --detections-only", "--video"},
      {"--out " + out + " --intrinsics-error cam1,3,8", "--intrinsics-error"},
      {"--out " + out + " --intrinsics-error cam1,x,8,0", "--intrinsics-error"},
      {"--out " + out + " --intrinsics-error cam9,3,8,0", "cam9"},
      {"--out " + out + " --clock cam1", "--clock"},
      {"--out " + out + " --clock cam7,5", "cam7"},
      {"--out " + out + " --clock cam1,5 --clock cam1,6", "--clock"},
      {"--out " + out + " --max-speed-m-s -1", "--max-speed-m-s"},
      {"--out " + file + "/sub --frames 2", "--out"},
      {"--out " + file + "/sub --frames 2", file + "/sub"},
  };
  for (const Case& c : cases) {
    const Result r = RunProgram(kSim, c.args);
    SCOPED_TRACE(c.args);
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_TRUE(!r.err.empty() && r.err.back() == '\n') << r.err;
    EXPECT_NE(r.err.find(c.named), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("mcmt-sim"), 0u) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_FALSE(fs::exists(out + "/ground_truth.yaml")) << "files written despite the error";
  }
}

// ---------------------------------------------------------------------------------------------
// mcmt-eval

TEST(SimProcess, EvalOfAMapConvertedFromGroundTruth) {
  const std::string dir = Tmp() / "eval";
  ASSERT_EQ(
      RunProgram(kSim, "--out " + dir + " --frames 20 --cameras 4 --seed 3 --detections-only --quiet").code,
      0);
  const sim::GroundTruth truth = sim::ReadGroundTruth(dir + "/ground_truth.yaml");
  std::vector<TrajectoryRow> trajectory;
  RigMap map = sim::MapFromGroundTruth(truth, 1, 2, &trajectory);
  WriteMap(dir + "/map.yaml", map);
  WriteTrajectory(dir + "/trajectory.csv", trajectory);
  const std::string gt_arg = " --ground-truth " + dir + "/ground_truth.yaml";
  {
    const Result r = RunProgram(
        kEval, gt_arg + " --map " + dir + "/map.yaml --trajectory " + dir + "/trajectory.csv --json");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    for (const char* key : {"mean", "median", "max", "rms"}) {
      const std::vector<double> v = JsonNumbers(r.out, key);
      EXPECT_EQ(v.size(), 6u) << key << "\n" << r.out;  // 6 statistics
      for (double x : v) EXPECT_LT(std::abs(x), 1e-6) << key << "\n" << r.out;
    }
    EXPECT_EQ(JsonNumbers(r.out, "frames_with_pose"), std::vector<double>{20}) << r.out;
    EXPECT_EQ(JsonNumbers(r.out, "mapped"), (std::vector<double>{4, 4})) << r.out;
  }
  {
    // The table (default output) also exits 0.
    const Result r = RunProgram(kEval, gt_arg + " --map " + dir + "/map.yaml");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("camera position error (mm)"), std::string::npos) << r.out;
  }
  {
    // A 1 mm radial shift of cam3: (N-1)/N mm for it and 1/N mm for the others (see test_sim_eval).
    RigMap shifted = map;
    Eigen::Vector3d radial = truth.cameras[3].rig_from_cam.translation();
    radial.z() = 0;
    shifted.cameras[3].rig_from_cam.translation() +=
        Inverse(truth.cameras[1].rig_from_cam).linear() * (0.001 * radial.normalized());
    WriteMap(dir + "/shifted.yaml", shifted);
    const Result r = RunProgram(kEval, gt_arg + " --map " + dir + "/shifted.yaml --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::vector<double> per = JsonNumbers(r.out, "position_mm");
    ASSERT_EQ(per.size(), 4u) << r.out;  // the per-camera values (the summary is an object)
    EXPECT_NEAR(per[0], 0.25, 1e-6);
    EXPECT_NEAR(per[1], 0.25, 1e-6);
    EXPECT_NEAR(per[2], 0.25, 1e-6);
    EXPECT_NEAR(per[3], 0.75, 1e-6);
    EXPECT_NE(r.out.find("\"object\": null"), std::string::npos) << r.out;
  }
  {
    // A camera the ground truth lacks: one line naming it, non-zero exit.
    RigMap wrong = map;
    wrong.cameras[2].name = "camZ";
    WriteMap(dir + "/wrong.yaml", wrong);
    const Result r = RunProgram(kEval, gt_arg + " --map " + dir + "/wrong.yaml --json");
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("camZ"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
  }
  {
    // A trajectory row with a seq the ground truth lacks.
    std::vector<TrajectoryRow> more = trajectory;
    more.back().seq = 4321;
    WriteTrajectory(dir + "/more.csv", more);
    const Result r =
        RunProgram(kEval, gt_arg + " --map " + dir + "/map.yaml --trajectory " + dir + "/more.csv");
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("4321"), std::string::npos) << r.err;
  }
  // Missing files: one line naming the file.
  for (const std::string& args :
       {gt_arg + " --map " + dir + "/absent_map.yaml",
        " --ground-truth " + dir + "/absent_gt.yaml --map " + dir + "/map.yaml",
        gt_arg + " --map " + dir + "/map.yaml --trajectory " + dir + "/absent_traj.csv"}) {
    const Result r = RunProgram(kEval, args);
    SCOPED_TRACE(args);
    EXPECT_NE(r.code, 0);
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("absent_"), std::string::npos) << r.err;
  }
  const Result help = RunProgram(kEval, "--help");
  EXPECT_EQ(help.code, 0);
  for (const char* name : {"--ground-truth", "--map", "--trajectory", "--json"})
    EXPECT_NE(help.out.find(name), std::string::npos) << name;
}

// ---------------------------------------------------------------------------------------------
// mcmt-markers (marker sheets themselves are covered by test_marker_sheet)

TEST(SimProcess, MarkersHelpAndBadIds) {
  const Result help = RunProgram(kMarkers, "--help");
  EXPECT_EQ(help.code, 0);
  for (const char* name : {"--out", "--ids", "--size", "--dictionary"})
    EXPECT_NE(help.out.find(name), std::string::npos) << name;
  const std::string out = Tmp() / "sheet.pdf";
  const Result bad = RunProgram(kMarkers, "--out " + out + " --ids 1,x,3");
  EXPECT_NE(bad.code, 0);
  EXPECT_EQ(Lines(bad.err), 1) << bad.err;
  EXPECT_NE(bad.err.find("'x'"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(out));
}
