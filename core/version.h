// The version of mcmt that a program or file comes from: the project version of CMakeLists.txt, plus
// `git describe` of the source tree at build time when it was built from a git checkout, e.g.
// "0.1.0 (git 75ef3b2-dirty)". Printed by every program's --version (core/cli.h) and recorded in
// map.yaml (written_by) and report.json (mcmt_version).
#pragma once

namespace mcmt {

const char* Version();

}  // namespace mcmt
