// The simulator tests' temporary folder: the one helper of tests/support.
#pragma once

#include "tests/support/temp_dir.h"

namespace mcmt::sim::testing {
using TempDir = mcmt::test::TempDir;
}  // namespace mcmt::sim::testing
