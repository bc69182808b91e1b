// core's JSON string writer: every byte a JSON parser refuses inside a string is escaped.
#include <gtest/gtest.h>

#include <string>

#include "core/json.h"

namespace mcmt {
namespace {

TEST(Json, QuotesBackslashesAndControlCharactersAreEscaped) {
  EXPECT_EQ(JsonString("cam0"), "\"cam0\"");
  EXPECT_EQ(JsonString("a\"b\\c"), "\"a\\\"b\\\\c\"");
  EXPECT_EQ(JsonString("a\tb\nc\rd\be\ff"), "\"a\\tb\\nc\\rd\\be\\ff\"");
  EXPECT_EQ(JsonString(std::string("x\x01y\x1f\x7fz", 6)), "\"x\\u0001y\\u001f\\u007fz\"");
  EXPECT_EQ(JsonString(std::string("a\0b", 3)), "\"a\\u0000b\"");
  EXPECT_EQ(JsonString("caméra"), "\"caméra\"");  // UTF-8 passes through
}

TEST(Json, NoByteBelowSpaceEverReachesTheOutput) {
  std::string all;
  for (int c = 1; c < 256; ++c) all += static_cast<char>(c);
  const std::string out = JsonString(all);
  for (const char c : out) EXPECT_GE(static_cast<unsigned char>(c), 0x20u) << int(c);
  EXPECT_EQ(out.front(), '"');
  EXPECT_EQ(out.back(), '"');
}

}  // namespace
}  // namespace mcmt
