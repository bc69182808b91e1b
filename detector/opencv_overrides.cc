// mcmt's own definitions of OpenCV functions that cv::aruco::detectMarkers calls: cv::adaptiveThreshold,
// cv::findContours, cv::approxPolyDP, cv::warpPerspective, cv::meanStdDev, cv::countNonZero and
// cv::aruco::Dictionary::identify. The aruco module (a shared library) calls them through the dynamic
// linker, which finds a program's definition before the library's, so these take OpenCV's place for every
// caller. Each computes exactly what OpenCV's does, bit for bit, for the cases the search uses (8-bit
// images, the modes detectMarkers passes), only cheaper; every other case goes to OpenCV's own definition
// (LibraryDefinition: the next one, dlsym(RTLD_NEXT)). They are checked against OpenCV's own at run time by
// test_detector_unit's CandidateSearch.*IsOpenCVs tests, which also check that calls reach these
// definitions.
//
// mcmt_detector is a static archive, and the linker takes an archive member only for a symbol something
// already references: nothing calls these by name, so MarkerDetector calls LinkOpenCvOverrides() (below)
// to bring this file into every program that detects markers.
#include "detector/opencv_overrides.h"

#include <dlfcn.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <opencv2/aruco/dictionary.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "detector/cpu.h"  // DetectorUsesAvx2: the one run-time choice of the AVX2 code

namespace mcmt {
namespace {

// cv::boxFilter's mean of a k x k window of 8-bit pixels where area = k * k <= 256 (its 16-bit sums,
// OpenCV's ColumnSum<ushort, uchar>) is the window sum s scaled as ((s + add) * mul) >> 23, mul 2^23 /
// area rounded and add area / 2 or area / 2 + 1 against its rounding. That mean is at least v exactly
// where s >= area * v - offset for one offset (a pixel's comparison with its window's mean is then one of
// the window sum with a threshold linear in the pixel): the offset, or -1 if not so for every
// v = 1..255 or if the mean could exceed 255.
int BoxMeanThresholdOffset(int area) {
  double exact = static_cast<double>(1 << 23) / area;
  int mul = cvFloor(exact), add = area / 2;
  exact -= mul;
  if (exact < 0.5)
    ++add;
  else
    ++mul;
  auto mean = [&](int sum) { return static_cast<int>((static_cast<uint32_t>(sum + add) * mul) >> 23); };
  int first = 0;  // the smallest sum of mean 1
  while (first <= area && mean(first) < 1) ++first;
  const int offset = area - first;
  if (offset < 0 || offset >= area || mean(255 * area) > 255) return -1;
  for (int v = 1; v <= 255; ++v) {
    const int t = area * v - offset;
    if (mean(t) < v || mean(t - 1) >= v) return -1;
  }
  return offset;
}

// The next row's column sums of a window (16 bits): row `in` enters, row `out` leaves. (Inlined: also the
// AVX2 code's last pixels.)
[[gnu::always_inline]] inline void SlideColumnSums(const uint8_t* in, const uint8_t* out, int w,
                                                   uint16_t* column) {
  int x = 0;
#ifdef __SSE2__
  const __m128i zero = _mm_setzero_si128();
  auto slide = [&](__m128i add, __m128i sub, uint16_t* at) {
    __m128i* c = reinterpret_cast<__m128i*>(at);
    _mm_storeu_si128(c, _mm_sub_epi16(_mm_add_epi16(_mm_loadu_si128(c), add), sub));
  };
  for (; x + 16 <= w; x += 16) {  // 16 pixels of each row per load
    const __m128i add = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + x));
    const __m128i sub = _mm_loadu_si128(reinterpret_cast<const __m128i*>(out + x));
    slide(_mm_unpacklo_epi8(add, zero), _mm_unpacklo_epi8(sub, zero), column + x);
    slide(_mm_unpackhi_epi8(add, zero), _mm_unpackhi_epi8(sub, zero), column + x + 8);
  }
  for (; x + 8 <= w; x += 8)
    slide(_mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(in + x)), zero),
          _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(out + x)), zero), column + x);
#endif
  for (; x < w; ++x) column[x] = static_cast<uint16_t>(column[x] + in[x] - out[x]);
}

// sums[x] = column[x - R] + ... + column[x + R], x < w (column valid from -R to w + R).
template <int R>
[[gnu::always_inline]] inline void WindowSums(const uint16_t* column, int w, uint16_t* sums) {
  int x = 0;
#ifdef __SSE2__
  for (; x + 8 <= w; x += 8) {
    __m128i sum = _mm_loadu_si128(reinterpret_cast<const __m128i*>(column + x - R));
    for (int i = 1 - R; i <= R; ++i)
      sum = _mm_add_epi16(sum, _mm_loadu_si128(reinterpret_cast<const __m128i*>(column + x + i)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(sums + x), sum);
  }
#endif
  for (; x < w; ++x) {
    int sum = 0;
    for (int i = -R; i <= R; ++i) sum += column[x + i];
    sums[x] = static_cast<uint16_t>(sum);
  }
}

// column[x] += in[x], x < w (16 bits).
void AddRowToColumnSums(const uint8_t* in, int w, uint16_t* column) {
  int x = 0;
#ifdef __SSE2__
  const __m128i zero = _mm_setzero_si128();
  for (; x + 8 <= w; x += 8) {
    const __m128i add = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(in + x)), zero);
    __m128i* c = reinterpret_cast<__m128i*>(column + x);
    _mm_storeu_si128(c, _mm_add_epi16(_mm_loadu_si128(c), add));
  }
#endif
  for (; x < w; ++x) column[x] = static_cast<uint16_t>(column[x] + in[x]);
}

// out[x] = a[x] + b[x] + c[x], x < n, modulo 2^16.
[[gnu::always_inline]] inline void AddThree(const uint16_t* a, const uint16_t* b, const uint16_t* c, int n,
                                            uint16_t* out) {
  int x = 0;
#ifdef __SSE2__
  for (; x + 8 <= n; x += 8) {
    const __m128i sum = _mm_add_epi16(_mm_add_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + x)),
                                                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + x))),
                                      _mm_loadu_si128(reinterpret_cast<const __m128i*>(c + x)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), sum);
  }
#endif
  for (; x < n; ++x) out[x] = static_cast<uint16_t>(a[x] + b[x] + c[x]);
}

// prefix[0] = 0 and prefix[i + 1] = prefix[i] + column[i], i < n, modulo 2^16. A window's sum is then
// the difference of two prefixes, modulo 2^16: exact for sums below 2^16 (k x k windows of 8-bit pixels,
// k <= 15: at most 57,375), whatever the wrapped prefixes. About 20 instructions per 8 pixels whatever
// the window (with the subtraction in CompareWithWindowSums), where WindowSums<R> takes about 4 R + 6
// (measured: 34 for R = 7, 14 for R = 2): used from R = 4 (9 x 9) on. For detectMarkers' 15 px window
// this and 16 pixels a load took cv::adaptiveThreshold from 45.4 to 33.3 M instructions on
// bench_detector's 10 frames at 640 x 480 (accurate mode, both windows; the frame's search 12.1 -> 10.8 M).
void PrefixSums(const uint16_t* column, int n, uint16_t* prefix) {
  prefix[0] = 0;
  int i = 0;
#ifdef __SSE2__
  __m128i carry = _mm_setzero_si128();  // every lane prefix[i]
  for (; i + 8 <= n; i += 8) {
    __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(column + i));
    v = _mm_add_epi16(v, _mm_slli_si128(v, 2));
    v = _mm_add_epi16(v, _mm_slli_si128(v, 4));
    v = _mm_add_epi16(v, _mm_slli_si128(v, 8));
    v = _mm_add_epi16(v, carry);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(prefix + i + 1), v);
    const __m128i last = _mm_shufflehi_epi16(v, _MM_SHUFFLE(3, 3, 3, 3));
    carry = _mm_unpackhi_epi64(last, last);
  }
#endif
  for (; i < n; ++i) prefix[i + 1] = static_cast<uint16_t>(prefix[i] + column[i]);
}

// Where CompareWithWindowSums finds a pixel's window sum: sums[x] (WindowSums), sums[x + k] - sums[x]
// (PrefixSums), or sums[x] + b[x] + c[x] (three rows of sums added in the comparison, not stored first).
enum SumsAre { kWindowSums, kPrefixSums, kThreeRows };

// d[x] = `below` where the window sum >= area * (p - at) - offset (p = s[x]; p - at <= 0: always,
// p - at >= 256: never, as the sum is at most 255 * area), else `above`. The window sum as kSums says
// (SumsAre), modulo 2^16 (b and c are read for kThreeRows only).
template <int kSums>
[[gnu::always_inline]] inline void CompareWithWindowSums(const uint8_t* s, const uint16_t* sums,
                                                         const uint16_t* b, const uint16_t* c, int k, int w,
                                                         int at, int area, int offset, uint8_t below,
                                                         uint8_t above, uint8_t* d) {
  constexpr bool kPrefix = kSums == kPrefixSums;
  int x = 0;
#ifdef __SSE2__
  const __m128i zero = _mm_setzero_si128(), at16 = _mm_set1_epi16(static_cast<int16_t>(at));
  const __m128i area16 = _mm_set1_epi16(static_cast<int16_t>(area)), limit = _mm_set1_epi16(256);
  const __m128i offset16 = _mm_set1_epi16(static_cast<int16_t>(offset));
  const __m128i below8 = _mm_set1_epi8(static_cast<char>(below)),
                above8 = _mm_set1_epi8(static_cast<char>(above));
  // Lanes set where x + at's window sum >= its threshold (pixels p, 16 bits).
  auto is_below = [&](__m128i p, int at_x) {
    const __m128i v = _mm_min_epi16(_mm_max_epi16(_mm_sub_epi16(p, at16), zero), limit);
    const __m128i t = _mm_subs_epu16(_mm_mullo_epi16(v, area16), offset16);
    __m128i sum = _mm_loadu_si128(reinterpret_cast<const __m128i*>(sums + at_x + (kPrefix ? k : 0)));
    if (kPrefix) sum = _mm_sub_epi16(sum, _mm_loadu_si128(reinterpret_cast<const __m128i*>(sums + at_x)));
    if (kSums == kThreeRows)
      sum = _mm_add_epi16(_mm_add_epi16(sum, _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + at_x))),
                          _mm_loadu_si128(reinterpret_cast<const __m128i*>(c + at_x)));
    return _mm_cmpeq_epi16(_mm_subs_epu16(t, sum), zero);  // sum >= t
  };
  auto select = [&](__m128i mask) {
    return _mm_or_si128(_mm_and_si128(mask, below8), _mm_andnot_si128(mask, above8));
  };
  for (; x + 16 <= w; x += 16) {  // 16 pixels: one load, pack and store
    const __m128i p = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x));
    const __m128i mask =
        _mm_packs_epi16(is_below(_mm_unpacklo_epi8(p, zero), x), is_below(_mm_unpackhi_epi8(p, zero), x + 8));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(d + x), select(mask));
  }
  for (; x + 8 <= w; x += 8) {
    const __m128i p = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(s + x)), zero);
    const __m128i below_lanes = is_below(p, x);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(d + x), select(_mm_packs_epi16(below_lanes, below_lanes)));
  }
