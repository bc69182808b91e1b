// The mcmt-mapper process around the Mapper: collects detections from live LCM or a log (core's log
// reader: damage is skipped and reported), shows progress, solves when told, writes the files and
// publishes rig_map2_t on MCMT_MAP and mapper_status_t on MCMT_MAPPER_STATUS.
// Every message is checked where it enters (one-line warnings naming camera and channel): undecodable,
// camera field vs channel, invalid camera model, non-finite corners, a camera model that changes
// mid-stream; repeated messages (same camera, seq, utime) are dropped and counted (report.json
// `duplicates`). From a log, messages are added in capture-time order whatever the order of the events,
// so the result never depends on it.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/lcm_util.h"
#include "core/log_reader.h"
#include "core/stop.h"
#include "mapper/mapper.h"
#include "mcmt/mapper_command_t.hpp"
#include "mcmt/mapper_status_t.hpp"

namespace mcmt {

struct MapperNodeOptions {
  std::string outdir;        // where the files go (required)
  std::string session;       // MapperSession(log): another session's results in outdir are refused
  bool force = false;        // ... unless force (mapper/out_folder.h)
  std::string log_path;      // read detections from this log (core's reader) instead of `input`
  int max_frames = 0;        // > 0: stop collecting after this many frames (max over cameras)
  double max_seconds = 0.0;  // > 0: stop after this long (live: wall time; log: message utime span)
  bool publish = true;       // publish status and map on `output`
  double progress_period_s = 1.0;
  // Image size per camera from the rig's intrinsics files: detections of another size are warned about.
  std::map<std::string, std::pair<int, int>> rig_image_sizes;
  StopToken stop;  // stop collecting and solve when requested (mcmt-mapper: SIGINT, SIGTERM, SIGUSR1)
};

class MapperNode {
 public:
  // `input` delivers MCMT_DETECTIONS_.* (and MCMT_MAPPER_COMMAND when live); `output` (may be the same
  // object, or null for no publishing) receives status and the map.
  MapperNode(lcm::LCM& input, lcm::LCM* output, Mapper& mapper, MapperNodeOptions options, std::ostream& log);
  ~MapperNode();

  // Collects until a stop condition (end of log, solve command, signal flag, --frames/--seconds).
  // Returns a short reason.
  std::string Collect();
  // Solves, writes the files, publishes the map. Throws MapperError (after publishing STATE_FAILED).
  MapResult SolveWriteAndPublish();

  int bad_messages() const { return bad_messages_; }
  int64_t duplicates() const { return duplicates_.count(); }
  // What reading the log found (log mode).
  const LogReadReport& log_report() const { return log_report_; }

 private:
  void OnDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  // Decodes and checks one message; false (with a warning) when it is not to be added.
  bool Decode(const std::string& channel, const void* data, size_t size, detections_t* msg);
  bool Admit(detections_t* msg, const std::string& channel);  // content checks, duplicates
  void AddChecked(const detections_t& msg);
  std::string CollectFromLog();
  bool LimitReached(std::string* reason, double elapsed_s) const;
  void Warn(const std::string& key, const std::string& text);
  void OnCommand(const lcm::ReceiveBuffer* rbuf, const std::string& channel, const mapper_command_t* msg);
  void ShowProgress(bool final_line);
  MapResult SolveAndWrite(std::string* verdicts);  // verdicts: the per-camera lines (diagnostics)
  void PublishStatus(int8_t state, const std::string& message, int iteration = 0, double cost = 0.0,
                     double rms = 0.0);

  lcm::LCM& input_;
  lcm::LCM* output_;
  Mapper& mapper_;
  MapperNodeOptions options_;
  std::ostream& log_;
  std::vector<lcm::Subscription*> subscriptions_;
  bool solve_requested_ = false;
  int bad_messages_ = 0;
  std::map<std::string, int> bad_by_channel_;
  int64_t first_utime_ = INT64_MIN, last_utime_ = INT64_MIN;
  DuplicateFilter duplicates_;
  std::map<std::string, camera_model_t> first_model_;  // per camera
  std::set<std::string> warned_;
  int64_t invalid_messages_ = 0, invalid_markers_ = 0;
  LogReadReport log_report_;
  // Live: every accepted detections message as log events (kept on disk when the solve or write fails).
  std::string collected_;
  int64_t collected_events_ = 0;
  std::string SaveCollected() const;  // returns the path written, "" when it could not be
  bool tty_ = false;
};

}  // namespace mcmt
