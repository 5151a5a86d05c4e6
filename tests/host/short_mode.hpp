// Test helper: the short mode of the long tests. `make sanitize` (scripts/sanitize.sh, docs/
// TESTING.md "Every test under ASan + UBSan") sets OMNILOC_TEST_SHORT=1 and runs every host test in
// an ASan + UBSan tree; the longest tests then run fewer points, seeds, venues or frames, judged by
// the same thresholds. Unset (make test, CTest), every test runs in full.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace omniloc::test {

/// True when OMNILOC_TEST_SHORT is set to anything but "" or "0".
inline bool short_mode() {
  const char* v = std::getenv("OMNILOC_TEST_SHORT");
  return v != nullptr && *v != '\0' && std::strcmp(v, "0") != 0;
}

/// `full` normally, `short_count` in short mode, saying so in the test's output ("short mode: 3 of
/// 9 points").
inline int full_or_short(int full, int short_count, const char* what) {
  if (!short_mode() || short_count >= full) return full;
  std::printf("short mode (OMNILOC_TEST_SHORT): %d of %d %s\n", short_count, full, what);
  return short_count;
}

}  // namespace omniloc::test
