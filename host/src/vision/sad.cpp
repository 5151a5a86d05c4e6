// SAD kernels. The AVX2 kernel is compiled for AVX2 with a target attribute (the library itself is
// built for the baseline ISA) and chosen at run time, so the binary still runs on older CPUs.
#include <cstdlib>
#include <cstring>

#include "omniloc/matcher.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define OMNILOC_HAVE_X86 1
#endif

namespace omniloc {

namespace {

std::uint32_t sad_portable(const std::uint8_t* db, const std::uint8_t* obs, const std::uint8_t* mask) {
  std::uint32_t sum = 0;
  for (int i = 0; i < kFeatureBytes; ++i) {
    const int d = db[i] & mask[i];
    const int o = obs[i];
    sum += static_cast<std::uint32_t>(d > o ? d - o : o - d);
  }
  return sum;
}

#ifdef OMNILOC_HAVE_X86
__attribute__((target("avx2"))) std::uint32_t sad_avx2(const std::uint8_t* db, const std::uint8_t* obs,
                                                        const std::uint8_t* mask) {
  static_assert(kFeatureBytes % 32 == 0);
  __m256i acc = _mm256_setzero_si256();
  for (int i = 0; i < kFeatureBytes; i += 32) {
    const __m256i d = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(db + i));
    const __m256i m = _mm256_load_si256(reinterpret_cast<const __m256i*>(mask + i));
    const __m256i o = _mm256_load_si256(reinterpret_cast<const __m256i*>(obs + i));
    acc = _mm256_add_epi64(acc, _mm256_sad_epu8(_mm256_and_si256(d, m), o));
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
    if (scan.ray_valid[static_cast<std::size_t>(k)] == 0) continue;
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      const int i = k * kCrossingsPerRay + n;
      sum += static_cast<std::uint32_t>(std::abs(int{db_entry[i]} - int{scan.radii_px[static_cast<std::size_t>(i)]}));
    }
  }
  return sum;
}

std::uint32_t sad_fast(const std::uint8_t* db_entry, const PreparedScan& s) {
#ifdef OMNILOC_HAVE_X86
  if (cpu_has_avx2()) return sad_avx2(db_entry, s.masked.data(), s.mask.data());
#endif
  return sad_portable(db_entry, s.masked.data(), s.mask.data());
}

PreparedScan prepare_scan(const Scan& scan) {
  PreparedScan p;
  // One 4-byte word per ray: the ray's crossings or zero, and an all-ones or zero mask.
  for (int k = 0; k < kScanRays; ++k) {
    const bool valid = scan.ray_valid[static_cast<std::size_t>(k)] != 0;
    p.rays_used += valid ? 1 : 0;
    std::uint32_t word = 0;
    std::memcpy(&word, scan.radii_px.data() + k * kCrossingsPerRay, sizeof word);
    const std::uint32_t mask = valid ? 0xFFFFFFFFu : 0u;
    word &= mask;
    std::memcpy(p.masked.data() + k * kCrossingsPerRay, &word, sizeof word);
    std::memcpy(p.mask.data() + k * kCrossingsPerRay, &mask, sizeof mask);
  }
  return p;
}

}  // namespace omniloc
