// ParallelFor for the mapper's stages: fn(i) for i in [0, n) on up to `threads` threads, in chunks of 64
// (each i writes only its own outputs, so results do not depend on the thread count).
#pragma once

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace mcmt {

template <typename Fn>
void ParallelFor(int n, int threads, const Fn& fn) {
  threads = std::max(1, std::min(threads, n / 64 + 1));
  if (threads == 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<int> next{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      for (;;) {
        const int begin = next.fetch_add(64);
        if (begin >= n) return;
        for (int i = begin; i < std::min(n, begin + 64); ++i) fn(i);
      }
    });
  for (auto& th : pool) th.join();
}

}  // namespace mcmt