#endif
  for (; x < w; ++x) {
    const int sum = kPrefix               ? static_cast<uint16_t>(sums[x + k] - sums[x])
                    : kSums == kThreeRows ? static_cast<uint16_t>(sums[x] + b[x] + c[x])
                                          : sums[x];
    d[x] = sum >= std::max(0, area * std::clamp(s[x] - at, 0, 256) - offset) ? below : above;
  }
}

// The helpers above on AVX2 lanes (16 x 16 bits, 32 x 8 bits), for the CPUs that have it: GCC on x86-64,
// compiled for AVX2 by #pragma GCC target and run only where the side model's dispatch runs its AVX2 code
// (DetectorUsesAvx2: the CPU has it, MCMT_NO_AVX2 unset; one switch for both). The same integer operations
// modulo 2^16 lane by lane, hence the same sums and the same binary image bit for bit
// (test_detector_unit, CandidateSearch.Avx2ThresholdIsSse2); each hands its last pixels to the SSE2 code.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define MCMT_SEARCH_HAS_AVX2 1
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2 {

__m256i Load(const void* at) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at)); }
void Store(void* at, __m256i v) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(at), v); }
__m256i Widen(__m128i v) { return _mm256_cvtepu8_epi16(v); }  // 16 bytes to 16 x 16 bits

void SlideColumnSums(const uint8_t* in, const uint8_t* out, int w, uint16_t* column) {
  int x = 0;
  auto slide = [&](__m256i add, __m256i sub, uint16_t* at) {
    Store(at, _mm256_sub_epi16(_mm256_add_epi16(Load(at), add), sub));
  };
  for (; x + 32 <= w; x += 32) {  // 32 pixels of each row per load
    const __m256i add = Load(in + x), sub = Load(out + x);
    slide(Widen(_mm256_castsi256_si128(add)), Widen(_mm256_castsi256_si128(sub)), column + x);
    slide(Widen(_mm256_extracti128_si256(add, 1)), Widen(_mm256_extracti128_si256(sub, 1)), column + x + 16);
  }
  for (; x + 16 <= w; x += 16)
    slide(Widen(_mm_loadu_si128(reinterpret_cast<const __m128i*>(in + x))),
          Widen(_mm_loadu_si128(reinterpret_cast<const __m128i*>(out + x))), column + x);
  mcmt::SlideColumnSums(in + x, out + x, w - x, column + x);
}

template <int R>
void WindowSums(const uint16_t* column, int w, uint16_t* sums) {
  int x = 0;
  for (; x + 16 <= w; x += 16) {
    __m256i sum = Load(column + x - R);
    for (int i = 1 - R; i <= R; ++i) sum = _mm256_add_epi16(sum, Load(column + x + i));
    Store(sums + x, sum);
  }
  mcmt::WindowSums<R>(column + x, w - x, sums + x);
}

void AddThree(const uint16_t* a, const uint16_t* b, const uint16_t* c, int n, uint16_t* out) {
  int x = 0;
  for (; x + 16 <= n; x += 16)
    Store(out + x, _mm256_add_epi16(_mm256_add_epi16(Load(a + x), Load(b + x)), Load(c + x)));
  mcmt::AddThree(a + x, b + x, c + x, n - x, out + x);
}

void PrefixSums(const uint16_t* column, int n, uint16_t* prefix) {
  prefix[0] = 0;
  int i = 0;
  __m256i carry = _mm256_setzero_si256();  // every lane prefix[i]
  for (; i + 16 <= n; i += 16) {
    __m256i v = Load(column + i);  // the prefixes within each half of 8 lanes, then the low half's last
    v = _mm256_add_epi16(v, _mm256_slli_si256(v, 2));  // added to the high half
    v = _mm256_add_epi16(v, _mm256_slli_si256(v, 4));
    v = _mm256_add_epi16(v, _mm256_slli_si256(v, 8));
    const __m256i last = _mm256_shufflehi_epi16(v, _MM_SHUFFLE(3, 3, 3, 3));  // lanes 4-7 of each: 7
    v = _mm256_add_epi16(v, _mm256_permute2x128_si256(_mm256_unpackhi_epi64(last, last), last, 0x08));
    v = _mm256_add_epi16(v, carry);
    Store(prefix + i + 1, v);
    carry = _mm256_permute4x64_epi64(_mm256_shufflehi_epi16(v, _MM_SHUFFLE(3, 3, 3, 3)), 0xff);
  }
  for (; i < n; ++i) prefix[i + 1] = static_cast<uint16_t>(prefix[i] + column[i]);
}

template <int kSums>
void CompareWithWindowSums(const uint8_t* s, const uint16_t* sums, const uint16_t* b, const uint16_t* c,
                           int k, int w, int at, int area, int offset, uint8_t below, uint8_t above,
                           uint8_t* d) {
  constexpr bool kPrefix = kSums == kPrefixSums;
  int x = 0;
  const __m256i zero = _mm256_setzero_si256(), at16 = _mm256_set1_epi16(static_cast<int16_t>(at));
  const __m256i area16 = _mm256_set1_epi16(static_cast<int16_t>(area)), limit = _mm256_set1_epi16(256);
  const __m256i offset16 = _mm256_set1_epi16(static_cast<int16_t>(offset));
  const __m256i below8 = _mm256_set1_epi8(static_cast<char>(below)),
                above8 = _mm256_set1_epi8(static_cast<char>(above));
  // Lanes set where x + at's window sum >= its threshold (pixels p, 16 bits).
  auto is_below = [&](__m256i p, int at_x) {
    const __m256i v = _mm256_min_epi16(_mm256_max_epi16(_mm256_sub_epi16(p, at16), zero), limit);
    const __m256i t = _mm256_subs_epu16(_mm256_mullo_epi16(v, area16), offset16);
    __m256i sum = Load(sums + at_x + (kPrefix ? k : 0));
    if (kPrefix) sum = _mm256_sub_epi16(sum, Load(sums + at_x));
    if (kSums == kThreeRows) sum = _mm256_add_epi16(_mm256_add_epi16(sum, Load(b + at_x)), Load(c + at_x));
    return _mm256_cmpeq_epi16(_mm256_subs_epu16(t, sum), zero);  // sum >= t
  };
  for (; x + 32 <= w; x += 32) {  // 32 pixels: one load, pack (lanes back in order) and store
    const __m256i p = Load(s + x);
    const __m256i mask =
        _mm256_permute4x64_epi64(_mm256_packs_epi16(is_below(Widen(_mm256_castsi256_si128(p)), x),
                                                    is_below(Widen(_mm256_extracti128_si256(p, 1)), x + 16)),
                                 _MM_SHUFFLE(3, 1, 2, 0));
    Store(d + x, _mm256_blendv_epi8(above8, below8, mask));
  }
  const bool three = kSums == kThreeRows;
  mcmt::CompareWithWindowSums<kSums>(s + x, sums + x, three ? b + x : b, three ? c + x : c, k, w - x, at,
                                     area, offset, below, above, d + x);
}

}  // namespace avx2
#pragma GCC pop_options
#else
#define MCMT_SEARCH_HAS_AVX2 0
#endif

// The helpers of ThresholdAgainstBoxMean: the SSE2 ones or the AVX2 ones (the same values), called directly
// (the SSE2 ones inlined, as before there were AVX2 ones).
struct Sse2BoxMean {
  static void Slide(const uint8_t* in, const uint8_t* out, int w, uint16_t* column) {
    SlideColumnSums(in, out, w, column);
  }
  static constexpr void (*kSumsOf[4])(const uint16_t*, int, uint16_t*) = {WindowSums<0>, WindowSums<1>,
                                                                          WindowSums<2>, WindowSums<3>};
  static void Prefix(const uint16_t* column, int n, uint16_t* prefix) { PrefixSums(column, n, prefix); }
  static void Three(const uint16_t* a, const uint16_t* b, const uint16_t* c, int n, uint16_t* out) {
    AddThree(a, b, c, n, out);
  }
  template <int kSums>
  static void Compare(const uint8_t* s, const uint16_t* sums, const uint16_t* b, const uint16_t* c, int k,
                      int w, int at, int area, int offset, uint8_t below, uint8_t above, uint8_t* d) {
    CompareWithWindowSums<kSums>(s, sums, b, c, k, w, at, area, offset, below, above, d);
  }
};
#if MCMT_SEARCH_HAS_AVX2
struct Avx2BoxMean {
  static void Slide(const uint8_t* in, const uint8_t* out, int w, uint16_t* column) {
    avx2::SlideColumnSums(in, out, w, column);
  }
  static constexpr void (*kSumsOf[4])(const uint16_t*, int, uint16_t*) = {
      avx2::WindowSums<0>, avx2::WindowSums<1>, avx2::WindowSums<2>, avx2::WindowSums<3>};
  static void Prefix(const uint16_t* column, int n, uint16_t* prefix) { avx2::PrefixSums(column, n, prefix); }
  static void Three(const uint16_t* a, const uint16_t* b, const uint16_t* c, int n, uint16_t* out) {
    avx2::AddThree(a, b, c, n, out);
  }
  template <int kSums>
  static void Compare(const uint8_t* s, const uint16_t* sums, const uint16_t* b, const uint16_t* c, int k,
                      int w, int at, int area, int offset, uint8_t below, uint8_t above, uint8_t* d) {
    avx2::CompareWithWindowSums<kSums>(s, sums, b, c, k, w, at, area, offset, below, above, d);
  }
};
#endif

