// Every log reader against a few hundred mutated logs (bounded, seeded, deterministic): the core reader,
// the mapper's and the tracker's log input, the viewer's collector, mcmt-eval's trajectory reader and
// mcmt-export, in process; then the real programs on a subset. Asserted for each log:
//  - no crash (a crash ends the test), no exception other than a one-line LogFormatError/FileFormatError;
//  - no silent truncation: when no damage is reported, every event of the original log that the mutation
//    left whole was read (the count of events equals the expected count);
//  - a reported damage reaches the program: exit status 3 (kExitDamagedLog) and the "is damaged" line.
// Mutations: random bytes inserted, bytes overwritten, the file cut at a random byte, a payload length set
// to 0x7FFFFFFF (LCM's own reader crashes on it), a header's sync word destroyed, a region repeated.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include "core/config.h"
#include "core/files.h"
#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "logger/export.h"
#include "mapper/mapper.h"
#include "mapper/node.h"
#include "sim/eval.h"
#include "tests/support/process.h"
#include "tests/support/temp_dir.h"
#include "tracker/tracker.h"
#include "viz/collector.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;
using test::RunProgram;
const std::string kBin = MCMT_BIN_DIR;
constexpr int kLogs = 300;        // in process
constexpr int kProcessLogs = 24;  // also through the real programs

struct Base {
  std::string dir, rig, map, log;
  std::vector<uint64_t> event_ends;  // byte offset after each event of the base log
  std::string bytes;
};

// mcmt-sim detections (60 frames) + mcmt-mapper's map, then a log holding the map, the detections and a
// pose per frame (every channel some reader reads).
Base MakeBase() {
  Base b;
  b.dir = test::MakeTempDir("log_fuzz");
  std::string out;
  EXPECT_EQ(RunProgram({kBin + "/mcmt-sim", "--out", b.dir, "--object", "four_sided", "--frames", "60",
                        "--seed", "3", "--detections-only", "--quiet"},
                       b.dir + "/sim.txt", &out),
            0)
      << out;
  EXPECT_EQ(RunProgram({kBin + "/mcmt-mapper", "--config", b.dir + "/rig.yaml", "--log",
                        b.dir + "/detections.lcmlog", "--out", b.dir + "/map"},
                       b.dir + "/mapper.txt", &out),
            0)
      << out;
  b.rig = b.dir + "/rig.yaml";
  b.map = b.dir + "/map/map.yaml";
  b.log = b.dir + "/base.lcmlog";
  const RigMap map = ReadMap(b.map);
  const std::vector<TrajectoryRow> trajectory = ReadTrajectory(b.dir + "/map/trajectory.csv");
  int64_t n = 0;
  auto add = [&](int64_t t, const std::string& channel, const std::vector<uint8_t>& data) {
    AppendEncodedEvent(n++, t, channel, data.data(), data.size(), &b.bytes);
    b.event_ends.push_back(b.bytes.size());
  };
  add(1, kMapChannel, Encode(ToRigMapMsg(map, 1)));
  size_t pose = 0;
  for (const LogEvent& e : ReadEventLog(b.dir + "/detections.lcmlog")) {
    add(e.timestamp, e.channel, e.data);
    if (pose < trajectory.size() && e.channel == "MCMT_DETECTIONS_CAM0") {
      object_pose_t p{};  // zeroed: num_cameras, num_markers, covariance, ... are encoded
      p.utime = trajectory[pose].utime;
      p.seq = trajectory[pose].seq;
      p.object = "object";
      p.rig_from_object = ToPose3d(trajectory[pose].rig_from_object);
      p.status = object_pose_t::STATUS_TRACKING;
      add(e.timestamp, kPoseChannel, Encode(p));
      ++pose;
    }
  }
  std::ofstream(b.log, std::ios::binary) << b.bytes;
  return b;
}

struct Mutated {
  std::string bytes;
  std::string what;
  int64_t whole_events = 0;  // events of the base log left whole and in place (a lower bound if unsure)
};

// Events of `base` that end at or before `offset` (left whole by a change at or after it).
int64_t EventsBefore(const Base& base, uint64_t offset) {
  return std::upper_bound(base.event_ends.begin(), base.event_ends.end(), offset) - base.event_ends.begin();
}

