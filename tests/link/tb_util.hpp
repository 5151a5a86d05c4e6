// Seeds and trace paths shared by the link testbenches.
#pragma once

#include <cstdint>
#include <string>

namespace omniloc::tb {

/// Where a failing scenario's trace goes: <build>/traces/<name>_seed<seed>.vcd.
std::string trace_path(const std::string& name, std::uint64_t seed);

/// The seed of a randomised test: OMNILOC_SEED from the environment, or `fallback`; printed.
std::uint64_t test_seed(std::uint64_t fallback);

}  // namespace omniloc::tb