// ThresholdAgainstBoxMean with the helpers of `Lanes` (Sse2BoxMean or Avx2BoxMean).
template <typename Lanes>
void ThresholdAgainstBoxMeanWith(const cv::Mat& src, int k, int at, int offset, uint8_t below, uint8_t above,
                                 bool isolated, cv::Mat& dst) {
  const int r = k / 2, w = src.cols, h = src.rows, area = k * k;
  if (w == 0 || h == 0) return;
  cv::Size whole(w, h);
  cv::Point at_whole(0, 0);  // the view's origin in its whole image
  if (!isolated) src.locateROI(whole, at_whole);
  // The columns of the view's windows within the whole image: [x_begin, x_end) of -r .. w + r.
  const int x_begin = std::max(-r, -at_whole.x), x_end = std::min(w + r, whole.width - at_whole.x);
  thread_local std::vector<uint16_t> padded, sums;
  padded.assign(static_cast<size_t>(w) + 2 * r, 0);
  sums.resize(static_cast<size_t>(w) + 2 * r + 1);
  uint16_t* column = padded.data() + r;  // column[-r..w + r): this row's column sums, edges replicated
  // Row y of the view (any y: the whole image's nearest row), from column x_begin on.
  auto row = [&](int y) {
    const int in_whole = std::clamp(at_whole.y + y, 0, whole.height - 1);
    return src.data +
           static_cast<std::ptrdiff_t>(in_whole - at_whole.y) * static_cast<std::ptrdiff_t>(src.step[0]) +
           x_begin;
  };
  const int real = x_end - x_begin;
  for (int y = -r; y <= r; ++y) AddRowToColumnSums(row(y), real, column + x_begin);
  for (int y = 0; y < h; ++y) {
    if (y > 0) Lanes::Slide(row(y + r), row(y - r - 1), real, column + x_begin);
    for (int x = -r; x < x_begin; ++x) column[x] = column[x_begin];
    for (int x = x_end; x < w + r; ++x) column[x] = column[x_end - 1];
    const uint8_t* s = src.ptr<uint8_t>(y);
    uint8_t* d = dst.ptr<uint8_t>(y);
    if (r < 4) {
      Lanes::kSumsOf[r](column, w, sums.data());
      Lanes::template Compare<kWindowSums>(s, sums.data(), nullptr, nullptr, k, w, at, area, offset, below,
                                           above, d);
    } else {  // sums[i]: the sum of column[-r .. i - r), x's window column[x - r .. x + r]: i = x + k, x
      Lanes::Prefix(padded.data(), w + 2 * r, sums.data());
      Lanes::template Compare<kPrefixSums>(s, sums.data(), nullptr, nullptr, k, w, at, area, offset, below,
                                           above, d);
    }
  }
}

// dst = `below` where src - mean <= at, else `above`, the mean that of the k x k window (k odd, 3 to 15)
// rounded as cv::boxFilter rounds it (`offset`: BoxMeanThresholdOffset), with BORDER_REPLICATE: edges
// replicated within src (`isolated`, BORDER_ISOLATED) or, for a view, its whole image's pixels beyond
// the view and that image's edges replicated (cv::blur's default): 16-bit column sums slid down the
// image, their window sums compared with a threshold linear in the pixel. dst must not be src.
void ThresholdAgainstBoxMean(const cv::Mat& src, int k, int at, int offset, uint8_t below, uint8_t above,
                             bool isolated, cv::Mat& dst) {
#if MCMT_SEARCH_HAS_AVX2
  if (DetectorUsesAvx2())  // where the side model runs its AVX2 code
    return ThresholdAgainstBoxMeanWith<Avx2BoxMean>(src, k, at, offset, below, above, isolated, dst);
#endif
  ThresholdAgainstBoxMeanWith<Sse2BoxMean>(src, k, at, offset, below, above, isolated, dst);
}

// ThresholdAgainstBoxMean (isolated) for the k x k window into `small` and the 3k x 3k window into `large`
// in one pass, with the helpers of `Lanes`. A 3k window's sum is that of the 3 x 3 k-windows centred k
// apart (with the edges replicated index by index, as each k-window's own pixels are): each row's k-window
// sums from -k to w + k (the small threshold's, over 2k more columns), three of them added across (k apart)
// into a ring of 2k + 1 rows, three rows of it added down (k apart) for the large threshold k rows behind.
// Instead of the large window's own column sums and prefix sums: 0.55 fewer instructions per pixel
// (AVX2; bench_detector's 15 px window). Same sums modulo 2^16 (below 2^16: k <= 5), same images. The
// three ring rows are added within the comparison (kThreeRows), not stored first. Row y of each image:
// small_row(y), large_row(y) (w bytes each: a cv::Mat's rows, or a FramedBinary's).
template <typename Lanes, typename SmallRow, typename LargeRow>
void ThresholdPairAgainstBoxMeansWith(const cv::Mat& src, int k, int at, int offset_small, int offset_large,
                                      uint8_t below, uint8_t above, SmallRow small_row, LargeRow large_row) {
  const int r = k / 2, w = src.cols, h = src.rows, reach = k + r;  // columns -reach .. w + reach
  if (w == 0 || h == 0) return;
  const int ring_rows = 2 * k + 1;
  thread_local std::vector<uint16_t> padded, box, ring;
  padded.assign(static_cast<size_t>(w) + 2 * reach, 0);
  box.resize(static_cast<size_t>(w) + 2 * k);
  ring.resize(static_cast<size_t>(ring_rows) * w);
  uint16_t* column = padded.data() + reach;  // column[-reach .. w + reach): edges replicated
  auto row = [&](int y) { return src.ptr<uint8_t>(std::clamp(y, 0, h - 1)); };
  auto ring_row = [&](int y) {
    return ring.data() + static_cast<size_t>((y % ring_rows + ring_rows) % ring_rows) * w;
  };
  // The k-window rows from y = -k (its rows -k - r .. -k + r, each the nearest row) to h - 1 + k.
  for (int y = -k - r; y <= -k + r; ++y) AddRowToColumnSums(row(y), w, column);
  for (int y = -k; y < h + k; ++y) {
    if (y > -k) Lanes::Slide(row(y + r), row(y - r - 1), w, column);
    for (int x = -reach; x < 0; ++x) column[x] = column[0];
    for (int x = w; x < w + reach; ++x) column[x] = column[w - 1];
    // box[i]: the k-window sum centred on column i - k, i < w + 2k.
    Lanes::kSumsOf[r](column - k, w + 2 * k, box.data());
    if (y >= 0 && y < h)
      Lanes::template Compare<kWindowSums>(src.ptr<uint8_t>(y), box.data() + k, nullptr, nullptr, k, w, at,
                                           k * k, offset_small, below, above, small_row(y));
    Lanes::Three(box.data(), box.data() + k, box.data() + 2 * k, w, ring_row(y));
    const int y_large = y - k;
    if (y_large >= 0)
      Lanes::template Compare<kThreeRows>(src.ptr<uint8_t>(y_large), ring_row(y_large - k), ring_row(y_large),
                                          ring_row(y), 3 * k, w, at, 9 * k * k, offset_large, below, above,
                                          large_row(y_large));
  }
}

// The 8 neighbours of a pixel of the framed 0/1 image as one byte: bit d set where the neighbour in
// direction d (FollowBorder's order: right first, counter-clockwise on screen) is not 0. Indexed by the
// nonzero bytes of its three rows read 4 bytes wide from the up-left neighbour: bits 0-2 up-left, up,
// up-right; 4 left, 5 the pixel, 6 right; 8-10 down-left, down, down-right (3 and 7: the bytes after).
struct NeighbourTable {
  uint8_t bits[2048];
};

constexpr NeighbourTable MakeNeighbourTable() {
  NeighbourTable table{};
  // Direction d's bit in the index.
  constexpr int kIndexBit[8] = {6, 2, 1, 0, 4, 8, 9, 10};
  for (int index = 0; index < 2048; ++index) {
    int bits = 0;
    for (int d = 0; d < 8; ++d) bits |= ((index >> kIndexBit[d]) & 1) << d;
    table.bits[index] = static_cast<uint8_t>(bits);
  }
  return table;
}

constexpr NeighbourTable kNeighbours = MakeNeighbourTable();

// Bit d set where the neighbour of `p` in direction d is not 0 (`p` inside the frame; the image readable
// to p + step + 2). The same bits on every path: SSE2 (also under AVX2) or one byte at a time.
inline unsigned NonzeroNeighbours(const int8_t* p, std::ptrdiff_t step) {
#ifdef __SSE2__
  int32_t up, middle, down;
  std::memcpy(&up, p - step - 1, 4);
  std::memcpy(&middle, p - 1, 4);
  std::memcpy(&down, p + step - 1, 4);
  const __m128i rows = _mm_setr_epi32(up, middle, down, 0);
  const unsigned zero = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(rows, _mm_setzero_si128())));
  return kNeighbours.bits[~zero & 0x7ffu];
#else
  const std::ptrdiff_t delta[8] = {1, 1 - step, -step, -step - 1, -1, step - 1, step, step + 1};
  unsigned bits = 0;
  for (int d = 0; d < 8; ++d) bits |= static_cast<unsigned>(p[delta[d]] != 0) << d;
  return bits;
#endif
}

// OpenCV's contour follower's marks in its 0/1 image (Suzuki and Abe's NBD 2 for every border in its list
// modes): a border pixel whose right neighbour (a 0 pixel) was examined while following the border, and
// any other border pixel.
constexpr int8_t kBorderRightExamined = -126, kBorderPixel = 2;

// Follows the border through `start` (a pixel of the framed 0/1 image; `delta`: the offsets of its 8
// neighbours, right first and counter-clockwise on screen, twice over) as OpenCV's icvFetchContour does
// for 8-bit images and CHAIN_APPROX_NONE: the same first direction (an outer border searches from the
// left neighbour, a hole's from the right one), the same marks, every pixel passed appended to `points`
// from `pt` on. OpenCV probes the neighbours one by one; here each pixel's 8 are read at once
// (NonzeroNeighbours; marks never make a pixel 0 or nonzero) and the first one found by bit scans:
// OpenCV's first search clockwise from first_end - 1 is the highest nonzero direction below
// first_end + 8 in the byte twice over, its search counter-clockwise from end + 1 the lowest above end.
void FollowBorder(int8_t* start, const std::ptrdiff_t* delta, bool hole, cv::Point pt,
                  std::vector<cv::Point>* points) {
  static constexpr int kDx[8] = {1, 1, 0, -1, -1, -1, 0, 1}, kDy[8] = {0, -1, -1, -1, 0, 1, 1, 1};
  const std::ptrdiff_t step = delta[6];
  const int first_end = hole ? 0 : 4;
  const unsigned around = NonzeroNeighbours(start, step);
  if ((around & ~(1u << first_end)) == 0) {  // a single pixel
    *start = kBorderRightExamined;
    points->push_back(pt);
    return;
  }
  unsigned twice = around * 0x101u;
  int s = (31 - __builtin_clz(twice & ((256u << first_end) - 1))) & 7;
  int8_t* const second = start + delta[s];
  int8_t* here = start;
  for (;;) {
    const int end = s;
    s = (end + 1 + __builtin_ctz(twice >> (end + 1))) & 7;
    int8_t* const next = here + delta[s];
    if (static_cast<unsigned>(s - 1) < static_cast<unsigned>(end))
      *here = kBorderRightExamined;
    else if (*here == 1)
      *here = kBorderPixel;
    points->push_back(pt);
    pt.x += kDx[s], pt.y += kDy[s];
    if (next == start && here == second) break;
    here = next;
    s = (s + 4) & 7;
    twice = NonzeroNeighbours(here, step) * 0x101u;
  }
}

