// Fuzzy choice of the local search range (paper section 2.5, Figs. 12-13): the robot's speed is
// fuzzified into four terms (very low, low, high, very high), four rules map each speed term to a
// search-range term, Mamdani min-max inference clips and unites the output sets, and the centroid
// of the union (numerical integration over the output universe) is the crisp range, which is then
// snapped to the nearest range the database search offers ({0, 10, 20, 30} cm).
//
// The paper prints the shapes but no numbers; the breakpoints live in the config file
// (common/localizer/default.json) and are explained in docs/LOCALIZER.md.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "omniloc/config.hpp"

namespace omniloc {

/// The four linguistic terms, in this order everywhere (config arrays, rules, firing strengths).
enum class FuzzyTerm { kVeryLow = 0, kLow = 1, kHigh = 2, kVeryHigh = 3 };
inline constexpr int kFuzzyTerms = 4;

/// Trapezoidal membership a <= b <= c <= d: 0 outside [a, d], 1 on [b, c], linear between.
/// b == c gives a triangle; a == b (or c == d) a vertical edge, i.e. a shoulder at the universe's
/// end where the degree is 1 right at a (or d).
struct Trapezoid {
  double a = 0.0;
  double b = 0.0;
  double c = 0.0;
  double d = 0.0;
  [[nodiscard]] double degree(double x) const;
  bool operator==(const Trapezoid&) const = default;
};

/// The most midpoint steps the centroid may take over [0, range_max_cm]: resolution_cm must be at
/// least range_max_cm / kFuzzyMaxSteps. The integration runs on every frame (up to ~60 a second
/// beside the search); 10000 steps (~0.1 ms) is over three times the shipped 3000 and far finer
/// than the 10 cm snap ranges need. Without it a resolution of 2e-8 cm made 1.5e9 steps a frame.
inline constexpr int kFuzzyMaxSteps = 10000;
/// The most ranges snap_ranges_cm may list (the shipped list has 4; it is walked on every frame).
inline constexpr int kFuzzyMaxSnapRanges = 64;

/// The member initialisers are the shipped defaults: a test checks they equal every key of the
/// "fuzzy" block of common/localizer/default.json.
struct FuzzyConfig {
  /// Input universe: robot speed over ground (cm/s). Inputs are clamped into it.
  double speed_max_cm_per_s = 300.0;
  /// VL, L, H, VH (Fig. 12). The robot's top speed is ~300 cm/s; most play happens below 150 cm/s.
  std::array<Trapezoid, kFuzzyTerms> speed_terms{
      Trapezoid{0, 0, 20, 50}, Trapezoid{20, 50, 80, 120}, Trapezoid{80, 120, 150, 200},
      Trapezoid{150, 200, 300, 300}};
  /// Output universe: search range A (cm), [0, range_max_cm].
  double range_max_cm = 30.0;
  /// VL, L, H, VH (Fig. 13): each term's core sits on (or against) one database range 0/10/20/30.
  std::array<Trapezoid, kFuzzyTerms> range_terms{Trapezoid{0, 0, 3, 8}, Trapezoid{3, 8, 12, 17},
                                                 Trapezoid{12, 17, 22, 27},
                                                 Trapezoid{22, 27, 30, 30}};
  /// rules[i] = output term for input term i; the paper's four rules are the identity
  /// (speed very low -> range very low, ..., very high -> very high).
  std::array<FuzzyTerm, kFuzzyTerms> rules{FuzzyTerm::kVeryLow, FuzzyTerm::kLow, FuzzyTerm::kHigh,
                                           FuzzyTerm::kVeryHigh};
  /// Integration step of the centroid (midpoint rule over [0, range_max_cm]); validation keeps it
  /// in [range_max_cm / kFuzzyMaxSteps, range_max_cm / 10].
  double resolution_cm = 0.01;
  /// Ranges the database search offers; the crisp output snaps to the nearest (ties go up).
  std::vector<double> snap_ranges_cm{0.0, 10.0, 20.0, 30.0};

  /// FuzzyConfig{}: the defaults documented in docs/LOCALIZER.md.
  [[nodiscard]] static FuzzyConfig defaults();

  /// Throws ConfigError "<at>.<field>: <why> (got <value>)": unordered or non-finite breakpoints,
  /// terms outside their universe, input terms that leave a speed uncovered, rule indices out of
  /// range, a too coarse, too fine (more than kFuzzyMaxSteps steps) or non-positive resolution,
  /// empty, unsorted or more than kFuzzyMaxSnapRanges snap ranges.
  void validate(const config::Origin& at) const;
  bool operator==(const FuzzyConfig&) const = default;
};

struct FuzzyResult {
  std::array<double, kFuzzyTerms> speed_degrees{};  ///< membership of the input in VL, L, H, VH
  std::array<double, kFuzzyTerms>
      output_clip{};        ///< clip level of each output term (max over rules)
  double crisp_cm = 0.0;    ///< centroid of the aggregated output
  double snapped_cm = 0.0;  ///< nearest of snap_ranges_cm
};

/// Mamdani min-max inference + centroid. A speed below 0 or above the universe is clamped; NaN
/// throws std::invalid_argument. If no rule fires (a gap in the input terms) the range is the
/// largest snap range (search widely when unsure).
[[nodiscard]] FuzzyResult fuzzy_search_range(const FuzzyConfig& config, double speed_cm_per_s);

/// Nearest of `ranges_cm` (ties, within 1e-9 cm, go to the larger).
[[nodiscard]] double snap_to_ranges(double value_cm, const std::vector<double>& ranges_cm);

/// Reads {"speed_max_cm_per_s", "speed_terms": {"VL": [a,b,c,d], "L": ..., "H": ..., "VH": ...},
/// "range_max_cm", "range_terms": {...}, "rules": {"VL": "VL", ...}, "resolution_cm",
/// "snap_ranges_cm": [...]} (every key required) from a parsed JSON node and validates it; errors
/// name the node's origin ("loc.json:fuzzy.speed_terms.L[1]").
[[nodiscard]] FuzzyConfig parse_fuzzy_config(const config::Node& node);

/// The key table (config_reader.hpp) of the fuzzy block.
[[nodiscard]] const std::vector<config::Key<FuzzyConfig>>& fuzzy_config_keys();

/// "VL", "L", "H", "VH".
[[nodiscard]] const char* fuzzy_term_name(FuzzyTerm term);

}  // namespace omniloc
