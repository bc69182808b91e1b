// mcmt's detections CSV (det.csv: one row per marker) and its conversion to a log of detections_t, for
// mcmt-export (log -> CSV) and mcmt-import (CSV -> log).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"

namespace mcmt {

extern const char kDetectionsCsvHeader[];  // "utime,seq,camera,id,x0,y0,x1,y1,x2,y2,x3,y3"

// The fields of one CSV line split at commas, blanks (spaces, tabs, a CR) around each trimmed; an empty
// field (also a trailing one, "a,b,") is kept, so that a column count can be checked.
std::vector<std::string> SplitCsv(const std::string& line);

struct CsvToLogResult {
  int64_t rows = 0;
  int64_t messages = 0;
};

// Rows of one (camera, utime, seq) in a row become one detections_t with the camera model and dictionary
// of the rig config, published on MCMT_DETECTIONS_<CAMERA> with the event timestamp = utime. Frames
// without markers have no rows, so they do not come back. Refuses to overwrite `out_log`. Errors name
// the CSV file, line and column.
CsvToLogResult DetectionsCsvToLog(const std::string& csv_path, const RigConfig& rig,
                                  const std::string& out_log);

}  // namespace mcmt