// Bit i set where a border starts at row[x + i] as the row is (i < 16; row readable from x - 1 to
// x + 15): a 1 after a 0 (an outer border) or a 0 after a 1 or 2 (a hole's; the image holds 0, 1, 2 and
// kBorderRightExamined only, so a 1 or 2 is a value above 0).
uint32_t BorderStarts(const int8_t* row, int x) {
#ifdef __SSE2__
  const __m128i p = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
  const __m128i prev = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x - 1));
  if (_mm_movemask_epi8(_mm_cmpeq_epi8(p, prev)) == 0xffff) return 0;  // no change (most of an image)
  const __m128i zero = _mm_setzero_si128(), one = _mm_set1_epi8(1);
  const __m128i outer = _mm_and_si128(_mm_cmpeq_epi8(p, one), _mm_cmpeq_epi8(prev, zero));
  const __m128i hole = _mm_and_si128(_mm_cmpeq_epi8(p, zero), _mm_cmpgt_epi8(prev, zero));
  return static_cast<uint32_t>(_mm_movemask_epi8(_mm_or_si128(outer, hole)));
#else
  uint32_t mask = 0;
  for (int i = 0; i < 16; ++i) {
    const int8_t p = row[x + i], prev = row[x + i - 1];
    mask |= static_cast<uint32_t>((prev == 0 && p == 1) || (p == 0 && prev > 0)) << i;
  }
  return mask;
#endif
}

// The contour scan's framing and border starts on AVX2 lanes (32 pixels), run where the threshold's AVX2
// code runs (DetectorUsesAvx2): the same bytes and the same starts (test_detector_unit,
// FindContoursIsOpenCVs on both).
#if MCMT_SEARCH_HAS_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2 {

// BorderStarts for 32 pixels: bit i set where a border starts at row[x + i] (row readable from x - 1 to
// x + 31).
uint32_t BorderStarts(const int8_t* row, int x) {
  const __m256i p = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x));
  const __m256i prev = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x - 1));
  if (_mm256_movemask_epi8(_mm256_cmpeq_epi8(p, prev)) == -1) return 0;  // no change
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi8(1);
  const __m256i outer = _mm256_and_si256(_mm256_cmpeq_epi8(p, one), _mm256_cmpeq_epi8(prev, zero));
  const __m256i hole = _mm256_and_si256(_mm256_cmpeq_epi8(p, zero), _mm256_cmpgt_epi8(prev, zero));
  return static_cast<uint32_t>(_mm256_movemask_epi8(_mm256_or_si256(outer, hole)));
}

// The first x from `base` to w where a border starts in `row` as it is, else w + 1: BorderStarts 32 pixels
// at a time, in one call (a call per 32 pixels was 3.1 M instructions in bench_detector's 10 accurate
// frames).
int NextBorderStart(const int8_t* row, int base, int w) {
  for (; base <= w; base += 32) {
    uint32_t starts = BorderStarts(row, base);
    if (base > w - 31) starts &= (2u << (w - base)) - 1;  // the row's last pixels
    if (starts != 0) return base + __builtin_ctz(starts);
  }
  return w + 1;
}

// d[x] = 1 where s[x] != 0, else 0, 32 pixels at a time while a whole 32 fit in w; returns the pixels done.
int FrameRow(const uint8_t* s, int w, int8_t* d) {
  const __m256i one = _mm256_set1_epi8(1);
  int x = 0;
  for (; x + 32 <= w; x += 32)
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(d + x),
                        _mm256_min_epu8(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(s + x)), one));
  return x;
}

}  // namespace avx2
#pragma GCC pop_options
#endif

// framed->bytes sized for a cols x rows image (FramedBinary's layout) and its frame set to 0: the rows above
// and below (and the 32 bytes after, for the last row's 32-pixel reads), each row's left and right column.
// The image's own pixels are left to the caller, which writes every one.
void PrepareFrame(int cols, int rows, FramedBinary* framed) {
  framed->cols = cols, framed->rows = rows;
  const std::ptrdiff_t step = cols + 2;
  const size_t size = static_cast<size_t>(step) * (rows + 2) + 32;
  // Allocated, not cleared (as a std::vector's resize would clear it): 0.3 M instructions per window on a
  // thread's first 640 x 480 frame.
  if (framed->capacity < size) {
    framed->bytes.reset(new int8_t[size]);
    framed->capacity = size;
  }
  int8_t* const bytes = framed->bytes.get();
  std::fill_n(bytes, step, 0);
  std::fill_n(bytes + (rows + 1) * step, step + 32, 0);
  for (int y = 1; y <= rows; ++y) bytes[y * step] = 0, bytes[y * step + cols + 1] = 0;
}

// *framed = the 0/1 image of the nonzero pixels of `src` (8-bit, one channel), framed by zeros.
void FrameNonzero(const cv::Mat& src, FramedBinary* framed) {
  const int w = src.cols, h = src.rows;
  PrepareFrame(w, h, framed);
#if MCMT_SEARCH_HAS_AVX2
  const bool avx2 = DetectorUsesAvx2();
#endif
  for (int y = 0; y < h; ++y) {
    const uint8_t* s = src.ptr<uint8_t>(y);
    int8_t* d = framed->Row(y);
    int x = 0;
#if MCMT_SEARCH_HAS_AVX2
    if (avx2) x = avx2::FrameRow(s, w, d);
#endif
#ifdef __SSE2__
    const __m128i one = _mm_set1_epi8(1);
    for (; x + 16 <= w; x += 16)
      _mm_storeu_si128(reinterpret_cast<__m128i*>(d + x),
                       _mm_min_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x)), one));
#endif
    for (; x < w; ++x) d[x] = s[x] != 0 ? 1 : 0;
  }
}

// Every border of the 1 pixels of `framed` (a 0/1 image framed by zeros) as OpenCV's findContours with
// RETR_LIST and CHAIN_APPROX_NONE finds them in the nonzero pixels of its input (its 0/1 image framed by
// zeros), scanned row by row; an outer border starts where a 1 follows a 0, a hole's where a 0 follows a
// pixel of value 1 or 2, and each is followed at once (FollowBorder, which marks the image). Points
// shifted by `offset`, border k's points ending at ends[k], in the order found (OpenCV returns them last
// found first).
void ListBorders(FramedBinary* framed, cv::Point offset, std::vector<cv::Point>* points,
                 std::vector<size_t>* ends) {
  const int w = framed->cols, h = framed->rows;
  const std::ptrdiff_t step = w + 2;
#if MCMT_SEARCH_HAS_AVX2
  const bool avx2 = DetectorUsesAvx2();
#endif
  points->clear();
  ends->clear();
  const std::ptrdiff_t delta[16] = {1, 1 - step, -step, -step - 1, -1, step - 1, step, step + 1,
                                    1, 1 - step, -step, -step - 1, -1, step - 1, step, step + 1};
  // OpenCV compares each pixel with the one before it as it is then (after the borders followed so far
  // marked it): where a border starts it follows it. The starts are found 16 pixels at a time, and found
  // again after each border followed (it may have marked pixels ahead).
  for (int y = 1; y <= h; ++y) {
    int8_t* row = framed->bytes.get() + y * step;
    for (int base = 1; base <= w;) {
      int x;
#if MCMT_SEARCH_HAS_AVX2
      if (avx2) {
        x = avx2::NextBorderStart(row, base, w);
        if (x > w) break;
      } else
#endif
      {
        uint32_t starts = BorderStarts(row, base);
        if (base > w - 15) starts &= (2u << (w - base)) - 1;  // the row's last pixels
        if (starts == 0) {
          base += 16;
          continue;
        }
        x = base + __builtin_ctz(starts);
      }
      const bool hole = row[x] == 0;
      FollowBorder(row + x - (hole ? 1 : 0), delta, hole, cv::Point(x - (hole ? 2 : 1), y - 1) + offset,
                   points);
      ends->push_back(points->size());
      base = x + 1;
    }
  }
}

// *contours = the borders ListBorders found (points, ends), last found first (OpenCV's order), less those
// of fewer than `floor` points (0: none left out).
void BordersToContours(const std::vector<cv::Point>& points, const std::vector<size_t>& ends, size_t floor,
                       std::vector<std::vector<cv::Point>>* contours) {
  auto begin_of = [&](size_t k) { return k == 0 ? 0 : ends[k - 1]; };
  size_t kept = 0;
  for (size_t k = 0; k < ends.size(); ++k) kept += ends[k] - begin_of(k) >= floor;
  contours->resize(kept);
  for (size_t k = 0; k < ends.size(); ++k) {
    if (ends[k] - begin_of(k) < floor) continue;
    (*contours)[--kept].assign(points.begin() + static_cast<std::ptrdiff_t>(begin_of(k)),
                               points.begin() + static_cast<std::ptrdiff_t>(ends[k]));
  }
}

// The scalar part of WarpSegmentNearest (OpenCV's scalar code): pixels i .. bw - 1 of the segment whose
// first pixel's map is X0, Y0, W0.
[[gnu::always_inline]] inline void WarpSegmentNearestTail(const cv::Mat& src, double X0, double Y0, double W0,
                                                          const double* M, int i, int bw, uint8_t border,
                                                          uint8_t* d) {
  const unsigned cols = static_cast<unsigned>(src.cols), rows = static_cast<unsigned>(src.rows);
  for (; i < bw; ++i) {
    double w = W0 + M[6] * i;
    w = w != 0 ? 1. / w : 0;
    const double fx =
        std::max(static_cast<double>(INT_MIN), std::min(static_cast<double>(INT_MAX), (X0 + M[0] * i) * w));
    const double fy =
        std::max(static_cast<double>(INT_MIN), std::min(static_cast<double>(INT_MAX), (Y0 + M[3] * i) * w));
    const int sx = cv::saturate_cast<int16_t>(cv::saturate_cast<int>(fx)),
              sy = cv::saturate_cast<int16_t>(cv::saturate_cast<int>(fy));
    d[i] = static_cast<unsigned>(sx) < cols && static_cast<unsigned>(sy) < rows
               ? src.data[sy * src.step[0] + sx]
               : border;
  }
}

