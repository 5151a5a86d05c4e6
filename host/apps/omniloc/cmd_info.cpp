// `omniloc version` and `omniloc regmap`: what the host was built against.
#include <cstdio>

#include "commands.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc/version.hpp"

namespace omniloc::cli {

namespace {
const char* access_name(regmap::Access a) {
  switch (a) {
    case regmap::Access::kReadOnly:
      return "RO";
    case regmap::Access::kReadWrite:
      return "RW";
    case regmap::Access::kWriteOneToClear:
      return "W1C";
    case regmap::Access::kReadOnlyLatching:
      return "RO (latches snapshot)";
  }
  return "?";
}

int print_version() {
  std::printf("%s\n", version_line("omniloc").c_str());
  return 0;
}

int print_regmap() {
  std::printf("%-8s %-18s %s\n", "address", "register", "access");
  for (const auto& r : regmap::kRegisters) {
    std::printf("0x%02X     %-18.*s %s\n", r.address, static_cast<int>(r.name.size()),
                r.name.data(), access_name(r.access));
  }
  return 0;
}
}  // namespace

Subcommand add_version(CLI::App& program) {
  return {program.add_subcommand("version",
                                 "print the host version and the register-map version it speaks"),
          print_version};
}

Subcommand add_regmap(CLI::App& program) {
  return {program.add_subcommand("regmap", "print the register map the host was built against"),
          print_regmap};
}

}  // namespace omniloc::cli
