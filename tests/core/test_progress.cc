// core/progress.h: on a terminal (a pty here) a bar redrawn in place with rate and ETA; elsewhere (a
// pipe) plain lines at the period, no escape codes; both end with the final count and elapsed time.
#include <gtest/gtest.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>

#include "core/progress.h"

namespace {

// Runs a 40-step job with Progress in a child whose stderr is a pty (terminal) or a pipe; returns what
// the child wrote there.
std::string ChildOutput(bool terminal) {
  int read_fd = -1, write_fd = -1;
  if (terminal) {
    if (::openpty(&read_fd, &write_fd, nullptr, nullptr, nullptr) != 0) return "openpty failed";
  } else {
    int fds[2];
    if (::pipe(fds) != 0) return "pipe failed";
    read_fd = fds[0];
    write_fd = fds[1];
  }
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(write_fd, 2);
    ::close(read_fd);
    {
      mcmt::Progress progress("job", 40, "frames", mcmt::Progress::Mode::kAuto, 0.1);
      for (int i = 1; i <= 40; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        progress.Update(i);
      }
      progress.Finish();
    }
    ::_exit(0);
  }
  ::close(write_fd);
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = ::read(read_fd, buf, sizeof(buf))) > 0;) out.append(buf, static_cast<size_t>(n));
  ::close(read_fd);  // a pty's master reads EIO once the child has closed the slave
  int status = 0;
  ::waitpid(pid, &status, 0);
  return out;
}

}  // namespace

TEST(Progress, OnATerminalABarWithRateAndEtaRedrawnInPlace) {
  const std::string out = ChildOutput(true);
  EXPECT_NE(out.find("\r\033[Kjob ["), std::string::npos) << out;
  EXPECT_NE(out.find("frames/s  ETA 0:0"), std::string::npos) << out;
  EXPECT_NE(out.find("100 % 40/40 frames"), std::string::npos) << out;
  EXPECT_NE(out.find("done in 0:0"), std::string::npos) << out;
  // Redrawn, not scrolled: one line in all (the pty turns "\n" into "\r\n").
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
}

TEST(Progress, ElsewherePlainLinesAtThePeriodWithoutEscapeCodes) {
  const auto start = std::chrono::steady_clock::now();
  const std::string out = ChildOutput(false);
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(out.find('\r'), std::string::npos) << out;
  EXPECT_EQ(out.find('\033'), std::string::npos) << out;
  EXPECT_EQ(out.find('['), std::string::npos) << out;
  // One line per 0.1 s period (the job sleeps 40 x 10 ms, longer on a loaded machine), plus the final
  // line: never one line per update.
  const long lines = std::count(out.begin(), out.end(), '\n');
  EXPECT_GE(lines, 3) << out;
  EXPECT_LE(lines, static_cast<long>(elapsed_s / 0.1) + 2) << out;
  EXPECT_LT(lines, 40) << out;
  EXPECT_NE(out.find("job: "), std::string::npos) << out;
  EXPECT_NE(out.find(" frames/s, ETA 0:0"), std::string::npos) << out;
  EXPECT_NE(out.find("job: 100 % 40/40 frames, "), std::string::npos) << out;
  // The elapsed time rounds to whole seconds: 0:00 or 0:01 for a job of about half a second.
  EXPECT_NE(out.find(", done in 0:0"), std::string::npos) << out;
  EXPECT_EQ(out.back(), '\n') << out;
}

TEST(Progress, FormatWithAndWithoutATotal) {
  EXPECT_EQ(mcmt::Progress::Format("replay", 30, 120, "kB", 10.0, false, false),
            "replay: 25 % 30/120 kB, 3.0 kB/s, ETA 0:30");
  EXPECT_EQ(mcmt::Progress::Format("replay", 30, 120, "kB", 10.0, true, false),
            "replay [######..................]  25 % 30/120 kB  3.0 kB/s  ETA 0:30");
  EXPECT_EQ(mcmt::Progress::Format("reading", 5000, 0, "messages", 2.0, false, true),
            "reading: 5000 messages, 2500.0 messages/s, done in 0:02");
  EXPECT_EQ(mcmt::Progress::Format("long", 1, 4000, "frames", 1.0, false, false),
            "long: 0 % 1/4000 frames, 1.0 frames/s, ETA 1:06:39");
}
