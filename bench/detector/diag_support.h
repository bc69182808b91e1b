// Small helpers shared by the detector's diagnostic programs (bench/detector/diag_*), not the detector's
// own math.
#pragma once

#include <cmath>
#include <cstdlib>

namespace mcmt::diag {

// The environment variable `key` as a number; `fallback` where it is unset.
inline double Env(const char* key, double fallback) {
  const char* value = std::getenv(key);
  return value ? std::atof(value) : fallback;
}

// The standard normal distribution function to double precision (erfc): the exact reference, not the
// detector's faster approximation (PhiAndDensityOf in detector/side_model.h).
inline double Phi(double z) { return 0.5 * std::erfc(-z * M_SQRT1_2); }

}  // namespace mcmt::diag