// One row segment of OpenCV 4.6's warpPerspective with INTER_NEAREST (its WarpPerspectiveInvoker: column
// blocks of `bw` pixels from `x`): d[i] = the pixel of `src` nearest to M (x + i, y), `border` outside.
// Each map position is computed as OpenCV computes it, bit for bit: (X0 + M0 i) times 1 / (W0 + M6 i)
// (0 where that denominator is 0) with X0 = M0 x + M1 y + M2 per block row, clamped to the int range,
// rounded to even and saturated to 16 bits, 16 pixels at a time as its SSE4.1 line (every operation
// SSE2's) and the rest as its scalar code.
void WarpSegmentNearest(const cv::Mat& src, const double* M, int x, int y, int bw, uint8_t border,
                        uint8_t* d) {
  const double X0 = M[0] * x + M[1] * y + M[2], Y0 = M[3] * x + M[4] * y + M[5],
               W0 = M[6] * x + M[7] * y + M[8];
  int16_t xy[2 * 16];
  const uint8_t* data = src.data;
  const size_t step = src.step[0];
  const unsigned cols = static_cast<unsigned>(src.cols), rows = static_cast<unsigned>(src.rows);
  auto sample = [&](int i, int n) {
    for (int k = 0; k < n; ++k) {
      const int sx = xy[2 * k], sy = xy[2 * k + 1];
      d[i + k] = static_cast<unsigned>(sx) < cols && static_cast<unsigned>(sy) < rows ? data[sy * step + sx]
                                                                                      : border;
    }
  };
  int i = 0;
#ifdef __SSE2__
  const __m128d m0 = _mm_set1_pd(M[0]), m3 = _mm_set1_pd(M[3]), m6 = _mm_set1_pd(M[6]);
  const __m128d int_max = _mm_set1_pd(static_cast<double>(INT_MAX)),
                int_min = _mm_set1_pd(static_cast<double>(INT_MIN));
  const __m128d zero = _mm_setzero_pd(), one = _mm_set1_pd(1), x0 = _mm_set1_pd(X0), y0 = _mm_set1_pd(Y0),
                w0 = _mm_set1_pd(W0);
  for (; i <= bw - 16; i += 16) {
    __m128d at = _mm_set_pd(i + 1, i);
    for (int k = 0; k < 16; k += 4) {
      __m128i xy4[2];
      for (int h = 0; h < 2; ++h, at = _mm_add_pd(at, _mm_set1_pd(2))) {
        __m128d w = _mm_add_pd(_mm_mul_pd(m6, at), w0);
        w = _mm_andnot_pd(_mm_cmpeq_pd(w, zero), _mm_div_pd(one, w));
        const __m128d fx =
            _mm_max_pd(int_min, _mm_min_pd(int_max, _mm_mul_pd(_mm_add_pd(x0, _mm_mul_pd(m0, at)), w)));
        const __m128d fy =
            _mm_max_pd(int_min, _mm_min_pd(int_max, _mm_mul_pd(_mm_add_pd(y0, _mm_mul_pd(m3, at)), w)));
        xy4[h] = _mm_unpacklo_epi32(_mm_cvtpd_epi32(fx), _mm_cvtpd_epi32(fy));  // x0 y0 x1 y1
      }
      _mm_storeu_si128(reinterpret_cast<__m128i*>(xy + 2 * k), _mm_packs_epi32(xy4[0], xy4[1]));
    }
    sample(i, 16);
  }
#endif
  WarpSegmentNearestTail(src, X0, Y0, W0, M, i, bw, border, d);
}

#if MCMT_SEARCH_HAS_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2 {

// WarpSegmentNearest on AVX2 lanes: each 16-pixel block's positions 4 at a time by the same double
// operations lane by lane (the same operands in the same order: the same values, NaN and infinity
// included), saturated to 16 bits as there; each pixel's address and whether it lies inside `src` 8 at a
// time (32-bit products: `src` below 2^31 bytes, else the SSE2 code), then the pixels read one by one and
// the border put in where outside. The rest of the segment: the SSE2 code's scalar part.
void WarpSegmentNearest(const cv::Mat& src, const double* M, int x, int y, int bw, uint8_t border,
                        uint8_t* d) {
  const double X0 = M[0] * x + M[1] * y + M[2], Y0 = M[3] * x + M[4] * y + M[5],
               W0 = M[6] * x + M[7] * y + M[8];
  const __m256d m0 = _mm256_set1_pd(M[0]), m3 = _mm256_set1_pd(M[3]), m6 = _mm256_set1_pd(M[6]);
  const __m256d int_max = _mm256_set1_pd(static_cast<double>(INT_MAX)),
                int_min = _mm256_set1_pd(static_cast<double>(INT_MIN));
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1), x0 = _mm256_set1_pd(X0),
                y0 = _mm256_set1_pd(Y0), w0 = _mm256_set1_pd(W0), four = _mm256_set1_pd(4);
  const __m256i cols = _mm256_set1_epi32(src.cols), rows = _mm256_set1_epi32(src.rows),
                minus_one = _mm256_set1_epi32(-1), step = _mm256_set1_epi32(static_cast<int>(src.step[0]));
  const __m128i border8 = _mm_set1_epi8(static_cast<char>(border));
  const uint8_t* data = src.data;
  alignas(32) int32_t at_pixel[16];
  alignas(16) uint8_t pixels[16];
  int i = 0;
  for (; i <= bw - 16; i += 16) {
    __m256d at = _mm256_set_pd(i + 3, i + 2, i + 1, i);
    __m256i inside[2];
    for (int h = 0; h < 2; ++h) {  // 8 pixels: x and y of 4 and 4, saturated to 16 bits, widened again
      __m128i xs[2], ys[2];
      for (int q = 0; q < 2; ++q, at = _mm256_add_pd(at, four)) {
        __m256d w = _mm256_add_pd(_mm256_mul_pd(m6, at), w0);
        w = _mm256_andnot_pd(_mm256_cmp_pd(w, zero, _CMP_EQ_OQ), _mm256_div_pd(one, w));
        const __m256d fx = _mm256_max_pd(
            int_min, _mm256_min_pd(int_max, _mm256_mul_pd(_mm256_add_pd(x0, _mm256_mul_pd(m0, at)), w)));
        const __m256d fy = _mm256_max_pd(
            int_min, _mm256_min_pd(int_max, _mm256_mul_pd(_mm256_add_pd(y0, _mm256_mul_pd(m3, at)), w)));
        xs[q] = _mm256_cvtpd_epi32(fx);
        ys[q] = _mm256_cvtpd_epi32(fy);
      }
      const __m256i sx = _mm256_cvtepi16_epi32(_mm_packs_epi32(xs[0], xs[1]));
      const __m256i sy = _mm256_cvtepi16_epi32(_mm_packs_epi32(ys[0], ys[1]));
      inside[h] =
          _mm256_and_si256(_mm256_and_si256(_mm256_cmpgt_epi32(sx, minus_one), _mm256_cmpgt_epi32(cols, sx)),
                           _mm256_and_si256(_mm256_cmpgt_epi32(sy, minus_one), _mm256_cmpgt_epi32(rows, sy)));
      _mm256_store_si256(reinterpret_cast<__m256i*>(at_pixel + 8 * h),
                         _mm256_and_si256(inside[h], _mm256_add_epi32(_mm256_mullo_epi32(sy, step), sx)));
    }
    for (int k = 0; k < 16; ++k) pixels[k] = data[at_pixel[k]];  // (outside: pixel 0, replaced below)
    const __m256i inside16 = _mm256_permute4x64_epi64(_mm256_packs_epi32(inside[0], inside[1]), 0xd8);
    const __m128i inside8 =
        _mm_packs_epi16(_mm256_castsi256_si128(inside16), _mm256_extracti128_si256(inside16, 1));
    _mm_storeu_si128(
        reinterpret_cast<__m128i*>(d + i),
        _mm_blendv_epi8(border8, _mm_load_si128(reinterpret_cast<const __m128i*>(pixels)), inside8));
  }
  if (i < bw) mcmt::WarpSegmentNearestTail(src, X0, Y0, W0, M, i, bw, border, d);
}

}  // namespace avx2
#pragma GCC pop_options
#endif

// Whether every coordinate of points [0, n) lies in [-16384, 16383]: then differences of two fit in 16
// bits, squared distances and cross products with such differences in 31 (FirstLargest).
bool NarrowPoints(const cv::Point* src, int n) {
  uint32_t bits = 0;
  int i = 0;
#ifdef __SSE2__
  const __m128i shift = _mm_set1_epi32(16384);
  __m128i lanes = _mm_setzero_si128();
  for (; i + 2 <= n; i += 2)
    lanes =
        _mm_or_si128(lanes, _mm_add_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(src + i)), shift));
  alignas(16) uint32_t v[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(v), lanes);
  bits = v[0] | v[1] | v[2] | v[3];
#endif
  for (; i < n; ++i)
    bits |= (static_cast<uint32_t>(src[i].x) + 16384u) | (static_cast<uint32_t>(src[i].y) + 16384u);
  return (bits & ~0x7fffu) == 0;
}

// Over points [from, to) of src (NarrowPoints): v(i) = |p_i - s|^2 (kSquared) or |(p_i - s) x (dx, dy)|
// = |(y_i - s.y) dx - (x_i - s.x) dy| (|dx|, |dy| < 2^15), exact integers, as approxPolyDP's scans in
// double; where the largest exceeds *best, it and the first i where it is (a scan in index order that
// keeps its first maximum: ranges scanned in turn give the first maximum over their union). 4 points at a
// time: differences packed to 16 bits, then one multiply-add.
template <bool kSquared>
void FirstLargest(const cv::Point* src, int from, int to, cv::Point s, int dx, int dy, int* best,
                  int* best_at) {
  int i = from, value = -1, at = -1;
#ifdef __SSE2__
  if (to - from >= 8) {
    const __m128i start = _mm_set_epi32(s.y, s.x, s.y, s.x);
    const __m128i k =
        _mm_set_epi16(static_cast<int16_t>(dx), static_cast<int16_t>(-dy), static_cast<int16_t>(dx),
                      static_cast<int16_t>(-dy), static_cast<int16_t>(dx), static_cast<int16_t>(-dy),
                      static_cast<int16_t>(dx), static_cast<int16_t>(-dy));
    __m128i lane_value = _mm_set1_epi32(-1), lane_at = _mm_setzero_si128();
    __m128i index = _mm_set_epi32(i + 3, i + 2, i + 1, i);
    const __m128i four = _mm_set1_epi32(4);
    for (; i + 4 <= to; i += 4, index = _mm_add_epi32(index, four)) {
      const __m128i d01 = _mm_sub_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(src + i)), start);
      const __m128i d23 =
          _mm_sub_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(src + i + 2)), start);
      const __m128i d = _mm_packs_epi32(d01, d23);  // x0 y0 x1 y1 x2 y2 x3 y3
      __m128i v;
      if (kSquared) {
        v = _mm_madd_epi16(d, d);
      } else {
        v = _mm_madd_epi16(d, k);
        const __m128i sign = _mm_srai_epi32(v, 31);
        v = _mm_sub_epi32(_mm_xor_si128(v, sign), sign);
      }
      const __m128i larger = _mm_cmpgt_epi32(v, lane_value);
      lane_value = _mm_or_si128(_mm_and_si128(larger, v), _mm_andnot_si128(larger, lane_value));
      lane_at = _mm_or_si128(_mm_and_si128(larger, index), _mm_andnot_si128(larger, lane_at));
    }
    alignas(16) int32_t values[4], ats[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(values), lane_value);
    _mm_store_si128(reinterpret_cast<__m128i*>(ats), lane_at);
    for (int l = 0; l < 4; ++l)
      if (values[l] > value || (values[l] == value && ats[l] < at)) value = values[l], at = ats[l];
  }
