// OpenCV's 8-bit BGR->HSV divisor tables (color_hsv: hsv_shift 12, rounded), shared by the line
// scan and the line extraction so that their per-pixel S and H equal cvtColor's bit for bit.
#pragma once

#include <cmath>

namespace omniloc::detail {

/// s = (diff * sat_div[v] + 2^11) >> 12; h = (h' * hue_div[diff] + 2^11) >> 12 (h' per OpenCV).
struct HsvTables {
  int sat_div[256];
  int hue_div[256];
  HsvTables() {
    sat_div[0] = hue_div[0] = 0;
    for (int i = 1; i < 256; ++i) {
      sat_div[i] = static_cast<int>(std::lround((255 << 12) / static_cast<double>(i)));
      hue_div[i] = static_cast<int>(std::lround((180 << 12) / (6.0 * i)));
    }
  }
};

inline const HsvTables& hsv_tables() {
  static const HsvTables t;  // immutable lookup tables, built once
  return t;
}

}  // namespace omniloc::detail
