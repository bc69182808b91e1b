// The mapper's --out folder: it never silently overwrites another session's results. A session is the
// input the results were computed from: a log (its absolute path) or a live collection (new every time).
#pragma once

#include <string>

namespace mcmt {

// "log /abs/path/session.lcmlog" for a log, "live" for live LCM (empty log).
std::string MapperSession(const std::string& log);

// Creates the output folder when missing and checks that files can be written in it; throws one line
// naming --out otherwise.
void CheckOutputFolder(const std::string& outdir);

// Throws std::runtime_error (one line, naming the folder and what it holds) when `outdir` holds mapper
// results (map.yaml, report.json, trajectory.csv) of another session than `session` -- any results when
// live -- unless `force`. Re-mapping the same log into its own folder is allowed.
void CheckOutFolder(const std::string& outdir, const std::string& session, bool force);

// Records the session beside the results (OUTDIR/.mcmt-session), after they are written.
void RecordSession(const std::string& outdir, const std::string& session);

}  // namespace mcmt
