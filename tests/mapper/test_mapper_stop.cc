// MapperNode stops through the StopToken it is given: two mappers in one process no longer share a flag
// (was the static MapperNode::StopFlag(): stopping one stopped every mapper).
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "core/stop.h"
#include "mapper/node.h"
#include "tests/support/temp_dir.h"

namespace mcmt {
namespace {

namespace fs = std::filesystem;

std::string CollectReason(const StopToken& stop, const std::string& name, double max_seconds) {
  lcm::LCM lcm("memq://");
  EXPECT_TRUE(lcm.good());
  MapperOptions options;
  options.sizes.default_size = 0.05;
  Mapper mapper(options);
  MapperNodeOptions node_options;
  const test::TempDir tmp("mapper_stop_" + name);
  node_options.outdir = tmp / "out";
  node_options.publish = false;
  node_options.max_seconds = max_seconds;
  node_options.stop = stop;
  std::ostringstream log;
  MapperNode node(lcm, nullptr, mapper, node_options, log);
  return node.Collect();
}

TEST(MapperNodeStop, EachNodeStopsOnItsOwnToken) {
  const StopToken stopped;
  stopped.request_stop();
  EXPECT_EQ(CollectReason(stopped, "a", 0.0), "signal");
  // Another mapper of the same process, with a token nobody stopped, runs to its own limit.
  EXPECT_EQ(CollectReason(StopToken(), "b", 0.2), "time limit");
}

TEST(MapperNodeStop, SignalsRequestAStopOfTheSignalToken) {
  const StopToken stop = StopOnSignals({SIGUSR2});
  EXPECT_FALSE(stop.stop_requested());
  std::raise(SIGUSR2);
  EXPECT_TRUE(stop.stop_requested());
  EXPECT_EQ(CollectReason(stop, "c", 0.0), "signal");
  EXPECT_FALSE(StopToken().stop_requested());  // a new token is not stopped
  DefaultSignals({SIGUSR2});
}

}  // namespace
}  // namespace mcmt
