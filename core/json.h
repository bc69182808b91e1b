// JSON text for the reports (mapper report.json, mcmt-eval --json): one string writer for every file.
#pragma once

#include <string>

namespace mcmt {

// `s` as a JSON string literal, quotes included: '"' and '\' escaped, every control character (below
// 0x20, and DEL) written as \n, \t, ... or \u00XX, so that any name (a camera called "cam\t0") gives valid
// JSON. Other bytes (UTF-8) pass through unchanged.
std::string JsonString(const std::string& s);

// A finite number with 10 significant digits; `null` for NaN and infinities (JSON has no such numbers).
std::string JsonNumber(double v);

}  // namespace mcmt
