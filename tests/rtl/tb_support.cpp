#include "tb_support.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>

namespace omniloc::rtl_tb {

std::uint64_t test_seed(const std::string& test_name, std::uint64_t fallback) {
  std::uint64_t seed = fallback;
  if (const char* env = std::getenv("OMNILOC_SEED"); env != nullptr && *env != '\0') {
    seed = std::strtoull(env, nullptr, 0);
  }
  std::cout << "[seed] " << test_name << " seed=" << seed << " (replay with OMNILOC_SEED=" << seed
            << ")" << std::endl;
  return seed;
}

std::string trace_path(const std::string& name, std::uint64_t seed) {
  const std::filesystem::path dir = std::filesystem::path(OMNILOC_RTL_TRACE_DIR);
  std::filesystem::create_directories(dir);
  return (dir / (name + "_seed" + std::to_string(seed) + ".vcd")).string();
}

}  // namespace omniloc::rtl_tb
