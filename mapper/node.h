// The mcmt-mapper process around the Mapper: collects detections from live LCM or a log (LCM's
// file:// provider; the same handlers), shows progress, solves when told, writes the files and
// publishes rig_map_t on MCMT_MAP and mapper_status_t on MCMT_MAPPER_STATUS.
#pragma once

#include <atomic>
#include <cstdint>
#include <iosfwd>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>

#include "mapper/mapper.h"
#include "mcmt/mapper_command_t.hpp"
#include "mcmt/mapper_status_t.hpp"

namespace mcmt {

struct MapperNodeOptions {
  std::string outdir;        // where the files go (required)
  std::string session;       // MapperSession(log): another session's results in outdir are refused
  bool force = false;        // ... unless force (mapper/out_folder.h)
  bool from_log = false;     // input is a file:// log: collect until its end
  int max_frames = 0;        // > 0: stop collecting after this many frames (max over cameras)
  double max_seconds = 0.0;  // > 0: stop after this long (live: wall time; log: message utime span)
  bool publish = true;       // publish status and map on `output`
  double progress_period_s = 1.0;
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

  // Set from signal handlers (SIGINT, SIGTERM, SIGUSR1): stop collecting and solve.
  static std::atomic<bool>& StopFlag();

  int bad_messages() const { return bad_messages_; }

 private:
  void OnDetections(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void OnCommand(const lcm::ReceiveBuffer* rbuf, const std::string& channel, const mapper_command_t* msg);
  void ShowProgress(bool final_line);
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
  bool tty_ = false;
};

}  // namespace mcmt