Mutated Mutate(const Base& base, std::mt19937& rng) {
  Mutated m;
  m.bytes = base.bytes;
  const uint64_t size = base.bytes.size();
  auto at = [&](uint64_t lo, uint64_t hi) { return std::uniform_int_distribution<uint64_t>(lo, hi)(rng); };
  const int64_t all = static_cast<int64_t>(base.event_ends.size());
  switch (at(0, 5)) {
    case 0: {  // random bytes inserted: every event survives, shifted (a lower bound: those before)
      const uint64_t pos = at(0, size), n = at(1, 400);
      std::string junk(n, '\0');
      for (char& c : junk) c = static_cast<char>(at(0, 255));
      m.bytes.insert(pos, junk);
      m.what = "inserted " + std::to_string(n) + " bytes at " + std::to_string(pos);
      m.whole_events = EventsBefore(base, pos);
      break;
    }
    case 1: {  // bytes overwritten
      const uint64_t pos = at(0, size - 1), n = std::min<uint64_t>(at(1, 300), size - pos);
      for (uint64_t i = 0; i < n; ++i) m.bytes[pos + i] = static_cast<char>(at(0, 255));
      m.what = "overwrote " + std::to_string(n) + " bytes at " + std::to_string(pos);
      m.whole_events = EventsBefore(base, pos);
      break;
    }
    case 2: {  // cut
      const uint64_t pos = at(1, size - 1);
      m.bytes.resize(pos);
      m.what = "cut at " + std::to_string(pos);
      m.whole_events = EventsBefore(base, pos);
      break;
    }
    case 3: {  // a payload length of 0x7FFFFFFF
      const int64_t k = static_cast<int64_t>(at(0, all - 1));
      const uint64_t start = k == 0 ? 0 : base.event_ends[k - 1];
      for (int i = 0; i < 4; ++i) m.bytes[start + 24 + i] = static_cast<char>(i == 0 ? 0x7f : 0xff);
      m.what = "payload length 0x7FFFFFFF in event " + std::to_string(k);
      m.whole_events = k;
      break;
    }
    case 4: {  // a sync word destroyed
      const int64_t k = static_cast<int64_t>(at(1, all - 1));
      m.bytes[base.event_ends[k - 1]] = 0x00;
      m.what = "sync word of event " + std::to_string(k) + " destroyed";
      m.whole_events = k;
      break;
    }
    default: {  // a region repeated (a relay glitch)
      const uint64_t pos = at(0, size - 1), n = std::min<uint64_t>(at(1, 500), size - pos);
      m.bytes.insert(pos + n, base.bytes.substr(pos, n));
      m.what = "repeated " + std::to_string(n) + " bytes at " + std::to_string(pos);
      m.whole_events = EventsBefore(base, pos);
      break;
    }
  }
  return m;
}

