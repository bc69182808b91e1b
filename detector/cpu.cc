#include "detector/cpu.h"

#include <atomic>
#include <cstdlib>
#include <cstring>

namespace mcmt {
namespace {

// Whether the AVX2 code runs: the CPU has it and MCMT_NO_AVX2 is unset or "0" (read once), or as the test
// hook UseDetectorAvx2 set it.
std::atomic<bool>& Avx2Chosen() {
  static std::atomic<bool> chosen{
      DetectorAvx2Available() &&
      !(std::getenv("MCMT_NO_AVX2") && std::strcmp(std::getenv("MCMT_NO_AVX2"), "0"))};
  return chosen;
}

}  // namespace

bool DetectorAvx2Available() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)  // the AVX2 code's build condition
  __builtin_cpu_init();  // (where called before the constructors that run it: static initialisers)
  return __builtin_cpu_supports("avx2");  // (libgcc: also that the OS saves the AVX registers)
#else
  return false;
#endif
}

bool DetectorUsesAvx2() { return Avx2Chosen().load(std::memory_order_relaxed); }

bool UseDetectorAvx2(bool use) {
  return Avx2Chosen().exchange(use && DetectorAvx2Available(), std::memory_order_relaxed);
}

}  // namespace mcmt
