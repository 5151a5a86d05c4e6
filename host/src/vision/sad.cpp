// SAD kernels. The AVX2 kernel is compiled for AVX2 with a target attribute (the library itself is
// built for the baseline ISA) and chosen at run time, so the binary still runs on older CPUs.
#include <cstdlib>

#include "omniloc/matcher.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define OMNILOC_HAVE_X86 1
#endif

namespace omniloc {

namespace {

// A database byte at or beyond the ray's end becomes kNoCrossing (unknown, like the scan's).
inline int clip_to_end(int d, int end) { return d >= end ? int{kNoCrossing} : d; }

std::uint32_t sad_portable(const std::uint8_t* db, const std::uint8_t* obs, const std::uint8_t* end) {
  std::uint32_t sum = 0;
  for (int i = 0; i < kFeatureBytes; ++i) {
    const int d = clip_to_end(db[i], end[i]);
    const int o = obs[i];
    sum += static_cast<std::uint32_t>(d > o ? d - o : o - d);
  }
  return sum;
}

#ifdef OMNILOC_HAVE_X86
__attribute__((target("avx2"))) std::uint32_t sad_avx2(const std::uint8_t* db, const std::uint8_t* obs,
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
  static const bool has = __builtin_cpu_supports("avx2") != 0;  // CPU feature, fixed for the process
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

}  // namespace omniloc