#endif
  for (; i < to; ++i) {
    const int ex = src[i].x - s.x, ey = src[i].y - s.y;
    const int v = kSquared ? ex * ex + ey * ey : std::abs(ey * dx - ex * dy);
    if (v > value) value = v, at = i;
  }
  if (value > *best) *best = value, *best_at = at;
}

// The Douglas-Peucker approximation of OpenCV 4.6's cv::approxPolyDP (approx.cpp, approxPolyDP_) for int
// points, step for step: for a closed curve (or an open one whose ends coincide) the two points found
// farthest apart by three (one) passes from point 0 split it, then slices are split at their farthest point
// (cross product with the chord) until within `epsilon`, last pushed first; then one pass drops the points
// on [almost] straight lines. Every distance is exact in double (integer products below 2^53), so the
// comparisons are OpenCV's. Writes at most n points to `out` and returns their number. `stack` is scratch.
int ApproximatePolygon(const cv::Point* src, int n, bool closed, double epsilon,
                       std::vector<cv::Range>* stack, cv::Point* out) {
  if (n == 0) return 0;
  const double eps = epsilon * epsilon;
  stack->clear();
  const bool narrow = NarrowPoints(src, n);
  int count = n, pos = 0, written = 0, init_iters = 3;
  bool is_closed = closed, le_eps = false;
  cv::Range slice(0, 0), right(0, 0);
  cv::Point start(-1000000, -1000000), end(0, 0), pt(0, 0);
  auto read = [&](int* at) {
    const cv::Point p = src[*at];
    if (++*at >= count) *at = 0;
    return p;
  };
  if (!is_closed) {
    right.start = count;
    end = src[0];
    start = src[count - 1];
    if (start != end) {
      stack->push_back(cv::Range(0, count - 1));
    } else {
      is_closed = true;
      init_iters = 1;
    }
  }
  if (is_closed) {
    right.start = 0;
    for (int i = 0; i < init_iters; ++i) {  // the farthest point from the start, the start moved there
      double max_dist = 0;
      pos = (pos + right.start) % count;
      start = read(&pos);
      if (narrow) {  // the same scan (j = 1 .. count - 1 from the start) on 4 points at a time
        const int at_start = (pos + count - 1) % count;
        int best = 0, at = -1;
        FirstLargest<true>(src, at_start + 1, count, start, 0, 0, &best, &at);
        FirstLargest<true>(src, 0, at_start, start, 0, 0, &best, &at);
        if (at >= 0) right.start = (at - at_start + count) % count;
        le_eps = best <= eps;
        pos = at_start;  // where the scan leaves it
        continue;
      }
      for (int j = 1; j < count; ++j) {
        pt = read(&pos);
        const double dx = pt.x - start.x, dy = pt.y - start.y, dist = dx * dx + dy * dy;
        if (dist > max_dist) {
          max_dist = dist;
          right.start = j;
        }
      }
      le_eps = max_dist <= eps;
    }
    if (!le_eps) {
      right.end = slice.start = pos % count;
      slice.end = right.start = (right.start + slice.start) % count;
      stack->push_back(right);
      stack->push_back(slice);
    } else {
      out[written++] = start;
    }
  }
  while (!stack->empty()) {
    slice = stack->back();
    stack->pop_back();
    end = src[slice.end];
    pos = slice.start;
    start = read(&pos);
    if (pos != slice.end) {
      const double dx = end.x - start.x, dy = end.y - start.y;
      double max_dist = 0;
      CV_Assert(dx != 0 || dy != 0);
      if (narrow) {  // the same scan of pos .. slice.end - 1 (around the end) on 4 points at a time
        int best = 0, at = -1;
        const int sx = end.x - start.x, sy = end.y - start.y;
        FirstLargest<false>(src, pos, pos < slice.end ? slice.end : count, start, sx, sy, &best, &at);
        if (pos > slice.end) FirstLargest<false>(src, 0, slice.end, start, sx, sy, &best, &at);
        if (at >= 0) right.start = at;
        max_dist = best;
        pos = slice.end;
      }
      while (pos != slice.end) {
        pt = read(&pos);
        const double dist = std::fabs((pt.y - start.y) * dx - (pt.x - start.x) * dy);
        if (dist > max_dist) {
          max_dist = dist;
          right.start = (pos + count - 1) % count;
        }
      }
      le_eps = max_dist * max_dist <= eps * (dx * dx + dy * dy);
    } else {
      le_eps = true;
      start = src[slice.start];
    }
    if (le_eps) {
      out[written++] = start;
    } else {
      right.end = slice.end;
      slice.end = right.start;
      stack->push_back(right);
      stack->push_back(slice);
    }
  }
  if (!is_closed) out[written++] = src[count - 1];
  // The clean-up pass over the approximation, in place.
  is_closed = closed;
  count = written;
  int kept = written;
  auto read_out = [&](int* at) {
    const cv::Point p = out[*at];
    if (++*at >= count) *at = 0;
    return p;
  };
  pos = is_closed ? count - 1 : 0;
  start = read_out(&pos);
  int wpos = pos;
  pt = read_out(&pos);
  for (int i = !is_closed; i < count - !is_closed && kept > 2; ++i) {
    end = read_out(&pos);
    const double dx = end.x - start.x, dy = end.y - start.y;
    const double dist = std::fabs((pt.x - start.x) * dy - (pt.y - start.y) * dx);
    const double inner = (pt.x - start.x) * (end.x - pt.x) + (pt.y - start.y) * (end.y - pt.y);
    if (dist * dist <= 0.5 * eps * (dx * dx + dy * dy) && dx != 0 && dy != 0 && inner >= 0) {
      --kept;
      out[wpos] = start = end;
      if (++wpos >= count) wpos = 0;
      pt = read_out(&pos);
      ++i;
      continue;
    }
    out[wpos] = start = pt;
    if (++wpos >= count) wpos = 0;
    pt = end;
  }
  if (!is_closed) out[wpos] = pt;
  return kept;
}

// The number of bits set in v (inline: __builtin_popcountll is a library call without -mpopcnt).
inline int BitCount(uint64_t v) {
  v -= (v >> 1) & 0x5555555555555555ULL;
  v = (v & 0x3333333333333333ULL) + ((v >> 2) & 0x3333333333333333ULL);
  v = (v + (v >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<int>((v * 0x0101010101010101ULL) >> 56);
}

// The shared library's definition of `symbol` (a mangled name of an OpenCV function mcmt defines too):
// the next one in the dynamic linker's lookup, where ours hands the cases it does not handle.
template <typename Function>
Function LibraryDefinition(const char* symbol) {
  void* next = dlsym(RTLD_NEXT, symbol);
  CV_Assert(next != nullptr);
  return reinterpret_cast<Function>(next);
}

}  // namespace

void LinkOpenCvOverrides() {}

namespace {
// The floor of ArucoContourFloor in this thread: minMarkerPerimeterRate (0: none) and
// minSideLengthCanonicalImg.
thread_local double contour_floor_rate = 0;
thread_local int contour_floor_side = 0;

// The fewest points a border of a `size` binary image needs for cv::aruco::detectMarkers to look at it,
// under this thread's ArucoContourFloor (0: none; opencv_overrides.h).
size_t ArucoContourMinimum(cv::Size size) {
  if (!(contour_floor_rate > 0)) return 0;
  size_t floor = static_cast<unsigned int>(contour_floor_rate * std::max(size.width, size.height));
  if (contour_floor_side > 0) floor = std::min(floor, 4 * static_cast<size_t>(contour_floor_side));
  return floor;
}
}  // namespace

ArucoContourFloor::ArucoContourFloor(double min_perimeter_rate, int min_side_canonical)
    : previous_rate_(contour_floor_rate), previous_side_(contour_floor_side) {
  contour_floor_rate = min_perimeter_rate > 0 ? min_perimeter_rate : 0;
  contour_floor_side = min_side_canonical;
}

ArucoContourFloor::~ArucoContourFloor() {
  contour_floor_rate = previous_rate_;
  contour_floor_side = previous_side_;
}

namespace {
// AdaptiveThresholdPair's checks and its pass (`set` where cv::adaptiveThreshold's image is 255, 0
// elsewhere) into the rows small_row(y), large_row(y); `prepare` makes the images once the checks pass.
template <typename Prepare, typename SmallRow, typename LargeRow>
bool ThresholdPairInto(const cv::Mat& src, int k, double delta, uint8_t set, Prepare prepare,
                       SmallRow small_row, LargeRow large_row) {
  if (src.type() != CV_8UC1 || src.dims != 2 || (k != 3 && k != 5)) return false;
  const int offset_small = BoxMeanThresholdOffset(k * k), offset_large = BoxMeanThresholdOffset(9 * k * k);
  if (offset_small < 0 || offset_large < 0) return false;
  // cv::adaptiveThreshold's (THRESH_BINARY_INV): set where src - mean <= -floor(delta).
  const int at = std::clamp(-cvFloor(delta), -256, 256);
  prepare();
#if MCMT_SEARCH_HAS_AVX2
  if (DetectorUsesAvx2()) {
    ThresholdPairAgainstBoxMeansWith<Avx2BoxMean>(src, k, at, offset_small, offset_large, set, 0, small_row,
                                                  large_row);
    return true;
  }
#endif
  ThresholdPairAgainstBoxMeansWith<Sse2BoxMean>(src, k, at, offset_small, offset_large, set, 0, small_row,
                                                large_row);
  return true;
}
}  // namespace

bool AdaptiveThresholdPair(const cv::Mat& src, int k, double delta, cv::Mat* small, cv::Mat* large) {
  auto prepare = [&] {
    small->create(src.size(), CV_8UC1);
    large->create(src.size(), CV_8UC1);
    CV_Assert(small->data != src.data && large->data != src.data && small->data != large->data);
  };
  return ThresholdPairInto(
      src, k, delta, 255, prepare, [small](int y) { return small->ptr<uint8_t>(y); },
      [large](int y) { return large->ptr<uint8_t>(y); });
}

bool AdaptiveThresholdPairFramed(const cv::Mat& src, int k, double delta, FramedBinary* small,
                                 FramedBinary* large) {
  if (small == large) return false;
  auto prepare = [&] {
    PrepareFrame(src.cols, src.rows, small);
    PrepareFrame(src.cols, src.rows, large);
  };
  return ThresholdPairInto(
      src, k, delta, 1, prepare, [small](int y) { return reinterpret_cast<uint8_t*>(small->Row(y)); },
      [large](int y) { return reinterpret_cast<uint8_t*>(large->Row(y)); });
}

void FramedContours(FramedBinary* image, size_t min_points, std::vector<std::vector<cv::Point>>* contours) {
  thread_local std::vector<cv::Point> points;
  thread_local std::vector<size_t> ends;
  ListBorders(image, cv::Point(0, 0), &points, &ends);
  BordersToContours(points, ends, min_points, contours);
}

bool ThresholdBelowBlur(const cv::Mat& src, int k, int at, uint8_t below, uint8_t above, cv::Mat* dst) {
  if (src.type() != CV_8UC1 || k % 2 != 1 || k < 3 || k > 15 || at < -256 || at > 256) return false;
  const int offset = BoxMeanThresholdOffset(k * k);
  if (offset < 0) return false;
  CV_Assert(dst->type() == CV_8UC1 && dst->size() == src.size() && dst->data != src.data);
  ThresholdAgainstBoxMean(src, k, at, offset, below, above, false, *dst);
  return true;
}

}  // namespace mcmt

