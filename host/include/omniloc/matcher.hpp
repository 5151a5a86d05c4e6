// Matcher: the match error between an observed scan and database entries (by default a bounded
// per-crossing cost normalised by the crossings compared, so that one missing or spurious crossing
// costs a bounded amount and a threshold E_TH means the same on real and rendered frames, with or
// without obstacles; equation (5)'s literal SAD stays available as MatchCost::kPaperSad), the
// global search (6) over every grid point,
// the local search within a range A around a pose, sub-grid refinement by ray casting, yaw
// estimation from the scan, and an ambiguity report (best versus second-best distinct minimum).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/line_scan.hpp"

namespace omniloc {

/// An observed scan ready for matching: each ray's end repeated on its four bytes, and the radii
/// with every value at or beyond the end set to kNoCrossing. A database crossing at or beyond the
/// end is compared as kNoCrossing too, so a hidden ray (end 0) costs nothing and a ray cut short
/// by an obstacle is compared up to the obstacle only.
struct PreparedScan {
  alignas(32) std::array<std::uint8_t, kFeatureBytes> radii{};
  alignas(32) std::array<std::uint8_t, kFeatureBytes> end{};
  int rays_used = 0;
};
[[nodiscard]] PreparedScan prepare_scan(const Scan& scan);

/// One frame's scan as every matcher step takes it: turned into the field frame at one heading
/// and prepared for the SAD, once. The localizer makes one per frame (and per heading it tries)
/// and hands it to the search, the interpolation and the refinement; the overloads below that
/// take a plain Scan make one on the spot.
struct FieldScan {
  double yaw_deg =
      0.0;  // the heading the robot-frame scan was rotated by (0 for a field-frame Scan)
  /// Where its rays really point: field ray k is the robot-frame ray nearest to bearing k, which
  /// at 1 / rays_per_degree steps lies this far off (the same for every k, at most half a step).
  /// The grid search ignores it (the database is cast at whole degrees); the ray-cast refinement
  /// casts at k + bearing_offset_deg, so a frame far from the lines is not off by the rounding.
  double bearing_offset_deg = 0.0;
  Scan scan;  // field frame
  PreparedScan prepared;
};
/// rotate_to_field(bearings, yaw_deg), then prepare_scan.
[[nodiscard]] FieldScan make_field_scan(const BearingScan& bearings, double yaw_deg);
/// A scan already in the field frame (scan_image at a known yaw, a database entry).
[[nodiscard]] FieldScan make_field_scan(const Scan& field_frame_scan);

/// The same sum, vectorised (AVX2 when the CPU has it, else a portable loop the compiler
/// vectorises).
[[nodiscard]] std::uint32_t sad_fast(const std::uint8_t* db_entry, const PreparedScan& scan);

/// The match error (docs/VISION.md, "Match error").
enum class MatchCost {
  /// Per ray, every crossing of the scan and of the database entry (clipped at the ray's end) is
  /// compared with the nearest crossing on the other side of the same ray: min(|d - o|, cap_px),
  /// and cap_px when that side has none on the ray. Summed over both sides and divided by the
  /// crossings on both sides (the "usable crossings"): a mean in px within [0, cap_px].
  kBounded,
  /// Equation (5) as printed: slot-by-slot |d - o| over the four crossings (a missing crossing
  /// costs |255 - r|), divided by the rays used.
  kPaperSad,
};

/// A bounded cost before normalisation: the capped sum and the crossings it covers.
struct CostTerms {
  std::uint32_t sum = 0;
  std::uint32_t crossings = 0;
  bool operator==(const CostTerms&) const = default;
};
/// The same, AVX2 when the CPU has it (else bounded_cost_portable); equal bit for bit.
[[nodiscard]] CostTerms bounded_cost_fast(const std::uint8_t* db_entry, const PreparedScan& scan,
                                          int cap_px);

/// How image_to_position goes below the grid step.
enum class Refinement {
  kNone,         // the best grid point
  kInterpolate,  // V-shaped fit of the error at the best point and its four neighbours (~1 us)
  kRayCast,  // then a pattern search on (linearised) ray-cast errors at off-grid points (~0.5 ms)
};

struct MatchOptions {
  MatchCost cost = MatchCost::kBounded;
  int crossing_cap_px = 16;  // kBounded's cap C (the localizer config's crossing_cap_px)
  double ambiguity_separation_cm = 50.0;  // a second minimum must lie at least this far away
  double ambiguity_ratio = 1.25;          // ambiguous when second_error <= ratio * best error
  Refinement refinement = Refinement::kInterpolate;
  double refine_start_step_cm = 2.5;  // ray-cast pattern search: first and last step (starting
  double refine_min_step_cm =
      0.625;                      //   at 1.25 gets trapped where the interpolation is ~10 cm off)
  double refine_reach_cm = 10.0;  // never further than this from the best grid point
};

inline constexpr double kNoError = std::numeric_limits<double>::infinity();

/// The normalised error of one database entry (or expected scan) under options.cost; kNoError
/// when nothing can be compared (no ray seen, or kBounded with no crossing on either side).
[[nodiscard]] double match_error(const std::uint8_t* db_entry, const PreparedScan& scan,
                                 const MatchOptions& options);

struct MatchResult {
  Eigen::Vector2d position_cm{0.0, 0.0};       // refined when requested, else the grid point
  Eigen::Vector2d grid_position_cm{0.0, 0.0};  // best grid point
  int cell = -1;
  double error = kNoError;          // normalised (match_error), at the best grid point
  double refined_error = kNoError;  // at position_cm (equals error without refinement)
  double second_error = kNoError;   // best distinct local minimum elsewhere (global search)
  Eigen::Vector2d second_position_cm{0.0, 0.0};
  bool ambiguous = false;
  int rays_used = 0;
  int cells_searched = 0;
  int refine_probes = 0;  // points refine_match evaluated
  int refine_casts =
      0;  // full ray casts among them (each ~0.1 ms; the rest come from a linear model)
  /// The position's uncertainty from the error surface's curvature at position_cm (refine_match
  /// only, docs/LOCALIZER.md "Uncertainty"): the covariance in cm^2 and sigma_cm = sqrt(trace), the
  /// radial RMS error it predicts. sigma_cm stays kNoError when it could not be computed (no
  /// ray-cast refinement, too few crossings, or the crossings do not fix the position).
  Eigen::Matrix2d covariance_cm2 = Eigen::Matrix2d::Zero();
  double sigma_cm = kNoError;
};

/// Global search over all grid points.
[[nodiscard]] MatchResult global_search(const FeatureDb& db, const FieldScan& scan,
                                        const MatchOptions& options = {});
[[nodiscard]] MatchResult global_search(const FeatureDb& db, const Scan& scan,
                                        const MatchOptions& options = {});
/// Grid points within range_cm (per axis) of the grid point nearest to centre_cm: 0 -> 1 point,
/// 10 -> 3 x 3, 20 -> 5 x 5, 30 -> 7 x 7 on a 10 cm grid (see local_search_reach_cells).
[[nodiscard]] MatchResult local_search(const FeatureDb& db, const FieldScan& scan,
                                       const Eigen::Vector2d& centre_cm, double range_cm,
                                       const MatchOptions& options = {});
[[nodiscard]] MatchResult local_search(const FeatureDb& db, const Scan& scan,
                                       const Eigen::Vector2d& centre_cm, double range_cm,
                                       const MatchOptions& options = {});
/// How many grid cells a local search reaches on each side of its centre for a range:
/// floor(range / step), so a range that is not a whole multiple of the step is cut down to one
/// (at a 20 cm step, 10 cm searches the centre only and 30 cm the same 3 x 3 as 20 cm).
[[nodiscard]] int local_search_reach_cells(double range_cm, double grid_step_cm);

/// Normalised error (match_error) of the scan against the expected scan at any position (ray cast
/// on the fly).
[[nodiscard]] double error_at(const FieldGeometry& field, const CameraModel& camera,
                              const PreparedScan& scan, const Eigen::Vector2d& position_cm,
                              const MatchOptions& options = {}, double bearing_offset_deg = 0.0);

/// Sub-grid position from the database errors at the best grid point and its four neighbours,
/// fitting a V (the shape of a sum of absolute differences, and of the bounded cost near its
/// minimum) along x and along y; updates position_cm (within half a step of the grid point).
/// refined_error is left unchanged.
void interpolate_match(const FeatureDb& db, const FieldScan& scan, MatchResult& result,
                       const MatchOptions& options = {});
void interpolate_match(const FeatureDb& db, const Scan& scan, MatchResult& result,
                       const MatchOptions& options = {});

/// Pattern search on ray-cast errors from result.position_cm with halving steps (4 neighbours per
/// step) and below each step the V fitted through the centre and its neighbours. The points come
/// from a linearised ray cast (three casts give every white run's radius and its gradient; rays
/// where that does not hold are cast exactly) and the end point is cast exactly: refined_error is
/// the true ray-cast error there, never above the start's. Updates position_cm, refined_error,
/// refine_probes and refine_casts.
void refine_match(const FieldGeometry& field, const CameraModel& camera, const FieldScan& scan,
                  MatchResult& result, const MatchOptions& options = {});
void refine_match(const FieldGeometry& field, const CameraModel& camera, const Scan& scan,
                  MatchResult& result, const MatchOptions& options = {});

/// options.refinement applied to a search result: nothing (kNone), interpolate_match
/// (kInterpolate), interpolate_match then refine_match (kRayCast).
void apply_refinement(const FeatureDb& db, const FieldGeometry& field, const CameraModel& camera,
                      const FieldScan& scan, MatchResult& result, const MatchOptions& options);

/// Yaw from the scan itself: the heading within yaw_hint_deg +- range_deg whose field-frame
/// rotation of `bearings` best matches the expected scan at position_cm, searched in steps of
/// 1 / rays_per_degree, then below the step by an equiangular fit through the best step and its
/// two neighbours. `error` is the normalised error at the best step.
struct YawEstimate {
  double yaw_deg = 0.0;
  double error = kNoError;
};
[[nodiscard]] YawEstimate estimate_yaw(const FieldGeometry& field, const CameraModel& camera,
                                       const BearingScan& bearings,
                                       const Eigen::Vector2d& position_cm, double yaw_hint_deg,
                                       double range_deg, const MatchOptions& options = {});

/// Global search without a heading (no gyro, or after a kidnapping): every yaw from 0 to 360 in
/// yaw_step_deg steps is tried on `bearings` (rotate_to_field + global_search); the best (cell,
/// yaw) is refined with estimate_yaw and a local search at that yaw. The second candidate is the
/// best result at a position at least ambiguity_separation_cm away: on a point-symmetric field the
/// mirror pose (centre * 2 - p, yaw + 180) sees exactly the same lines, so such a match is flagged
/// ambiguous and the caller must decide with another cue (gyro, odometry, goal colour).
struct PoseMatch {
  MatchResult match;  // at yaw_deg; second_* and ambiguous refer to the second candidate below
  double yaw_deg = 0.0;
  double second_yaw_deg = 0.0;
};
[[nodiscard]] PoseMatch global_search_any_yaw(const FeatureDb& db, const FieldGeometry& field,
                                              const CameraModel& camera,
                                              const BearingScan& bearings,
                                              double yaw_step_deg = 2.0,
                                              const MatchOptions& options = {});

/// The whole image-to-pose step: scan the image at the given yaw, search (globally when
/// around_cm is null, else locally within range_cm), then options.refinement.
[[nodiscard]] MatchResult image_to_position(const cv::Mat& bgr, const CameraModel& camera,
                                            const FieldGeometry& field, const FeatureDb& db,
                                            double yaw_deg, const Eigen::Vector2d* around_cm,
                                            double range_cm, const MatchOptions& options = {},
                                            const ScanParams& scan_params = {});

}  // namespace omniloc
