// The mapper's files: map.yaml, trajectory.csv, report.json and the initial (pre-refinement) pair.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "core/json.h"
#include "core/version.h"
#include "mapper/bodies.h"
#include "mapper/bodies_auto.h"
#include "mapper/diagnostics.h"
#include "mapper/epochs.h"
#include "mapper/intrinsics.h"
#include "mapper/mapper.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

const char* const kOutputFiles[] = {"map.yaml",         "trajectory.csv",         "report.json",
                                    "map_initial.yaml", "trajectory_initial.csv", "residuals.csv",
                                    "objects.yaml"};
constexpr char kStagingMarker[] = ".mcmt-staging-";

bool ProcessAlive(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

// The pid after `marker` at the end of `name` ("map.yaml.tmp.1234", ".out.mcmt-staging-1234"), else -1.
long PidAfter(const std::string& name, const std::string& marker) {
  const size_t at = name.rfind(marker);
  if (at == std::string::npos || at + marker.size() >= name.size()) return -1;
  const std::string digits = name.substr(at + marker.size());
  if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) return -1;
  return std::stol(digits);
}

// Leftovers of earlier runs that died while writing: temporary files in `out` (WriteFileAtomic's
// NAME.tmp.PID) and staging folders beside it, of processes that are gone.
void RemoveLeftovers(const fs::path& out) {
  std::error_code ec;
  if (fs::is_directory(out, ec))
    for (const auto& e : fs::directory_iterator(out, ec)) {
      const long pid = PidAfter(e.path().filename().string(), ".tmp.");
      if (pid > 0 && !ProcessAlive(pid)) fs::remove_all(e.path(), ec);
    }
  const std::string prefix = "." + out.filename().string() + kStagingMarker;
  for (const auto& e : fs::directory_iterator(out.parent_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const long pid = PidAfter(name, kStagingMarker);
    if (pid > 0 && !ProcessAlive(pid)) fs::remove_all(e.path(), ec);
  }
}

void WriteSet(const std::string& dir, const MapResult& result, const Diagnostics& diagnostics) {
  WriteMap(dir + "/map_initial.yaml", result.initial_map);
  if (result.map.objects.empty()) {
    WriteTrajectory(dir + "/trajectory_initial.csv", result.initial_trajectory);
    WriteTrajectory(dir + "/trajectory.csv", result.trajectory);
  }
  for (size_t k = 0; k < result.map.objects.size(); ++k) {  // several bodies: one per moving body
    if (result.map.objects[k].is_static) continue;
    const std::string& name = result.map.objects[k].name;
    WriteTrajectory(dir + "/trajectory_initial_" + name + ".csv", result.initial_object_trajectories.at(k));
    WriteTrajectory(dir + "/trajectory_" + name + ".csv", result.object_trajectories.at(k));
  }
  WriteFileAtomic(dir + "/residuals.csv", ResidualsCsv(diagnostics));
  if (result.report.auto_bodies.ran)  // objects: auto / ids: auto: the objects: section found
    WriteFileAtomic(dir + "/objects.yaml", result.report.auto_bodies.objects_yaml);
  WriteFileAtomic(dir + "/report.json", WithDiagnostics(ReportJson(result), diagnostics));
  // Last: its presence means the rest is there. With the map's covariance (single-object maps, whose
  // frames are the reference camera's and marker's as in the diagnostics' problem; core/map_covariance.h).
  const bool covariance = result.map.objects.empty() && diagnostics.map_covariance;
  WriteMapWithCovariance(dir + "/map.yaml", result.map, covariance ? &*diagnostics.map_covariance : nullptr);
}

bool IsOutputFile(const std::string& name) {
  for (const char* f : kOutputFiles)
    if (name == f) return true;
  const bool body_trajectory = name.rfind("trajectory_", 0) == 0 && name.size() > 15 &&
                               name.compare(name.size() - 4, 4, ".csv") == 0;  // trajectory_<body>.csv
  return body_trajectory;
}

// Several bodies: what each body's layout and poses came to (map.objects).
std::string ObjectsJson(const RigMap& map) {
  if (map.objects.empty()) return "";
  std::ostringstream j;
  j << "  \"objects\": [\n";
  for (size_t i = 0; i < map.objects.size(); ++i) {
    const MapObject& o = map.objects[i];
    j << "    {\"name\": " << JsonString(o.name) << ", \"static\": " << (o.is_static ? "true" : "false")
      << ", \"reference_marker\": " << o.reference_marker << ", \"markers\": [";
    for (size_t m = 0; m < o.markers.size(); ++m) j << (m ? ", " : "") << o.markers[m].id;
    j << "], \"observations\": " << o.num_observations << ", \"rms_px\": " << JsonNumber(o.rms_px)
      << ", \"frames\": " << o.num_frames << (o.name == map.rig_frame ? ", \"rig_frame\": true" : "") << "}"
      << (i + 1 < map.objects.size() ? "," : "") << "\n";
  }
  j << "  ],\n";
  return j.str();
}

// Can `out` be replaced as a whole? Not when it holds folders that are not ours, or holds the current
// directory (a shell there would be left in a deleted folder).
bool Swappable(const fs::path& out) {
  std::error_code ec;
  const fs::path cwd = fs::weakly_canonical(fs::current_path(ec), ec);
  const fs::path canonical = fs::weakly_canonical(out, ec);
  const std::string c = cwd.string() + "/", o = canonical.string() + "/";
  if (c.rfind(o, 0) == 0) return false;
  for (const auto& e : fs::directory_iterator(out, ec))
    if (e.is_directory(ec) && !e.is_symlink(ec)) return false;
  return true;
}

// Atomically exchanges `staging` and `out` (both exist); the old set ends at `staging`.
void Exchange(const fs::path& staging, const fs::path& out) {
  if (::renameat2(AT_FDCWD, staging.c_str(), AT_FDCWD, out.c_str(), RENAME_EXCHANGE) == 0) return;
  if (errno != EINVAL && errno != ENOSYS)
    throw std::runtime_error("cannot replace " + out.string() + ": " + std::strerror(errno));
  // No exchange on this file system: out is briefly absent, never mixed.
  const fs::path old = staging.string() + ".old";
  fs::rename(out, old);
  fs::rename(staging, out);
  fs::rename(old, staging);
}

}  // namespace

