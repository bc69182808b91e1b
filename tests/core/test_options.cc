// core/options.h: one declaration per key feeds loading, checking (file or code) and the docs table.
#include <gtest/gtest.h>

#include "core/options.h"

namespace mcmt {
namespace {

struct DemoOptions {
  double gap_ms = 3.0;
  int rounds = 2;
  bool fast = false;
  std::string mode = "a";
};

const OptionTable<DemoOptions>& DemoTable() {
  using O = DemoOptions;
  static const OptionTable<O>* t = &(*new OptionTable<O>("demo"))
                                        .Add("gap_ms", &O::gap_ms, "ms", "a gap", Above(0))
                                        .Add("rounds", &O::rounds, "", "rounds", InRange(1, 5))
                                        .Add("fast", &O::fast, "go fast")
                                        .Add("mode", &O::mode, "the mode", OneOf({"a", "b"}))
                                        .Deprecated("gap_us", "gap_ms", 1e-3);
  return *t;
}

YamlSection Section(const std::string& yaml) { return YamlSection(YAML::Load(yaml), "rig.yaml", "demo"); }

std::string LoadError(const std::string& yaml) {
  DemoOptions o;
  try {
    DemoTable().Load(Section(yaml), &o);
  } catch (const OptionError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Options, LoadsDeclaredKeysAndKeepsDefaults) {
  DemoOptions o;
  DemoTable().Load(Section("{gap_ms: 4.5, fast: true}"), &o);
  EXPECT_EQ(o.gap_ms, 4.5);
  EXPECT_EQ(o.rounds, 2);
  EXPECT_TRUE(o.fast);
  EXPECT_EQ(o.mode, "a");
}

TEST(Options, ErrorsNameFileAndKey) {
  EXPECT_EQ(LoadError("{gap_ms: 0}"), "rig.yaml: demo.gap_ms: must be > 0, got 0");
  EXPECT_EQ(LoadError("{rounds: 9}"), "rig.yaml: demo.rounds: must be in [1, 5], got 9");
  EXPECT_EQ(LoadError("{mode: c}"), "rig.yaml: demo.mode: expected one of a, b, got 'c'");
  EXPECT_EQ(LoadError("{gap_ms: abc}"), "rig.yaml: demo.gap_ms: expected a number, got 'abc'");
  EXPECT_NE(LoadError("{gapms: 1}").find("rig.yaml: demo.gapms: unknown key"), std::string::npos)
      << LoadError("{gapms: 1}");
}

TEST(Options, OptionsBuiltInCodeGetTheSameChecks) {
  DemoOptions o;
  EXPECT_NO_THROW(DemoTable().Check(o));
  o.rounds = 0;
  try {
    DemoTable().Check(o);
    FAIL() << "rounds 0 passed";
  } catch (const OptionError& e) {
    EXPECT_STREQ(e.what(), "demo.rounds: must be in [1, 5], got 0");
    EXPECT_EQ(e.key(), "demo.rounds");
    EXPECT_EQ(e.file(), "");
  }
}

TEST(Options, DeprecatedKeyIsReadInTheNewUnitAndTheNewKeyWins) {
  DemoOptions o;
  DemoTable().Load(Section("{gap_us: 2500}"), &o);
  EXPECT_DOUBLE_EQ(o.gap_ms, 2.5);
  DemoTable().Load(Section("{gap_us: 2500, gap_ms: 7}"), &o);
  EXPECT_EQ(o.gap_ms, 7.0);
  EXPECT_EQ(LoadError("{gap_us: -5}"), "rig.yaml: demo.gap_ms: must be > 0, got -0.005");
}

TEST(Options, MarkdownTableHasEveryKeyWithUnitDefaultAndCheck) {
  const std::string md = DemoTable().Markdown();
  EXPECT_NE(
      md.find("| `gap_ms` | ms | `3` | must be > 0 | a gap (old key `gap_us` still read, deprecated) |"),
      std::string::npos)
      << md;
  EXPECT_NE(md.find("| `rounds` |  | `2` | must be in [1, 5] | rounds |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `fast` |  | `false` |  | go fast |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `mode` |  | `a` | expected one of a, b | the mode |"), std::string::npos) << md;
}

TEST(Options, SyncSectionChecksItsKeys) {
  SyncOptions o;
  EXPECT_THROW(SyncOptionTable().Load(YamlSection(YAML::Load("{tolerance: 3}"), "r.yaml", "sync"), &o),
               OptionError);
  try {
    SyncOptionTable().Load(YamlSection(YAML::Load("{deadline_ms: 0}"), "r.yaml", "sync"), &o);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_STREQ(e.what(), "r.yaml: sync.deadline_ms: must be > 0, got 0");
  }
}

}  // namespace
}  // namespace mcmt