// OpenCV's cv::adaptiveThreshold, which cv::aruco::detectMarkers calls once per window size (a quarter of
// an accurate-mode frame's instructions): for 8-bit images and the local mean, the same box filter
// (cv::boxFilter, as OpenCV calls it) and then the same comparison, src - mean <= -floor(delta) for
// THRESH_BINARY_INV and src - mean > -ceil(delta) for THRESH_BINARY, vectorised, where OpenCV looks each
// pixel up in a 768-entry table one at a time (6 M instructions per 640 x 480 frame for two windows).
// Same binary image bit for bit (test_detector_unit, AdaptiveThresholdIsOpenCVs), hence the same contours
// and candidates. Defined in the program, it takes the place of the shared library's definition for every
// caller, the aruco module's included (the executable's symbols come first in the dynamic linker's
// lookup); every other case (Gaussian mean, other types, UMat) goes to OpenCV's own, the next definition.
namespace cv {

void adaptiveThreshold(InputArray src_array, OutputArray dst_array, double max_value, int method, int type,
                       int block_size, double delta) {
  if (method != ADAPTIVE_THRESH_MEAN_C || (type != THRESH_BINARY && type != THRESH_BINARY_INV) ||
      !src_array.isMat() || !dst_array.isMat() || src_array.type() != CV_8UC1 || block_size % 2 != 1 ||
      block_size <= 1 || max_value < 0) {
    using Function = void (*)(InputArray, OutputArray, double, int, int, int, double);
    static const Function opencv = mcmt::LibraryDefinition<Function>(
        "_ZN2cv17adaptiveThresholdERKNS_11_InputArrayERKNS_12_OutputArrayEdiiid");
    opencv(src_array, dst_array, max_value, method, type, block_size, delta);
    return;
  }
  Mat src = src_array.getMat();
  dst_array.create(src.size(), src.type());
  Mat dst = dst_array.getMat();
  const bool inverted = type == THRESH_BINARY_INV;
  // Set where src - mean <= `at` (inverted) or > `at`; differences lie within [-255, 255].
  const int at = std::clamp(inverted ? -cvFloor(delta) : -cvCeil(delta), -256, 256);
  const uint8_t on = saturate_cast<uint8_t>(max_value), below = inverted ? on : 0, above = inverted ? 0 : on;
  const int area = block_size * block_size;
  const int offset = block_size <= 15 ? mcmt::BoxMeanThresholdOffset(area) : -1;
  if (offset >= 0) {
    if (src.data == dst.data) src = src.clone();
    mcmt::ThresholdAgainstBoxMean(src, block_size, at, offset, below, above, true, dst);
    return;
  }
  Mat mean;
  if (src.data != dst.data) mean = dst;
  boxFilter(src, mean, src.type(), Size(block_size, block_size), Point(-1, -1), true,
            BORDER_REPLICATE | BORDER_ISOLATED);
  for (int y = 0; y < src.rows; ++y) {
    // The mean is written into dst (or dst is src): each pixel is read before it is written.
    const uint8_t* s = src.ptr<uint8_t>(y);
    const uint8_t* m = mean.ptr<uint8_t>(y);
    uint8_t* d = dst.ptr<uint8_t>(y);
    int x = 0;
#ifdef __SSE2__
    const __m128i zero = _mm_setzero_si128(), at16 = _mm_set1_epi16(static_cast<int16_t>(at));
    const __m128i below8 = _mm_set1_epi8(static_cast<char>(below)),
                  above8 = _mm_set1_epi8(static_cast<char>(above));
    for (; x + 16 <= src.cols; x += 16) {
      const __m128i sv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x));
      const __m128i mv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(m + x));
      const __m128i low = _mm_sub_epi16(_mm_unpacklo_epi8(sv, zero), _mm_unpacklo_epi8(mv, zero));
      const __m128i high = _mm_sub_epi16(_mm_unpackhi_epi8(sv, zero), _mm_unpackhi_epi8(mv, zero));
      const __m128i over = _mm_packs_epi16(_mm_cmpgt_epi16(low, at16), _mm_cmpgt_epi16(high, at16));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(d + x),
                       _mm_or_si128(_mm_and_si128(over, above8), _mm_andnot_si128(over, below8)));
    }
#endif
    for (; x < src.cols; ++x) d[x] = s[x] - m[x] <= at ? below : above;
  }
}

// OpenCV's cv::findContours without a hierarchy, which cv::aruco::detectMarkers calls once per window size
// with RETR_LIST and CHAIN_APPROX_NONE on its binary image (a fifth of an accurate-mode frame's
// instructions, most of them building and converting OpenCV's sequences and bounding boxes for the
// ~1,300 specks of a textured frame): for 8-bit images, these modes and vectors of point vectors, the same
// borders followed the same way (ListBorders), in the same order, each point the same; every other case
// goes to OpenCV's own. Same contours bit for bit (test_detector_unit, FindContoursIsOpenCVs).
void findContours(InputArray image_array, OutputArrayOfArrays contours_array, int mode, int method,
                  Point offset) {
  if (mode != RETR_LIST || method != CHAIN_APPROX_NONE || !image_array.isMat() ||
      image_array.type() != CV_8UC1 || image_array.empty() ||
      contours_array.kind() != _InputArray::STD_VECTOR_VECTOR ||
      CV_MAT_TYPE(contours_array.getFlags()) != CV_32SC2) {
    using Function = void (*)(InputArray, OutputArrayOfArrays, int, int, Point);
    static const Function opencv = mcmt::LibraryDefinition<Function>(
        "_ZN2cv12findContoursERKNS_11_InputArrayERKNS_12_OutputArrayEiiNS_6Point_IiEE");
    opencv(image_array, contours_array, mode, method, offset);
    return;
  }
  thread_local std::vector<Point> points;
  thread_local std::vector<size_t> ends;
  thread_local mcmt::FramedBinary framed;
  const Mat image = image_array.getMat();
  mcmt::FrameNonzero(image, &framed);
  mcmt::ListBorders(&framed, offset, &points, &ends);
  // Borders the aruco module would drop unseen are left out (ArucoContourFloor; 0: none).
  mcmt::BordersToContours(points, ends, mcmt::ArucoContourMinimum(image.size()),
                          static_cast<std::vector<std::vector<Point>>*>(contours_array.getObj()));
}

// OpenCV's cv::warpPerspective, which cv::aruco::detectMarkers calls for every candidate to read its
// cells (a 48 x 48 image with the default 6 px per cell, 100,000 instructions a call through OpenCV's
// invoker, map blocks and remap): for 8-bit images, INTER_NEAREST and a constant border, the same
// inverse map (cv::invert, as OpenCV inverts it) and the same positions bit for bit (WarpSegmentNearest,
// test_detector_unit WarpPerspectiveIsOpenCVs); every other case goes to OpenCV's own.
void warpPerspective(InputArray src_array, OutputArray dst_array, InputArray m_array, Size dsize, int flags,
                     int border_type, const Scalar& border_value) {
  const int m_type = m_array.type();
  if ((flags & INTER_MAX) != INTER_NEAREST || border_type != BORDER_CONSTANT || !src_array.isMat() ||
      !dst_array.isMat() || src_array.type() != CV_8UC1 || src_array.empty() ||
      (m_type != CV_32FC1 && m_type != CV_64FC1) || m_array.size() != Size(3, 3)) {
    using Function = void (*)(InputArray, OutputArray, InputArray, Size, int, int, const Scalar&);
    static const Function opencv = mcmt::LibraryDefinition<Function>(
        "_ZN2cv15warpPerspectiveERKNS_11_InputArrayERKNS_12_OutputArrayES2_"
        "NS_5Size_IiEEiiRKNS_7Scalar_IdEE");
    opencv(src_array, dst_array, m_array, dsize, flags, border_type, border_value);
    return;
  }
  Mat src = src_array.getMat();
  double m[9];
  Mat matrix(3, 3, CV_64F, m);
  m_array.getMat().convertTo(matrix, CV_64F);
  dst_array.create(dsize.empty() ? src.size() : dsize, src.type());
  Mat dst = dst_array.getMat();
  if (dst.data == src.data) src = src.clone();
  if (!(flags & WARP_INVERSE_MAP)) invert(matrix, matrix);
  const uint8_t border = saturate_cast<uint8_t>(border_value[0]);
  // OpenCV's column blocks (a block's map starts from its first column); its row blocks do not matter.
  const int block_width = std::min(32 * 32 / std::min(16, dst.rows), dst.cols);
  // The AVX2 code where the side model runs its AVX2 code (the same pixels), else the SSE2 code.
#if MCMT_SEARCH_HAS_AVX2
  if (mcmt::DetectorUsesAvx2() &&
      src.step[0] * static_cast<size_t>(src.rows) <= static_cast<size_t>(INT_MAX)) {
    for (int y = 0; y < dst.rows; ++y)
      for (int x = 0; x < dst.cols; x += block_width)
        mcmt::avx2::WarpSegmentNearest(src, m, x, y, std::min(block_width, dst.cols - x), border,
                                       dst.ptr<uint8_t>(y) + x);
    return;
  }
#endif
  for (int y = 0; y < dst.rows; ++y)
    for (int x = 0; x < dst.cols; x += block_width)
      mcmt::WarpSegmentNearest(src, m, x, y, std::min(block_width, dst.cols - x), border,
                               dst.ptr<uint8_t>(y) + x);
}