// Runs the in-process readers on `path`; returns the core report (EXPECTs on the way).
LogReadReport ReadEverywhere(const Base& base, const RigConfig& rig, const RigMap& map,
                             const std::string& path, const Mutated& m) {
  LogReadReport report;
  try {
    report = ForEachLogEvent(path, [](const LogEvent&) { return true; });
  } catch (const LogFormatError& e) {  // not a log at all (its start destroyed): said in one line
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return report;
  }
  if (!report.damaged()) {
    EXPECT_GE(report.events, m.whole_events) << m.what << ": events silently lost";
  }
  EXPECT_LE(report.events, static_cast<int64_t>(base.event_ends.size()) + 1000) << m.what;

  {  // the mapper's log input
    Mapper mapper(MapperOptions::FromConfig(rig));
    lcm::LCM none("memq://");
    MapperNodeOptions o;
    o.outdir = base.dir + "/unused";
    o.log_path = path;
    o.publish = false;
    std::ostringstream log;
    MapperNode node(none, nullptr, mapper, o, log);
    node.Collect();
    EXPECT_EQ(node.log_report().damaged(), report.damaged()) << m.what;
    if (report.damaged()) {
      EXPECT_NE(log.str().find("bytes"), std::string::npos) << m.what << ": damage not reported";
    }
  }
  {  // the tracker's
    lcm::LCM none("memq://");
    TrackerNodeOptions o;
    o.log_mode = true;
    o.quiet = true;
    TrackerNode node(none, rig, o, map);
    const StopToken stop;
    EXPECT_EQ(node.RunLog(path, stop).damaged(), report.damaged()) << m.what;
  }
  {  // the viewer's
    lcm::LCM none("memq://");
    viz::LcmCollector collector(none, 0);
    EXPECT_EQ(collector.ReadLog(path).damaged(), report.damaged()) << m.what;
  }
  try {  // mcmt-eval's: a damaged pose log is refused in one line
    sim::ReadTrajectoryAny(path);
    EXPECT_FALSE(report.damaged()) << m.what;
  } catch (const FileFormatError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  const LogSummary summary = SummarizeLog(path);  // mcmt-export --summary
  EXPECT_EQ(!summary.damage.empty(), report.damaged()) << m.what;
  return report;
}

TEST(LogFuzz, EveryReaderSurvivesAndReportsDamage) {
  for (const char* p : {"mcmt-sim", "mcmt-mapper", "mcmt-tracker", "mcmt-viz", "mcmt-eval", "mcmt-export"})
    if (access((kBin + "/" + p).c_str(), X_OK) != 0) GTEST_SKIP() << p << " not built in " << kBin;
  const auto start = std::chrono::steady_clock::now();
  const Base base = MakeBase();
  const RigConfig rig = LoadRigConfig(base.rig);
  const RigMap map = ReadMap(base.map);
  std::streambuf* cerr = std::cerr.rdbuf();
  std::ostringstream sink;  // the readers' warnings
  int damaged = 0;
  for (int i = 0; i < kLogs; ++i) {
    std::mt19937 rng(1000 + i);
    const Mutated m = Mutate(base, rng);
    const std::string path = base.dir + "/m" + std::to_string(i) + ".lcmlog";
    std::ofstream(path, std::ios::binary) << m.bytes;
    std::cerr.rdbuf(sink.rdbuf());
    const LogReadReport report = ReadEverywhere(base, rig, map, path, m);
    std::cerr.rdbuf(cerr);
    damaged += report.damaged();
    if (i >= kProcessLogs) {
      fs::remove(path);
      continue;
    }
    // The real programs: never a signal; damage gives exit status 3 and the "is damaged" line.
    const int expected = report.damaged() ? kExitDamagedLog : 0;
    std::string out;
    const std::string where = base.dir + "/p" + std::to_string(i);
    const int mapper = RunProgram(
        {kBin + "/mcmt-mapper", "--config", base.rig, "--log", path, "--out", where + "_map", "--no-refine"},
        where + "_mapper.txt", &out);
    EXPECT_LT(mapper, 128) << m.what << "\n" << out;
    if (mapper != 1) {  // 1: too little left to map
      EXPECT_EQ(mapper, expected) << m.what << "\n" << out;
    }
    if (expected) {
      EXPECT_NE(out.find("is damaged"), std::string::npos) << m.what << "\n" << out;
    }
    const int tracker = RunProgram({kBin + "/mcmt-tracker", "--config", base.rig, "--map", base.map, "--log",
                                    path, "--out", where + "_poses.csv", "--quiet"},
                                   where + "_tracker.txt", &out);
    EXPECT_EQ(tracker, expected) << m.what << "\n" << out;
    const int viz = RunProgram({kBin + "/mcmt-viz", "--map", base.map, "--log", path, "--snapshot",
                                where + ".png", "--size", "160x120"},
                               where + "_viz.txt", &out);
    EXPECT_LT(viz, 128) << m.what << "\n" << out;
    const int eval = RunProgram({kBin + "/mcmt-eval", "--ground-truth", base.dir + "/ground_truth.yaml",
                                 "--map", base.map, "--trajectory", path},
                                where + "_eval.txt", &out);
    EXPECT_TRUE(eval == 0 || eval == 1) << m.what << "\n" << out;
    const int summary =
        RunProgram({kBin + "/mcmt-export", "--log", path, "--summary"}, where + "_export.txt", &out);
    EXPECT_LT(summary, 128) << m.what << "\n" << out;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "[ fuzz ] " << kLogs << " mutated logs (" << damaged << " damaged) through 6 readers, "
            << kProcessLogs << " also through 5 programs: " << seconds << " s" << std::endl;
  EXPECT_GT(damaged, kLogs / 3);  // the mutations do damage
  if (!HasFailure()) fs::remove_all(base.dir);
}

}  // namespace
}  // namespace mcmt
