#include "tb_util.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace omniloc::tb {

std::string trace_path(const std::string& name, std::uint64_t seed) {
  std::filesystem::create_directories("traces");
  const auto path = std::filesystem::absolute("traces") / (name + "_seed" + std::to_string(seed) + ".vcd");
  return path.string();
}

std::uint64_t test_seed(std::uint64_t fallback) {
  std::uint64_t seed = fallback;
  if (const char* env = std::getenv("OMNILOC_SEED")) seed = std::strtoull(env, nullptr, 0);
  std::printf("seed %llu (set OMNILOC_SEED to repeat)\n", static_cast<unsigned long long>(seed));
  return seed;
}

}  // namespace omniloc::tb