std::string ReportJson(const MapResult& result) {
  const MapReport& r = result.report;
  const RigMap& map = result.map;
  std::ostringstream j;
  j << "{\n";
  j << "  \"mcmt_version\": " << JsonString(Version()) << ",\n";
  j << "  \"reference_camera\": " << JsonString(map.reference_camera) << ",\n";
  j << "  \"reference_marker\": " << map.reference_marker << ",\n";
  j << "  \"detections_messages\": " << r.detections_messages << ",\n";
  j << "  \"frames_assembled\": " << r.frames_assembled << ",\n";
  j << "  \"frames_used\": " << r.frames_used << ",\n";
  j << "  \"observations_total\": " << r.observations_total << ",\n";
  j << "  \"observations_used\": " << r.observations_used << ",\n";
  j << "  \"ambiguous_observations\": " << r.ambiguous_observations << ",\n";
  j << "  \"weak_frames\": " << r.weak_frames << ",\n";
  j << "  \"undecided_frames\": " << r.undecided_frames << ",\n";
  j << "  \"ignored_ids\": " << r.ignored_ids << ",\n";
  j << "  \"duplicates\": " << r.duplicates << ",\n";
  j << "  \"duplicate_examples\": [";
  for (size_t i = 0; i < r.duplicate_examples.size(); ++i)
    j << (i ? ", " : "") << JsonString(r.duplicate_examples[i]);
  j << "],\n";
  j << "  \"initial_rms_px\": " << JsonNumber(r.initial_rms_px) << ",\n";
  j << "  \"final_rms_px\": " << JsonNumber(r.final_rms_px) << ",\n";
  j << "  \"iterations\": " << r.iterations << ",\n";
  j << "  \"solves\": " << r.solves << ",\n";
  j << "  \"termination\": " << JsonString(r.termination) << ",\n";
  j << "  \"linear_solver\": " << JsonString(r.linear_solver) << ",\n";
  j << "  \"threads\": " << r.threads << ",\n";
  j << "  \"seconds\": {";
  for (size_t i = 0; i < r.stage_seconds.size(); ++i)
    j << (i ? ", " : "") << JsonString(r.stage_seconds[i].first) << ": "
      << JsonNumber(r.stage_seconds[i].second);
  j << (r.stage_seconds.empty() ? "" : ", ") << "\"total\": " << JsonNumber(r.total_seconds) << "},\n";
  j << "  \"cameras\": [\n";
  for (size_t i = 0; i < map.cameras.size(); ++i) {
    const MapCamera& c = map.cameras[i];
    j << "    {\"name\": " << JsonString(c.name) << ", \"observations\": " << c.observations
      << ", \"rms_px\": " << JsonNumber(c.rms_px) << ", \"max_px\": " << JsonNumber(c.max_px) << "}"
      << (i + 1 < map.cameras.size() ? "," : "") << "\n";
  }
  j << "  ],\n";
  j << "  \"markers\": [\n";
  for (size_t i = 0; i < map.markers.size(); ++i) {
    const MapMarker& m = map.markers[i];
    j << "    {\"id\": " << m.id << ", \"observations\": " << m.observations
      << ", \"rms_px\": " << JsonNumber(m.rms_px) << ", \"max_px\": " << JsonNumber(m.max_px) << "}"
      << (i + 1 < map.markers.size() ? "," : "") << "\n";
  }
  j << "  ],\n";
  j << ObjectsJson(map);
  j << "  \"rejected_markers\": [\n";
  for (size_t i = 0; i < r.rejected_markers.size(); ++i) {
    const RejectedMarker& m = r.rejected_markers[i];
    j << "    {\"id\": " << m.id << ", \"observations\": " << m.observations
      << ", \"reason\": " << JsonString(m.reason) << "}" << (i + 1 < r.rejected_markers.size() ? "," : "")
      << "\n";
  }
  j << "  ],\n";
  // At most kMaxListed observations are listed (the count is exact).
  constexpr size_t kMaxListed = 5000;
  const size_t listed = std::min(kMaxListed, r.rejected_observations.size());
  j << "  \"rejected_observations_count\": " << r.rejected_observations.size() << ",\n";
  j << "  \"rejected_observations\": [\n";
  for (size_t i = 0; i < listed; ++i) {
    const RejectedObservation& o = r.rejected_observations[i];
    j << "    {\"utime\": " << o.utime << ", \"seq\": " << o.seq << ", \"camera\": " << JsonString(o.camera)
      << ", \"id\": " << o.id << ", \"rms_px\": " << JsonNumber(o.rms_px)
      << ", \"reason\": " << JsonString(o.reason) << "}"
      << (i + 1 < r.rejected_observations.size() ? "," : "") << "\n";
  }
  j << "  ],\n";
  j << "  \"dropped_cameras\": [";
  for (size_t i = 0; i < r.dropped_cameras.size(); ++i)
    j << (i ? ", " : "") << JsonString(r.dropped_cameras[i]);
  j << "],\n";
  j << SelfCalibrationJson(r);
  j << CameraChangesJson(r);
  j << AutoBodiesJson(r.auto_bodies);
  j << "  \"warnings\": [";
  for (size_t i = 0; i < r.warnings.size(); ++i)
    j << (i ? ", " : "") << "\n    " << JsonString(r.warnings[i]);
  j << "]\n";
  j << "}\n";
  return j.str();
}

