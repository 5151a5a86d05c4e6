// Seeds and trace paths shared by the RTL testbenches.
#pragma once

#include <cstdint>
#include <string>

namespace omniloc::rtl_tb {

/// The seed of a randomised test: OMNILOC_SEED from the environment if set, else `fallback`.
/// Printed either way, so a failure can be replayed.
std::uint64_t test_seed(const std::string& test_name, std::uint64_t fallback);

/// <build>/rtl-traces/<name>_seed<seed>.vcd (directory created).
std::string trace_path(const std::string& name, std::uint64_t seed);

/// Where a replay writes its trace: from `from_cycle` on (a whole soak would be gigabytes).
struct TraceRequest {
  std::string path;
  std::uint64_t from_cycle = 0;
};

}  // namespace omniloc::rtl_tb
