// The mapper's files: map.yaml, trajectory.csv, report.json and the initial (pre-refinement) pair.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>

#include "core/json.h"
#include "mapper/diagnostics.h"
#include "core/version.h"
#include "mapper/mapper.h"

namespace mcmt {
namespace {

void MakeDirs(const std::string& dir) {
  std::string path;
  std::stringstream ss(dir);
  std::string part;
  if (!dir.empty() && dir[0] == '/') path = "/";
  while (std::getline(ss, part, '/')) {
    if (part.empty()) continue;
    path += part + "/";
    if (mkdir(path.c_str(), 0755) != 0 && errno != EEXIST)
      throw std::runtime_error("cannot create folder " + path + ": " + std::strerror(errno));
  }
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
  j << "  \"warnings\": [";
  for (size_t i = 0; i < r.warnings.size(); ++i)
    j << (i ? ", " : "") << "\n    " << JsonString(r.warnings[i]);
  j << "]\n";
  j << "}\n";
  return j.str();
}

std::string WriteMapOutputs(const std::string& outdir, const MapResult& result) {
  MakeDirs(outdir);
  const std::string dir = outdir.back() == '/' ? outdir : outdir + "/";
  WriteMap(dir + "map_initial.yaml", result.initial_map);
  WriteTrajectory(dir + "trajectory_initial.csv", result.initial_trajectory);
  WriteTrajectory(dir + "trajectory.csv", result.trajectory);
  const Diagnostics diagnostics = ComputeDiagnostics(result);  // mapper/diagnostics.h
  WriteFileAtomic(dir + "residuals.csv", ResidualsCsv(diagnostics));
  WriteFileAtomic(dir + "report.json", WithDiagnostics(ReportJson(result), diagnostics));
  WriteMap(dir + "map.yaml", result.map);  // last: its presence means the rest is there
  return VerdictLines(diagnostics);
}

}  // namespace mcmt
