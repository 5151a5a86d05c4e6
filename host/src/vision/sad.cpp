// Match-cost kernels: the paper's SAD and the bounded per-crossing cost. The AVX2 kernel is
// compiled for AVX2 with a target attribute (the library itself is built for the baseline ISA) and
// chosen at run time, so the binary still runs on older CPUs.
#include <algorithm>
#include <cstdlib>

#include "omniloc/detail/vision_reference.hpp"
#include "omniloc/matcher.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define OMNILOC_HAVE_X86 1
#endif

namespace omniloc {

namespace {

// A database byte at or beyond the ray's end becomes kNoCrossing (unknown, like the scan's).
inline int clip_to_end(int d, int end) {
  return d >= end ? int{kNoCrossing} : d;
}

std::uint32_t sad_portable(const std::uint8_t* db, const std::uint8_t* obs,
                           const std::uint8_t* end) {
  std::uint32_t sum = 0;
  for (int i = 0; i < kFeatureBytes; ++i) {
    const int d = clip_to_end(db[i], end[i]);
    const int o = obs[i];
    sum += static_cast<std::uint32_t>(d > o ? d - o : o - d);
  }
  return sum;
}

#ifdef OMNILOC_HAVE_X86
__attribute__((target("avx2"))) std::uint32_t sad_avx2(const std::uint8_t* db,
                                                       const std::uint8_t* obs,
                                                       const std::uint8_t* end) {
  static_assert(kFeatureBytes % 32 == 0);
  __m256i acc = _mm256_setzero_si256();
  for (int i = 0; i < kFeatureBytes; i += 32) {
    const __m256i d = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(db + i));
    const __m256i e = _mm256_load_si256(reinterpret_cast<const __m256i*>(end + i));
    const __m256i o = _mm256_load_si256(reinterpret_cast<const __m256i*>(obs + i));
    const __m256i beyond = _mm256_cmpeq_epi8(_mm256_max_epu8(d, e), d);  // 0xFF where d >= end
    acc = _mm256_add_epi64(acc, _mm256_sad_epu8(_mm256_or_si256(d, beyond), o));
  }
  const __m128i s = _mm_add_epi64(_mm256_castsi256_si128(acc), _mm256_extracti128_si256(acc, 1));
  return static_cast<std::uint32_t>(_mm_cvtsi128_si64(s) + _mm_extract_epi64(s, 1));
}

bool cpu_has_avx2() {
  static const bool has =
      __builtin_cpu_supports("avx2") != 0;  // CPU feature, fixed for the process
  return has;
}
#endif

}  // namespace

std::uint32_t sad_reference(const std::uint8_t* db_entry, const Scan& scan) {
  std::uint32_t sum = 0;
  for (int k = 0; k < kScanRays; ++k) {
    const int end = scan.ray_end_px[static_cast<std::size_t>(k)];
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      const int i = k * kCrossingsPerRay + n;
      const int d = clip_to_end(db_entry[i], end);
      const int o = clip_to_end(scan.radii_px[static_cast<std::size_t>(i)], end);
      sum += static_cast<std::uint32_t>(std::abs(d - o));
    }
  }
  return sum;
}

std::uint32_t sad_fast(const std::uint8_t* db_entry, const PreparedScan& s) {
#ifdef OMNILOC_HAVE_X86
  if (cpu_has_avx2()) return sad_avx2(db_entry, s.radii.data(), s.end.data());
#endif
  return sad_portable(db_entry, s.radii.data(), s.end.data());
}

PreparedScan prepare_scan(const Scan& scan) {
  PreparedScan p;
  for (int k = 0; k < kScanRays; ++k) {
    const std::uint8_t end = scan.ray_end_px[static_cast<std::size_t>(k)];
    p.rays_used += end != kRayHidden ? 1 : 0;
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      const auto i = static_cast<std::size_t>(k * kCrossingsPerRay + n);
      p.radii[i] = static_cast<std::uint8_t>(clip_to_end(scan.radii_px[i], end));
      p.end[i] = end;
    }
  }
  return p;
}