// OpenCV's cv::approxPolyDP, which cv::aruco::detectMarkers calls for every border long enough to be a
// marker (408 calls in bench_detector's 10 accurate frames, 19,000 instructions each, 7.7 M: most of it the
// library's generic point reads and its copies in and out): for int points in and a vector of int points
// out, the same approximation (ApproximatePolygon) written straight into the vector; every other case
// goes to OpenCV's own (test_detector_unit, ApproxPolyDpIsOpenCVs).
void approxPolyDP(InputArray curve_array, OutputArray approx_array, double epsilon, bool closed) {
  const Mat curve = curve_array.isVector() || curve_array.isMat() ? curve_array.getMat() : Mat();
  const int n = curve.isContinuous() ? curve.checkVector(2, CV_32S) : -1;
  if (n <= 0 || approx_array.kind() != _InputArray::STD_VECTOR || approx_array.type() != CV_32SC2 ||
      epsilon < 0.0 || !(epsilon < 1e30)) {
    using Function = void (*)(InputArray, OutputArray, double, bool);
    static const Function opencv =
        mcmt::LibraryDefinition<Function>("_ZN2cv12approxPolyDPERKNS_11_InputArrayERKNS_12_OutputArrayEdb");
    opencv(curve_array, approx_array, epsilon, closed);
    return;
  }
  thread_local std::vector<Point> points;
  thread_local std::vector<Range> stack;
  points.resize(n);
  const int kept = mcmt::ApproximatePolygon(curve.ptr<Point>(), n, closed, epsilon, &stack, points.data());
  auto& approx = *static_cast<std::vector<Point>*>(approx_array.getObj());
  approx.assign(points.begin(), points.begin() + kept);
}

// OpenCV's cv::meanStdDev, which cv::aruco::detectMarkers calls for every candidate's cell image (its inner
// part, 42 x 42 pixels with 6 px cells: 17,600 instructions a call through the library's plane iterator,
// 2.2 M in bench_detector's 10 accurate frames): for an 8-bit one-channel image without a mask, the same
// exact integer sums of the pixels and of their squares, then OpenCV's arithmetic on them (mean = sum
// times 1 / n, deviation = sqrt(max(squares times 1 / n - mean^2, 0))), written as it writes them; every
// other case goes to OpenCV's own (test_detector_unit, MeanStdDevIsOpenCVs).
void meanStdDev(InputArray src_array, OutputArray mean_array, OutputArray deviation_array,
                InputArray mask_array) {
  auto is_mat_or_none = [](const _OutputArray& a) {
    return a.kind() == _InputArray::NONE ||
           (a.kind() == _InputArray::MAT && !a.fixedSize() && !a.fixedType());
  };
  if (src_array.kind() != _InputArray::MAT || src_array.type() != CV_8UC1 || src_array.dims() > 2 ||
      src_array.empty() || !mask_array.empty() || src_array.cols() > 16384 || !is_mat_or_none(mean_array) ||
      !is_mat_or_none(deviation_array)) {
    using Function = void (*)(InputArray, OutputArray, OutputArray, InputArray);
    static const Function opencv =
        mcmt::LibraryDefinition<Function>("_ZN2cv10meanStdDevERKNS_11_InputArrayERKNS_12_OutputArrayES5_S2_");
    opencv(src_array, mean_array, deviation_array, mask_array);
    return;
  }
  const Mat& src = *static_cast<const Mat*>(src_array.getObj());
  int64_t sum = 0, squares = 0;
#ifdef __SSE2__
  const __m128i zero = _mm_setzero_si128();
  __m128i sums = zero, square_sums = zero;  // 64-bit halves; 32-bit lanes, added up every 65,536 pixels
  int pending = 0;                          // pixels in square_sums (each lane < 2^31)
  auto flush = [&]() {
    alignas(16) uint32_t lanes[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(lanes), square_sums);
    squares += static_cast<int64_t>(lanes[0]) + lanes[1] + lanes[2] + lanes[3];
    square_sums = zero;
    pending = 0;
  };
  auto add_squares = [&](__m128i low, __m128i high) {  // 16-bit pixels
    square_sums =
        _mm_add_epi32(square_sums, _mm_add_epi32(_mm_madd_epi16(low, low), _mm_madd_epi16(high, high)));
  };
#endif
  for (int y = 0; y < src.rows; ++y) {
    const uint8_t* p = src.ptr<uint8_t>(y);
    int x = 0;
#ifdef __SSE2__
    if (pending + src.cols > 65536) flush();
    pending += src.cols;
    for (; x + 16 <= src.cols; x += 16) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + x));
      sums = _mm_add_epi64(sums, _mm_sad_epu8(v, zero));
      add_squares(_mm_unpacklo_epi8(v, zero), _mm_unpackhi_epi8(v, zero));
    }
    if (x + 8 <= src.cols) {
      const __m128i v = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + x));
      sums = _mm_add_epi64(sums, _mm_sad_epu8(v, zero));
      add_squares(_mm_unpacklo_epi8(v, zero), zero);
      x += 8;
    }
#endif
    for (; x < src.cols; ++x) sum += p[x], squares += p[x] * p[x];
  }
#ifdef __SSE2__
  flush();
  sum += _mm_cvtsi128_si32(sums) + _mm_cvtsi128_si32(_mm_srli_si128(sums, 8));
#endif
  // OpenCV's sums are exact in double too (int blocks added up): the same values, the same arithmetic.
  const double scale = 1. / (static_cast<double>(src.rows) * src.cols);
  const double mean = static_cast<double>(sum) * scale;
  const double deviation = std::sqrt(std::max(static_cast<double>(squares) * scale - mean * mean, 0.));
  for (int j = 0; j < 2; ++j) {
    const _OutputArray& out = j == 0 ? mean_array : deviation_array;
    if (!out.needed()) continue;
    out.create(1, 1, CV_64F, -1, true);
    Mat dst = out.getMat();
    CV_Assert(dst.type() == CV_64F && dst.isContinuous() && (dst.cols == 1 || dst.rows == 1) &&
              dst.total() >= 1);
    double* d = dst.ptr<double>();
    d[0] = j == 0 ? mean : deviation;
    for (size_t k = 1; k < dst.total(); ++k) d[k] = 0;
  }
}

namespace aruco {

// OpenCV's cv::aruco::Dictionary::identify, which cv::aruco::detectMarkers calls for every candidate whose
// border is read as one (3.7 M instructions in bench_detector's 10 accurate frames, 80 % of them 24,000
// calls of cv::hal::normHamming on 5 bytes): the same search, the first id (in the dictionary's order)
// whose best rotation's Hamming distance (the smallest, the first rotation of it) is within the
// correction, each distance an inline popcount; bit matrices it does not take (not 8-bit, or codes over 8
// bytes) go to OpenCV's own (test_detector_unit, DictionaryIdentifyIsOpenCVs).
bool Dictionary::identify(const Mat& only_bits, int& idx, int& rotation, double max_correction_rate) const {
  const int nbytes = (markerSize * markerSize + 7) / 8;
  if (only_bits.type() != CV_8UC1 || only_bits.rows != markerSize || only_bits.cols != markerSize ||
      nbytes > 8 || bytesList.type() != CV_8UC4 || bytesList.cols != nbytes) {
    using Function = bool (*)(const Dictionary*, const Mat&, int&, int&, double);
    static const Function opencv =
        mcmt::LibraryDefinition<Function>("_ZNK2cv5aruco10Dictionary8identifyERKNS_3MatERiS5_d");
    return opencv(this, only_bits, idx, rotation, max_correction_rate);
  }
  const int max_correction = static_cast<int>(static_cast<double>(maxCorrectionBits) * max_correction_rate);
  const Mat candidate_bytes = getByteListFromBits(only_bits);
  CV_Assert(candidate_bytes.cols == nbytes);
  // A code's bytes as one word (little-endian, as x86-64): where 8 bytes from its start lie within the row
  // (4 nbytes bytes) one load masked, else the row's last 8 bytes shifted and masked (rows of 8 bytes at
  // least).
  const uint64_t mask = nbytes == 8 ? ~0ULL : (1ULL << (8 * nbytes)) - 1;
  const int row_bytes = 4 * nbytes;
  auto word = [&](const uint8_t* row, int at) {
    uint64_t w = 0;
    if (row_bytes < 8) {
      std::memcpy(&w, row + at, static_cast<size_t>(nbytes));
    } else if (at + 8 <= row_bytes) {
      std::memcpy(&w, row + at, 8);
      w &= mask;
    } else {
      std::memcpy(&w, row + row_bytes - 8, 8);
      w = (w >> (8 * (at + 8 - row_bytes))) & mask;
    }
    return w;
  };
  uint64_t candidate = 0;
  std::memcpy(&candidate, candidate_bytes.ptr<uint8_t>(), static_cast<size_t>(nbytes));
  idx = -1;
  for (int m = 0; m < bytesList.rows; ++m) {
    const uint8_t* row = bytesList.ptr<uint8_t>(m);
    int best = markerSize * markerSize + 1, best_rotation = -1;
    for (int r = 0; r < 4; ++r) {
      const int distance = mcmt::BitCount(word(row, r * nbytes) ^ candidate);
      if (distance < best) best = distance, best_rotation = r;
    }
    if (best <= max_correction) {
      idx = m;
      rotation = best_rotation;
      break;
    }
  }
  return idx != -1;
}

}  // namespace aruco

// OpenCV's cv::countNonZero, which cv::aruco::detectMarkers calls for every cell of every candidate (64
// calls a candidate, ~840 instructions each through OpenCV's type dispatch and plane iterator on a 4 x 4
// view): for 8-bit 2-D matrices the count row by row (16 pixels at a time); every other case goes to
// OpenCV's own (test_detector_unit, CountNonZeroIsOpenCVs).
int countNonZero(InputArray src_array) {
  // The kind from the flags (inline; kind(), type() and dims() are library calls, a third of a 4 x 4 cell's
  // count).
  const Mat* mat = (src_array.getFlags() & _InputArray::KIND_MASK) == _InputArray::MAT
                       ? static_cast<const Mat*>(src_array.getObj())
                       : nullptr;
  if (mat == nullptr || mat->type() != CV_8UC1 || mat->dims > 2) {
    using Function = int (*)(InputArray);
    static const Function opencv =
        mcmt::LibraryDefinition<Function>("_ZN2cv12countNonZeroERKNS_11_InputArrayE");
    return opencv(src_array);
  }
  const Mat& src = *mat;
  int64_t zeros = 0;
  for (int y = 0; y < src.rows; ++y) {
    const uint8_t* p = src.data + src.step[0] * static_cast<size_t>(y);
    int x = 0;
    if (src.cols == 4) {  // the aruco module's cells (6 px, margins of 1): one word a row
      zeros += mcmt::ZeroBytesOf4(p);
      continue;
    }
#ifdef __SSE2__
    while (x + 16 <= src.cols) {  // zeros per byte lane, summed every 255 loads at most
      __m128i lanes = _mm_setzero_si128();
      for (const int end = std::min(src.cols - 15, x + 255 * 16); x < end; x += 16)
        lanes = _mm_sub_epi8(lanes, _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + x)),
                                                   _mm_setzero_si128()));
      const __m128i sums = _mm_sad_epu8(lanes, _mm_setzero_si128());
      zeros += _mm_cvtsi128_si32(sums) + _mm_cvtsi128_si32(_mm_srli_si128(sums, 8));
    }
#endif
    for (; x < src.cols; ++x) zeros += p[x] == 0;
  }
  return static_cast<int>(static_cast<int64_t>(src.rows) * src.cols - zeros);
}

}  // namespace cv
