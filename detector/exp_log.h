// exp and log without a library call, for the refinement's hot paths (the side model and the boundaries'
// Phi): the same values on every x86-64 machine. glibc's exp and log pick an FMA variant at run time
// where the CPU has FMA (__ieee754_exp_fma), so their last bits, and then a corner's, could differ between
// machines. These use only IEEE additions and multiplications in a fixed order (no fused multiply-add: the
// project compiles for plain x86-64, and side_model_lanes.inc's AVX2 target does not enable FMA), and
// their two- and four-lane copies (ExpInline2 / 4, LogInline2 / 4 in side_model_lanes.inc) give the same
// values lane by lane.
//
// Accuracy against the exact function (SideModel.ExpInlineAndLogInlineAreWithinTheirBounds, against long
// double expl / logl): ExpInline relative error below 2.5e-16 (measured 1.73e-16, 1.15 ulp) for |x| < 700;
// LogInline relative error below 4e-16 (measured 3.28e-16, 2 ulp) for positive normal x. Outside those
// ranges (and for NaN) both call std::exp / std::log.
// In bench_detector's 10 accurate 640 px frames, the 177,000 exponentials of PhiAndDensity (the
// rays' Phi in CollectSideRays, PaperLevel, DetrendSurround) and FillBoundary took 9.31 M instructions in
// libm (52 per call, the call included) (expcost).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace mcmt {

// ExpInline: x = k ln 2 + r with |r| <= ln 2 / 2 (ln 2 in two parts, the first exact times k), e^r by its
// Taylor series to r^13 (truncation below 1e-17), times 2^k set in the exponent's bits.
// 1.5 * 2^52: adding and subtracting it rounds to an integer.
constexpr double kExpRound = 6755399441055744.0;
constexpr double kLn2High = 0.6931471803691238, kLn2Low = 1.9082149292705877e-10;
constexpr double kInverseFactorial[14] = {
    1.0,        1.0,         1.0 / 2,      1.0 / 6,       1.0 / 24,       1.0 / 120,       1.0 / 720,
    1.0 / 5040, 1.0 / 40320, 1.0 / 362880, 1.0 / 3628800, 1.0 / 39916800, 1.0 / 479001600, 1.0 / 6227020800};

// exp(x).
inline double ExpInline(double x) {
  if (!(std::abs(x) < 700.0)) return std::exp(x);  // also NaN
  const double k = (x * 1.4426950408889634 + kExpRound) - kExpRound;
  const double r = (x - k * kLn2High) - k * kLn2Low;
  double e = kInverseFactorial[13];
  for (int i = 12; i >= 0; --i) e = kInverseFactorial[i] + r * e;
  const uint64_t bits = static_cast<uint64_t>(static_cast<int64_t>(k) + 1023) << 52;
  double two_k;
  std::memcpy(&two_k, &bits, sizeof two_k);
  return e * two_k;
}

// log(x): x = m 2^e with m within [sqrt(1/2), sqrt(2)), log m = 2 atanh(s), s = (m - 1) / (m + 1)
// (|s| <= 0.172), by its series to s^21 (truncation below 1e-17).
inline double LogInline(double x) {
  if (!(x >= 2.2250738585072014e-308 && x <= 1.7976931348623157e308)) return std::log(x);  // also NaN
  uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  int exponent = static_cast<int>((bits >> 52) & 0x7ff) - 1023;
  bits = (bits & 0x000fffffffffffffULL) | 0x3ff0000000000000ULL;
  double m;
  std::memcpy(&m, &bits, sizeof m);
  if (m > M_SQRT2) m *= 0.5, ++exponent;
  const double f = m - 1.0, s = f / (2.0 + f), s2 = s * s;
  double series = 1.0 / 21;
  for (int odd = 19; odd >= 3; odd -= 2) series = 1.0 / odd + s2 * series;
  const double k = exponent;
  return k * kLn2High + (2.0 * s + 2.0 * s * s2 * series + k * kLn2Low);
}

// pow(x, y) = exp(y log x) for positive normal x and finite y, exactly x where y = 1 (linear images:
// gamma 1) and 1 where x = 1; elsewhere (x <= 0, infinities, NaN) std::pow. Relative error at most
// 4.5e-16 |y log x| + 2e-16: LogInline's error times y, then ExpInline's
// (SideModel.PowInlineIsWithinItsBound; measured 2.35e-15, about 10 ulp, for x within [0.5 / 255, 1] and y
// within [0.2, 5]; std::pow: 0.52 ulp).
inline double PowInline(double x, double y) {
  if (y == 1.0) return x;
  if (x == 1.0) return 1.0;
  if (!(x >= 2.2250738585072014e-308 && x <= 1.7976931348623157e308) || !(std::abs(y) < 1e300))
    return std::pow(x, y);
  return ExpInline(y * LogInline(x));
}

}  // namespace mcmt
