// The vision's reference implementations (internal, not installed): the straightforward versions
// the fast paths must equal (tests) and are measured against (benchmarks), and the portable
// fallbacks of the vectorised code. Not part of the library's API: matcher.hpp and line_scan.hpp
// declare what a program uses.
#pragma once

#include <cstdint>

#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/matcher.hpp"

namespace omniloc {

/// The straightforward version: OpenCV cvtColor + inRange masks of the whole image, then the same
/// rays. Same result as scan_image; kept as its reference and benchmark baseline.
[[nodiscard]] Scan scan_image_reference(const cv::Mat& bgr, const CameraModel& camera,
                                        double yaw_deg, const ScanParams& params = {});

/// Equation (5) on the rays up to their ends, straightforward scalar code (the reference).
[[nodiscard]] std::uint32_t sad_reference(const std::uint8_t* db_entry, const Scan& scan);

/// The bounded cost, straightforward scalar code on the raw scan (the reference). cap_px 1..127.
[[nodiscard]] CostTerms bounded_cost_reference(const std::uint8_t* db_entry, const Scan& scan,
                                               int cap_px);

/// The same on a prepared scan, a portable loop (the fallback without AVX2).
[[nodiscard]] CostTerms bounded_cost_portable(const std::uint8_t* db_entry,
                                              const PreparedScan& scan, int cap_px);

/// Global search with sad_reference and no shortcuts: the test and benchmark reference.
[[nodiscard]] MatchResult global_search_reference(const FeatureDb& db, const Scan& scan,
                                                  const MatchOptions& options = {});

/// The plain pattern search (4 neighbours per step, re-cast on every visit, halving when none is
/// better): the reference refine_match is measured against (bench_frame_path).
void refine_match_reference(const FieldGeometry& field, const CameraModel& camera,
                            const FieldScan& scan, MatchResult& result,
                            const MatchOptions& options = {});

/// refine_match as it stood before the speed work of issue 13 item 8 (the same walk and result):
/// the reference bench_frame_path measures refine_match against.
void refine_match_previous(const FieldGeometry& field, const CameraModel& camera,
                           const FieldScan& scan, MatchResult& result,
                           const MatchOptions& options = {});

}  // namespace omniloc
