// The one udpm URL of the process tests, on a port no other test run is using. Each test file owns a
// range of base ports (7600-7999; the file's first comment names it). Multicast on a port reaches every
// socket bound to it on the machine, so two runs of the same test at once (a CI clone and a worktree)
// once received each other's messages and both failed. Now a test process claims its port: the first of
// base, base + 400, base + 800, ... (up to 31999) whose lock file it can lock (flock, LOCK_NB), and keeps
// the lock until it exits (the programs it starts inherit it). The same base gives the same port for the
// whole process. tests/e2e/udpm_port.sh does the same for the shell tests.
//
//   lcm::LCM lcm(mcmt::test::UdpmUrl(7741));   // udpm://239.255.76.67:7741?ttl=0, or 8141 if taken, ...
#pragma once

#include <string>

namespace mcmt::test {

constexpr int kUdpmSlotStride = 400;  // ports; every base port lies in 7600-7999
constexpr int kUdpmSlots = 61;        // 7999 + 60 * 400 = 31999, below Linux's ephemeral ports

// The lock file of a port: <temp dir>/mcmt_udpm_<port>.lock.
std::string UdpmLockPath(int port);

// The port this process uses for base (claimed on the first call); throws, naming the lock files, when
// every slot is held.
int UdpmPort(int base);

// "udpm://239.255.76.67:<UdpmPort(base)>?ttl=0": loopback only.
std::string UdpmUrl(int base);

}  // namespace mcmt::test
