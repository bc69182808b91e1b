// ArgParser: values, checks declared with the option, usage errors and --help.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/cli.h"

namespace mcmt {
namespace {

// Parses `words` (the program name first); *err: what it wrote on stderr.
bool ParseWords(ArgParser* args, std::vector<std::string> words, int* exit_code, std::string* err) {
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  testing::internal::CaptureStderr();
  const bool go_on = args->Parse(static_cast<int>(argv.size()), argv.data(), exit_code);
  *err = testing::internal::GetCapturedStderr();
  return go_on;
}

struct Values {
  double radius = 1.0;
  int cameras = 5;
  std::string scene = "object";
};

void Declare(ArgParser* args, Values* v) {
  args->AddDouble("radius", &v->radius, "circle radius, metres", InRange(0.1, 100));
  args->AddInt("cameras", &v->cameras, "cameras", InRange(1, 64));
  args->AddString("scene", &v->scene, "what is simulated", false, OneOf({"object", "bodies"}));
}

TEST(ArgParser, ValuesTheirChecksAcceptAreSet) {
  ArgParser args("prog", "summary");
  Values v;
  Declare(&args, &v);
  int code = -1;
  std::string err;
  EXPECT_TRUE(
      ParseWords(&args, {"prog", "--radius", "2.5", "--cameras=64", "--scene", "bodies"}, &code, &err));
  EXPECT_EQ(err, "");
  EXPECT_EQ(v.radius, 2.5);
  EXPECT_EQ(v.cameras, 64);
  EXPECT_EQ(v.scene, "bodies");
}

TEST(ArgParser, AValueItsCheckRefusesIsAUsageErrorNamingTheOption) {
  struct Case {
    std::vector<std::string> words;
    std::string line;
  };
  const std::vector<Case> cases = {
      {{"prog", "--radius", "200"}, "prog: error: --radius: must be in [0.1, 100], got '200' (see --help)\n"},
      {{"prog", "--radius=nan"}, "prog: error: --radius: must be in [0.1, 100], got 'nan' (see --help)\n"},
      {{"prog", "--cameras", "0"}, "prog: error: --cameras: must be in [1, 64], got '0' (see --help)\n"},
      {{"prog", "--scene", "room"},
       "prog: error: --scene: expected one of object, bodies, got 'room' (see --help)\n"},
      {{"prog", "--cameras", "2.5"}, "prog: error: --cameras: expected an integer, got '2.5' (see --help)\n"},
  };
  for (const Case& c : cases) {
    ArgParser args("prog", "summary");
    Values v;
    Declare(&args, &v);
    int code = -1;
    std::string err;
    EXPECT_FALSE(ParseWords(&args, c.words, &code, &err)) << c.line;
    EXPECT_EQ(code, 2);
    EXPECT_EQ(err, c.line);
  }
}

TEST(ArgParser, HelpShowsEachOptionsDefaultAndCheck) {
  ArgParser args("prog", "summary");
  Values v;
  Declare(&args, &v);
  const std::string help = args.Help();
  EXPECT_NE(help.find("circle radius, metres (default: 1; must be in [0.1, 100])"), std::string::npos)
      << help;
  EXPECT_NE(help.find("what is simulated (default: object; expected one of object, bodies)"),
            std::string::npos)
      << help;
}

}  // namespace
}  // namespace mcmt
