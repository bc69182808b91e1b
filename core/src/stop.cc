#include "core/stop.h"

namespace mcmt {

namespace {

std::atomic<bool>* g_signal_flag = nullptr;  // the signal token's flag, written only by the handler

void OnStopSignal(int) {
  if (g_signal_flag) g_signal_flag->store(true);
}

}  // namespace

StopToken StopOnSignals(const std::vector<int>& signals) {
  static const StopToken token;
  g_signal_flag = &token.flag();
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART
  for (int s : signals) sigaction(s, &action, nullptr);
  return token;
}

void DefaultSignals(const std::vector<int>& signals) {
  for (int s : signals) std::signal(s, SIG_DFL);
}

}  // namespace mcmt
