// Stopping a long-running loop: a StopToken is handed to whatever runs (a node's Collect or Run), which
// polls stop_requested(); whoever owns the token (a signal, a test, another thread) calls request_stop().
// Copies share one flag. Nothing is global but the one token the signal helper owns.
//
//   int main(...) {                              // every mcmt main
//     const mcmt::StopToken stop = mcmt::StopOnSignals();   // SIGINT, SIGTERM -> stop
//     node.Run(stop);
//   }
#pragma once

#include <atomic>
#include <csignal>
#include <memory>
#include <vector>

namespace mcmt {

class StopToken {
 public:
  StopToken() : flag_(std::make_shared<std::atomic<bool>>(false)) {}
  bool stop_requested() const { return flag_->load(); }
  void request_stop() const { flag_->store(true); }
  // For code that waits on a plain atomic (and for the signal handler, which may touch nothing else).
  std::atomic<bool>& flag() const { return *flag_; }

 private:
  std::shared_ptr<std::atomic<bool>> flag_;
};

// The process's signal token: from now on each of `signals` requests a stop of the returned token (the
// same token at every call). Handlers are installed without SA_RESTART, so a blocking receive returns
// (EINTR) and the loop sees the request at once.
StopToken StopOnSignals(const std::vector<int>& signals = {SIGINT, SIGTERM});
// Back to the default action (a second Ctrl-C during a long final step ends the process).
void DefaultSignals(const std::vector<int>& signals = {SIGINT, SIGTERM});

}  // namespace mcmt
