// Poses written by `omniloc replay` (poses.csv, read back) against the library's replay of the
// same recording: the same source and, to the CSV's precision, the same place and time.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

#include "omniloc/recording.hpp"

namespace omniloc::test {

inline void expect_same_poses(const std::vector<LocalizedPose>& csv,
                              const std::vector<LocalizedPose>& library) {
  ASSERT_EQ(csv.size(), library.size());
  for (std::size_t k = 0; k < csv.size(); ++k) {
    ASSERT_EQ(csv[k].source, library[k].source) << k;
    ASSERT_NEAR(csv[k].pose.x_cm, library[k].pose.x_cm, 1e-3) << k;
    ASSERT_NEAR(csv[k].pose.y_cm, library[k].pose.y_cm, 1e-3) << k;
    ASSERT_NEAR(csv[k].t_ms, library[k].t_ms, 1e-3) << k;
  }
}

}  // namespace omniloc::test