// ---- The bounded per-crossing cost (MatchCost::kBounded) -------------------------------------
//
// Per ray, each crossing on one side (scan or database, the database clipped at the ray's end)
// is compared with the NEAREST crossing on the other side of the same ray, |d - o| capped at
// cap_px; a crossing with no counterpart on that ray costs cap_px. The sum runs over both sides,
// so a matched pair counts twice (once from each side) and an unmatched crossing once, and it is
// normalised by the crossings on both sides: the error is a mean in px within [0, cap_px].

namespace {

// Distance from x (a crossing) to y (a crossing or kNoCrossing): kNoCrossing is never near.
inline int crossing_distance(int x, int y) {
  return y == kNoCrossing ? 255 : std::abs(x - y);
}

// One side of the ray: the cost of each crossing of `a` against the nearest of `b`.
inline std::uint32_t one_side(const std::uint8_t* a, const std::uint8_t* b, int cap_px,
                              std::uint32_t& crossings) {
  std::uint32_t sum = 0;
  for (int n = 0; n < kCrossingsPerRay; ++n) {
    if (a[n] == kNoCrossing) continue;
    ++crossings;
    int nearest = 255;
    for (int m = 0; m < kCrossingsPerRay; ++m)
      nearest = std::min(nearest, crossing_distance(a[n], b[m]));
    sum += static_cast<std::uint32_t>(std::min(nearest, cap_px));
  }
  return sum;
}

inline CostTerms bounded_ray(const std::uint8_t* d, const std::uint8_t* o, int cap_px) {
  CostTerms t;
  t.sum = one_side(d, o, cap_px, t.crossings) + one_side(o, d, cap_px, t.crossings);
  return t;
}

#ifdef OMNILOC_HAVE_X86
// Byte shuffles that rotate every 4-byte group (one ray) by 1, 2, 3: slot n then holds crossing (n
// + r) % 4.
alignas(32) constexpr std::uint8_t kRotate[3][32] = {
    {1, 2, 3, 0, 5, 6, 7, 4, 9, 10, 11, 8, 13, 14, 15, 12,
     1, 2, 3, 0, 5, 6, 7, 4, 9, 10, 11, 8, 13, 14, 15, 12},
    {2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13,
     2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13},
    {3, 0, 1, 2, 7, 4, 5, 6, 11, 8, 9, 10, 15, 12, 13, 14,
     3, 0, 1, 2, 7, 4, 5, 6, 11, 8, 9, 10, 15, 12, 13, 14}};

// Per byte of a: min over the 4 crossings of b on the same ray of the distance, capped; 0 where a
// has no crossing.
__attribute__((target("avx2"))) inline __m256i side_avx2(__m256i a, __m256i a_none, __m256i b,
                                                         __m256i cap) {
  const __m256i ones = _mm256_set1_epi8(static_cast<char>(0xFF));
  __m256i nearest = ones;
  for (int r = 0; r < kCrossingsPerRay; ++r) {
    const __m256i br =
        r == 0 ? b
               : _mm256_shuffle_epi8(
                     b, _mm256_load_si256(reinterpret_cast<const __m256i*>(kRotate[r - 1])));
    const __m256i diff = _mm256_or_si256(_mm256_subs_epu8(a, br), _mm256_subs_epu8(br, a));
    const __m256i far =
        _mm256_or_si256(diff, _mm256_cmpeq_epi8(br, ones));  // no crossing: never near
    nearest = _mm256_min_epu8(nearest, far);
  }
  return _mm256_andnot_si256(a_none, _mm256_min_epu8(nearest, cap));
}

__attribute__((target("avx2"))) CostTerms bounded_avx2(const std::uint8_t* db,
                                                       const std::uint8_t* obs,
                                                       const std::uint8_t* end, int cap_px) {
  const __m256i ones = _mm256_set1_epi8(static_cast<char>(0xFF));
  const __m256i cap = _mm256_set1_epi8(static_cast<char>(cap_px));
  __m256i acc = _mm256_setzero_si256();
  std::uint32_t crossings = 0;
  for (int i = 0; i < kFeatureBytes; i += 32) {
    const __m256i raw = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(db + i));
    const __m256i e = _mm256_load_si256(reinterpret_cast<const __m256i*>(end + i));
    const __m256i o = _mm256_load_si256(reinterpret_cast<const __m256i*>(obs + i));
    const __m256i d = _mm256_or_si256(
        raw, _mm256_cmpeq_epi8(_mm256_max_epu8(raw, e), raw));  // clipped at the end
    const __m256i d_none = _mm256_cmpeq_epi8(d, ones), o_none = _mm256_cmpeq_epi8(o, ones);
    const __m256i cost =
        _mm256_adds_epu8(side_avx2(d, d_none, o, cap), side_avx2(o, o_none, d, cap));
    acc = _mm256_add_epi64(acc, _mm256_sad_epu8(cost, _mm256_setzero_si256()));
    crossings += static_cast<std::uint32_t>(
                     __builtin_popcount(~static_cast<unsigned>(_mm256_movemask_epi8(d_none)))) +
                 static_cast<std::uint32_t>(
                     __builtin_popcount(~static_cast<unsigned>(_mm256_movemask_epi8(o_none))));
  }
  const __m128i s = _mm_add_epi64(_mm256_castsi256_si128(acc), _mm256_extracti128_si256(acc, 1));
  return {static_cast<std::uint32_t>(_mm_cvtsi128_si64(s) + _mm_extract_epi64(s, 1)), crossings};
}
#endif

}  // namespace

