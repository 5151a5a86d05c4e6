// LineExtractor's internals (not installed): its ray tables, and the reference walks the tests and
// benchmarks compare extract() with (LineExtractor::extract_reference, extract_with), reached
// through detail::LineExtractorAccess.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "omniloc/line_scan.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

struct LineExtractor::RayTable {
  std::vector<std::int32_t> offset;  // byte offset of each pixel in the image
  std::vector<std::uint8_t> bin;     // its integer radius
  std::vector<std::int32_t> begin;   // ray j's pixels are [begin[j], begin[j + 1])
  std::vector<std::uint8_t> sector;  // per ray
  std::vector<bool> hidden;          // per ray: in a mast sector
  int step_bytes = 0;                // image row size the offsets assume
  // The fast walk's view of the same pixels: each pixel's index (row * width + column) in the
  // per-frame code plane, and per image row the columns [row_u0, row_u1] any ray touches.
  std::vector<std::int32_t> pixel;
  std::vector<std::int32_t> row_u0, row_u1;
  // ... and bin by bin: ray j's bins are [bin_begin[j], bin_begin[j + 1]), the first numbered
  // first_bin[j] and the others following; a bin's pixels are bin_pixel and bin_pixel +
  // bin_second.
  bool bins_ok = false;
  std::vector<std::int32_t> bin_begin, bin_pixel;
  std::vector<std::int16_t> bin_second;  // 0, +-1 or +-width: a 4-connected neighbour
  std::vector<std::uint8_t> first_bin;
  // Where along the ray each pixel's centre lies (in samples: px / scan_step_px), and per bin its
  // outer pixel's (a bin b holds the centres in (b - 1, b] and reports its brighter pixel, the
  // outer one on a rising edge): where a line's edge is placed between two bins.
  std::vector<float> along, bin_centre;
  // The lockstep walk's layout: the rays that are not hidden, 8 to a group (one per lane, the
  // last group padded with empty lanes). Group g's steps are [lock_begin[g], lock_begin[g + 1]);
  // step s of lane l reads lock_pixel0/1[8 s + l] (the bin's two pixels, equal for a one-pixel
  // bin; past the lane's bins, pixel 0). Per lane (8 g + l): its ray (-1: padding) and bins.
  std::vector<std::int32_t> lock_begin, lock_pixel0, lock_pixel1, lock_ray, lock_bins;
};

namespace detail {

/// The private walks of a LineExtractor: every one gives the same bytes as extract().
struct LineExtractorAccess {
  using Walk = LineExtractor::Walk;
  /// The straightforward walk (every pixel's H, S, V computed on every ray that touches it).
  static BearingScan extract_reference(LineExtractor& ex, const cv::Mat& bgr, int rays_per_degree,
                                       ExtractionReport* report = nullptr) {
    return ex.extract_reference(bgr, rays_per_degree, report);
  }
  static BearingScan extract_with(LineExtractor& ex, Walk how, const cv::Mat& bgr,
                                  int rays_per_degree, ExtractionReport* report = nullptr) {
    return ex.extract_with(how, bgr, rays_per_degree, report);
  }
};

}  // namespace detail
}  // namespace omniloc
