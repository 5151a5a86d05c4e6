// FNV-1a 64-bit hashing, used for geometry/camera fingerprints and database checksums.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace omniloc::detail {

inline constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;

[[nodiscard]] inline std::uint64_t fnv1a(const void* data, std::size_t size,
                                         std::uint64_t h = kFnvOffset) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

[[nodiscard]] inline std::uint64_t fnv1a_double(double x, std::uint64_t h) {
  if (x == 0.0) x = 0.0;  // -0 and +0 hash alike
  return fnv1a(&x, sizeof x, h);
}

}  // namespace omniloc::detail