CostTerms bounded_cost_reference(const std::uint8_t* db_entry, const Scan& scan, int cap_px) {
  CostTerms total;
  for (int k = 0; k < kScanRays; ++k) {
    const int end = scan.ray_end_px[static_cast<std::size_t>(k)];
    std::uint8_t d[kCrossingsPerRay], o[kCrossingsPerRay];
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      const int i = k * kCrossingsPerRay + n;
      d[n] = static_cast<std::uint8_t>(clip_to_end(db_entry[i], end));
      o[n] =
          static_cast<std::uint8_t>(clip_to_end(scan.radii_px[static_cast<std::size_t>(i)], end));
    }
    const CostTerms t = bounded_ray(d, o, cap_px);
    total.sum += t.sum;
    total.crossings += t.crossings;
  }
  return total;
}

CostTerms bounded_cost_portable(const std::uint8_t* db_entry, const PreparedScan& s, int cap_px) {
  CostTerms total;
  for (int i = 0; i < kFeatureBytes; i += kCrossingsPerRay) {
    std::uint8_t d[kCrossingsPerRay];
    for (int n = 0; n < kCrossingsPerRay; ++n)
      d[n] = static_cast<std::uint8_t>(
          clip_to_end(db_entry[i + n], s.end[static_cast<std::size_t>(i + n)]));
    const CostTerms t = bounded_ray(d, s.radii.data() + i, cap_px);
    total.sum += t.sum;
    total.crossings += t.crossings;
  }
  return total;
}

CostTerms bounded_cost_fast(const std::uint8_t* db_entry, const PreparedScan& s, int cap_px) {
#ifdef OMNILOC_HAVE_X86
  if (cpu_has_avx2()) return bounded_avx2(db_entry, s.radii.data(), s.end.data(), cap_px);
#endif
  return bounded_cost_portable(db_entry, s, cap_px);
}

double match_error(const std::uint8_t* db_entry, const PreparedScan& s, const MatchOptions& opt) {
  if (s.rays_used == 0) return kNoError;
  if (opt.cost == MatchCost::kPaperSad)
    return static_cast<double>(sad_fast(db_entry, s)) / s.rays_used;
  const CostTerms t = bounded_cost_fast(db_entry, s, opt.crossing_cap_px);
  return t.crossings == 0 ? kNoError : static_cast<double>(t.sum) / t.crossings;
}

}  // namespace omniloc