std::string WriteMapOutputs(const std::string& outdir, const MapResult& result) {
  DiagnosticsOptions options;
  options.marker_size_sigma = result.report.marker_size_sigma_percent / 100.0;
  const Diagnostics diagnostics = ComputeObjectDiagnostics(result, options);  // mapper/diagnostics.h
  const std::string verdicts = VerdictLines(diagnostics);
  fs::path out = fs::absolute(outdir).lexically_normal();
  if (!out.has_filename()) out = out.parent_path();
  std::error_code ec;
  fs::create_directories(out.parent_path(), ec);
  if (ec)
    throw std::runtime_error("cannot create folder " + out.parent_path().string() + ": " + ec.message());
  RemoveLeftovers(out);
  const bool exists = fs::exists(out);
  // Without write access beside `out` (its staging folder goes there), or when it cannot be swapped:
  if (exists &&
      (!Swappable(out) || ::access(out.parent_path().c_str(), W_OK) !=
                              0)) {  // in place: map.yaml (whose presence means the set is whole) last
    fs::remove(out / "map.yaml", ec);
    WriteSet(out.string(), result, diagnostics);
    return verdicts;
  }
  // The whole set in a staging folder beside `out`, then swapped in at once.
  const fs::path staging =
      out.parent_path() / ("." + out.filename().string() + kStagingMarker + std::to_string(::getpid()));
  fs::remove_all(staging, ec);
  if (!fs::create_directory(staging, ec))
    throw std::runtime_error("cannot create folder " + staging.string() + ": " + ec.message());
  try {
    WriteSet(staging.string(), result, diagnostics);
    if (!exists) {
      fs::rename(staging, out);
      return verdicts;
    }
    for (const auto& e : fs::directory_iterator(out)) {  // the user's files stay (hard links)
      const std::string name = e.path().filename().string();
      if (!IsOutputFile(name)) fs::create_hard_link(e.path(), staging / name);
    }
    Exchange(staging, out);
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
  fs::remove_all(staging, ec);  // the old set
  return verdicts;
}

}  // namespace mcmt
