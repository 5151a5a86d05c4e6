// Fuzzy search-range system (paper 2.5) against hand-derived shapes: for each speed, the
// aggregated output set is written down by hand as a polyline (vertices worked out from the
// breakpoints in docs/LOCALIZER.md) and its centroid integrated exactly here, independently of
// the implementation's numerical integration.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "config_test_util.hpp"
#include "omniloc/detail/config_reader.hpp"
#include "omniloc/fuzzy.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/robot_config.hpp"

namespace omniloc {
namespace {

using Polyline = std::vector<std::pair<double, double>>;  // (x, mu), x increasing

/// Exact centroid of a piecewise-linear membership function.
double exact_centroid(const Polyline& p) {
  double area = 0.0, moment = 0.0;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    const auto [x0, y0] = p[i];
    const auto [x1, y1] = p[i + 1];
    const double w = x1 - x0;
    area += w * (y0 + y1) / 2.0;
    // integral of x * (y0 + (y1 - y0) (x - x0) / w) over [x0, x1]
    moment += w * (x0 * (2 * y0 + y1) + x1 * (y0 + 2 * y1)) / 6.0;
  }
  return moment / area;
}

TEST(Fuzzy, TrapezoidDegreesAtBreakpoints) {
  const FuzzyConfig c = FuzzyConfig::defaults();
  const Trapezoid vl = c.speed_terms[0], l = c.speed_terms[1], vh = c.speed_terms[3];
  EXPECT_DOUBLE_EQ(vl.degree(0.0), 1.0);  // left shoulder: 1 right at the universe's start
  EXPECT_DOUBLE_EQ(vl.degree(20.0), 1.0);
  EXPECT_DOUBLE_EQ(vl.degree(35.0), 0.5);
  EXPECT_DOUBLE_EQ(vl.degree(50.0), 0.0);
  EXPECT_DOUBLE_EQ(l.degree(20.0), 0.0);
  EXPECT_DOUBLE_EQ(l.degree(50.0), 1.0);
  EXPECT_DOUBLE_EQ(l.degree(100.0), 0.5);
  EXPECT_DOUBLE_EQ(l.degree(120.0), 0.0);
  EXPECT_DOUBLE_EQ(vh.degree(300.0), 1.0);  // right shoulder
  EXPECT_DOUBLE_EQ(vh.degree(175.0), 0.5);
  EXPECT_DOUBLE_EQ(vh.degree(-1.0), 0.0);
  const Trapezoid tri{0, 5, 5, 10};
  EXPECT_DOUBLE_EQ(tri.degree(5.0), 1.0);
  EXPECT_DOUBLE_EQ(tri.degree(2.5), 0.5);
}

struct Case {
  double speed;
  Polyline shape;  // aggregated output, by hand
  double snapped;
};

TEST(Fuzzy, CentroidsMatchHandDerivedShapes) {
  const FuzzyConfig c = FuzzyConfig::defaults();
  // Output terms: VL [0,0,3,8], L [3,8,12,17], H [12,17,22,27], VH [22,27,30,30].
  const std::vector<Case> cases = {
      // Only VL fires fully (v in the VL core): the VL set itself.
      {0.0, {{0, 1}, {3, 1}, {8, 0}, {30, 0}}, 0.0},
      {20.0, {{0, 1}, {3, 1}, {8, 0}, {30, 0}}, 0.0},
      // v = 30: VL 2/3, L 1/3. VL clipped at 2/3 until its slope reaches 2/3 at 8 - 10/3, falls
      // to 1/3 at 8 - 5/3 where the clipped L takes over until 17 - 5/3.
      {30.0,
       {{0, 2.0 / 3},
        {14.0 / 3, 2.0 / 3},
        {19.0 / 3, 1.0 / 3},
        {46.0 / 3, 1.0 / 3},
        {17, 0},
        {30, 0}},
       10.0},
      // v = 35: VL = L = 0.5: flat 0.5 from 0 to 14.5, down to 0 at 17.
      {35.0, {{0, 0.5}, {14.5, 0.5}, {17, 0}, {30, 0}}, 10.0},
      // L core: the L set, symmetric about 10.
      {60.0, {{0, 0}, {3, 0}, {8, 1}, {12, 1}, {17, 0}, {30, 0}}, 10.0},
      {80.0, {{0, 0}, {3, 0}, {8, 1}, {12, 1}, {17, 0}, {30, 0}}, 10.0},
      // v = 100: L = H = 0.5, symmetric about 15: centroid exactly 15, a tie -> snaps up to 20.
      {100.0, {{0, 0}, {3, 0}, {5.5, 0.5}, {24.5, 0.5}, {27, 0}, {30, 0}}, 20.0},
      {135.0, {{0, 0}, {12, 0}, {17, 1}, {22, 1}, {27, 0}, {30, 0}}, 20.0},
      // v = 175: H = VH = 0.5: up from 12 to 0.5 at 14.5, flat to 30.
      {175.0, {{0, 0}, {12, 0}, {14.5, 0.5}, {30, 0.5}}, 20.0},
      // VH only.
      {300.0, {{0, 0}, {22, 0}, {27, 1}, {30, 1}}, 30.0},
      // Clamped into the universe.
      {-5.0, {{0, 1}, {3, 1}, {8, 0}, {30, 0}}, 0.0},
      {1000.0, {{0, 0}, {22, 0}, {27, 1}, {30, 1}}, 30.0},
  };
  for (const Case& k : cases) {
    const FuzzyResult r = fuzzy_search_range(c, k.speed);
    const double expected = exact_centroid(k.shape);
    EXPECT_NEAR(r.crisp_cm, expected, 1e-3) << "speed " << k.speed;
    EXPECT_EQ(r.snapped_cm, k.snapped) << "speed " << k.speed << " crisp " << r.crisp_cm;
  }
  // Spot values of the hand integration itself (worked on paper): VL alone 16.1667 / 5.5.
  EXPECT_NEAR(exact_centroid(cases[0].shape), (4.5 + 35.0 / 3.0) / 5.5, 1e-12);
  EXPECT_NEAR(exact_centroid(cases[6].shape), 15.0, 1e-12);
}

TEST(Fuzzy, FiringStrengthsAndRules) {
  FuzzyConfig c = FuzzyConfig::defaults();
  const FuzzyResult r = fuzzy_search_range(c, 30.0);
  EXPECT_NEAR(r.speed_degrees[0], 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(r.speed_degrees[1], 1.0 / 3.0, 1e-12);
  EXPECT_EQ(r.speed_degrees[2], 0.0);
  EXPECT_EQ(r.speed_degrees[3], 0.0);
  // Rules from the config: map every speed term to VH -> the VH shape whatever the speed.
  c.rules = {FuzzyTerm::kVeryHigh, FuzzyTerm::kVeryHigh, FuzzyTerm::kVeryHigh,
             FuzzyTerm::kVeryHigh};
  const FuzzyResult vh = fuzzy_search_range(c, 60.0);
  EXPECT_NEAR(vh.crisp_cm, exact_centroid({{0, 0}, {22, 0}, {27, 1}, {30, 1}}), 1e-3);
  EXPECT_EQ(vh.output_clip[3], 1.0);
  EXPECT_THROW((void)fuzzy_search_range(c, std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
}

TEST(Fuzzy, SnapToRanges) {
  const std::vector<double> r{0, 10, 20, 30};
  EXPECT_EQ(snap_to_ranges(4.99, r), 0.0);
  EXPECT_EQ(snap_to_ranges(5.0, r), 10.0);           // ties go up: search wider when unsure
  EXPECT_EQ(snap_to_ranges(15.0 - 1e-12, r), 20.0);  // a tie up to rounding is still a tie
  EXPECT_EQ(snap_to_ranges(14.9, r), 10.0);
  EXPECT_EQ(snap_to_ranges(26.0, r), 30.0);
  EXPECT_EQ(snap_to_ranges(-3.0, r), 0.0);
  EXPECT_EQ(snap_to_ranges(99.0, r), 30.0);
}

// --- config files: the fuzzy block and the localizer file around it
// --------------------------------

using test::error_of;

const std::string kGood =
    R"({"speed_max_cm_per_s": 300,
        "speed_terms": {"VL": [0, 0, 20, 50], "L": [20, 50, 80, 120], "H": [80, 120, 150, 200], "VH": [150, 200, 300, 300]},
        "range_max_cm": 30,
        "range_terms": {"VL": [0, 0, 3, 8], "L": [3, 8, 12, 17], "H": [12, 17, 22, 27], "VH": [22, 27, 30, 30]},
        "rules": {"VL": "VL", "L": "L", "H": "H", "VH": "VH"},
        "resolution_cm": 0.01, "snap_ranges_cm": [0, 10, 20, 30]})";

FuzzyConfig parse_fuzzy(const std::string& json) {
  return parse_fuzzy_config(config::parse_json_text(json, "cfg.json").root());
}

std::string fuzzy_error_of(const std::string& json) {
  return error_of([&] { (void)parse_fuzzy(json); });
}

using test::replaced;

TEST(FuzzyConfig, TheInitialisersAreTheDocumentedDefaults) {
  const FuzzyConfig c = parse_fuzzy(kGood);
  EXPECT_TRUE(c == FuzzyConfig{});
  EXPECT_TRUE(FuzzyConfig::defaults() == FuzzyConfig{});
}

TEST(FuzzyConfig, EveryKeyReachesItsMember) {
  // Every value differs from the defaults; the expected values are written out by hand.
  const FuzzyConfig c = parse_fuzzy(R"({"speed_max_cm_per_s": 400,
      "speed_terms": {"VL": [0, 0, 25, 60], "L": [25, 60, 90, 130], "H": [90, 130, 160, 220], "VH": [160, 220, 400, 400]},
      "range_max_cm": 40,
      "range_terms": {"VL": [0, 0, 4, 9], "L": [4, 9, 13, 18], "H": [13, 18, 23, 28], "VH": [23, 28, 40, 40]},
      "rules": {"VL": "L", "L": "H", "H": "VH", "VH": "VL"},
      "resolution_cm": 0.02, "snap_ranges_cm": [0, 15, 40]})");
  EXPECT_EQ(c.speed_max_cm_per_s, 400.0);
  EXPECT_TRUE(c.speed_terms[0] == (Trapezoid{0, 0, 25, 60}));
  EXPECT_TRUE(c.speed_terms[1] == (Trapezoid{25, 60, 90, 130}));
  EXPECT_TRUE(c.speed_terms[2] == (Trapezoid{90, 130, 160, 220}));
  EXPECT_TRUE(c.speed_terms[3] == (Trapezoid{160, 220, 400, 400}));
  EXPECT_EQ(c.range_max_cm, 40.0);
  EXPECT_TRUE(c.range_terms[0] == (Trapezoid{0, 0, 4, 9}));
  EXPECT_TRUE(c.range_terms[1] == (Trapezoid{4, 9, 13, 18}));
  EXPECT_TRUE(c.range_terms[2] == (Trapezoid{13, 18, 23, 28}));
  EXPECT_TRUE(c.range_terms[3] == (Trapezoid{23, 28, 40, 40}));
  EXPECT_EQ(c.rules[0], FuzzyTerm::kLow);
  EXPECT_EQ(c.rules[1], FuzzyTerm::kHigh);
  EXPECT_EQ(c.rules[2], FuzzyTerm::kVeryHigh);
  EXPECT_EQ(c.rules[3], FuzzyTerm::kVeryLow);
  EXPECT_EQ(c.resolution_cm, 0.02);
  EXPECT_EQ(c.snap_ranges_cm, (std::vector<double>{0, 15, 40}));
}

TEST(FuzzyConfig, ClearErrorsNameTheFieldPath) {
  EXPECT_EQ(fuzzy_error_of(kGood), "(no error)");
  auto expect_error = [](const std::string& json, const std::string& path, const std::string& why) {
    const std::string e = fuzzy_error_of(json);
    EXPECT_EQ(e.rfind("cfg.json:" + path + ": ", 0), 0u)
        << "want cfg.json:" << path << " in: " << e;
    EXPECT_NE(e.find(why), std::string::npos) << "want '" << why << "' in: " << e;
  };
  expect_error(replaced(kGood, "\"L\": [20, 50, 80, 120]", "\"L\": [20, 90, 80, 120]"),
               "speed_terms.L", "a <= b <= c <= d (got [20, 90, 80, 120])");
  expect_error(replaced(kGood, "\"VH\": [150, 200, 300, 300]", "\"VH\": [150, 200, 300, 400]"),
               "speed_terms.VH", "must lie in [0, 300]");
  // A gap between L and H: speeds 121..129 would fire no rule.
  expect_error(replaced(kGood, "\"H\": [80, 120, 150, 200]", "\"H\": [130, 140, 150, 200]"),
               "speed_terms", "uncovered");
  expect_error(replaced(kGood, "\"H\": \"H\"", "\"H\": \"XX\""), "rules.H",
               "must be one of \"VL\", \"L\", \"H\", \"VH\"");
  expect_error(replaced(kGood, "\"H\": \"H\"", "\"HH\": \"H\""), "rules.HH", "unknown term");
  expect_error(replaced(kGood, "\"L\": [3, 8, 12, 17]", "\"L\": [3, 8, 12]"), "range_terms.L",
               "array of 4");
  expect_error(replaced(kGood, "\"L\": [3, 8, 12, 17]", "\"L\": [3, 8, true, 17]"),
               "range_terms.L[2]", "must be a number, not a boolean");
  expect_error(
      replaced(kGood, "\"L\": [3, 8, 12, 17]", "\"L\": [3, 8, 12, 17], \"L\": [3, 8, 12, 17]"),
      "range_terms.L", "duplicate key");
  expect_error(replaced(kGood, "\"resolution_cm\": 0.01", "\"resolution_cm\": 0"), "resolution_cm",
               "at most a tenth of range_max_cm (got 0)");
  expect_error(replaced(kGood, "[0, 10, 20, 30]", "[0, 20, 10, 30]"), "snap_ranges_cm[2]",
               "strictly increasing (after 20) (got 10)");
  expect_error(replaced(kGood, "[0, 10, 20, 30]", "[0, 10, NaN, 30]"), "snap_ranges_cm[2]",
               "not valid JSON");
  expect_error(replaced(kGood, "[0, 10, 20, 30]", "[0, 10, 1e400, 30]"), "snap_ranges_cm[2]",
               "number out of range: beyond a double (got 1e400)");
  expect_error(
      replaced(kGood, "\"range_max_cm\": 30", "\"range_max_cm\": 30, \"speed_maximum\": 1"),
      "speed_maximum", "unknown key");
  expect_error(replaced(kGood, "\"range_max_cm\": 30,", ""), "range_max_cm", "missing (required)");
}

// Issue (hostile input): resolution_cm sizes the centroid's loop (range_max_cm / resolution_cm
// midpoint steps on every frame), so it has a lower bound derived from that step count, not only
// "> 0": 1e-300 was undefined behaviour (the step count overflowed int) and 2e-8 made a 15-frame
// replay take over a minute.
TEST(FuzzyConfig, ResolutionIsBoundedByTheStepsItMakes) {
  struct Bad {
    std::string value;
    std::string why;
  };
  const std::vector<Bad> bad = {
      {"1e-300",
       "must be at least range_max_cm / 10000 = 0.003 cm: the centroid integrates range_max_cm / "
       "resolution_cm steps on every frame (got 1e-300)"},
      {"2e-8", "(got 2e-08)"},
      {"0.001", "the centroid integrates range_max_cm / resolution_cm steps on every frame"},
      {"0.0029", "(got 0.0029)"},
      {"-1", "must be > 0 and at most a tenth of range_max_cm (got -1)"},
      {"0", "must be > 0 and at most a tenth of range_max_cm (got 0)"},
      {"3.5", "at most a tenth of range_max_cm (got 3.5)"},
  };
  for (const Bad& b : bad) {
    const std::string e =
        fuzzy_error_of(replaced(kGood, "\"resolution_cm\": 0.01", "\"resolution_cm\": " + b.value));
    EXPECT_EQ(e.rfind("cfg.json:resolution_cm: ", 0), 0u) << b.value << ": " << e;
    EXPECT_NE(e.find(b.why), std::string::npos) << b.value << ": want '" << b.why << "' in: " << e;
  }
  // The bound itself, and the bound follows range_max_cm (a wider universe allows a coarser step).
  EXPECT_EQ(fuzzy_error_of(replaced(kGood, "\"resolution_cm\": 0.01", "\"resolution_cm\": 0.003")),
            "(no error)");
  FuzzyConfig c;
  c.resolution_cm = c.range_max_cm / kFuzzyMaxSteps;
  EXPECT_NO_THROW(c.validate("cfg.json"));
  EXPECT_NO_THROW((void)fuzzy_search_range(c, 100.0));
  c.resolution_cm = c.range_max_cm / kFuzzyMaxSteps * 0.99;
  EXPECT_THROW(c.validate("cfg.json"), ConfigError);
  // The other key that sizes a per-frame loop: the snap list (the terms and rules are four each,
  // the coverage check samples a fixed 1001 speeds).
  std::string many = "[0";
  for (int i = 1; i <= kFuzzyMaxSnapRanges; ++i) many += ", " + std::to_string(i * 10);
  many += "]";
  const std::string snap = fuzzy_error_of(replaced(kGood, "[0, 10, 20, 30]", many));
  EXPECT_EQ(snap.rfind("cfg.json:snap_ranges_cm: must list at most 64 ranges", 0), 0u) << snap;
  EXPECT_NE(snap.find("(got 65)"), std::string::npos) << snap;
  // Through the localizer file the path carries the block's name.
  const std::string e = error_of([] {
    (void)parse_localizer_config(
        config::parse_json_text(
            "{\"fuzzy\": " +
                replaced(kGood, "\"resolution_cm\": 0.01", "\"resolution_cm\": 1e-300") + "}",
            "loc.json")
            .root());
  });
  EXPECT_EQ(e.rfind("loc.json:fuzzy.resolution_cm: must be at least", 0), 0u) << e;
}

// --- the localizer file
// ---------------------------------------------------------------------------

// Every key of LocalizerConfig, by hand, in the shipped file's order.
const std::vector<std::string> kEveryLocalizerKey = {"mode",
                                                     "match_cost",
                                                     "crossing_cap_px",
                                                     "e_th",
                                                     "ambiguity_ratio",
                                                     "reset_period_ms",
                                                     "history_ms",
                                                     "scan_rays_per_degree",
                                                     "refinement",
                                                     "min_range_cm",
                                                     "refuse_ambiguous",
                                                     "image_sigma_cm",
                                                     "image_sigma_yaw_deg",
                                                     "lost_after_bad_frames",
                                                     "check_period_ms",
                                                     "disagree_min_cm",
                                                     "disagree_sigmas",
                                                     "disagree_error_ratio",
                                                     "disagree_frames",
                                                     "cross_check_worker",
                                                     "gyro_yaw_known",
                                                     "yaw_correction",
                                                     "yaw_search_deg",
                                                     "yaw_gain",
                                                     "yaw_rate_gain",
                                                     "yaw_rate_max_deg_per_s",
                                                     "fuzzy"};
const std::vector<std::string> kEveryFuzzyKey = {
    "speed_max_cm_per_s", "speed_terms",   "range_max_cm", "range_terms", "rules",
    "resolution_cm",      "snap_ranges_cm"};

LocalizerConfig parse_localizer(const std::string& json) {
  return parse_localizer_config(config::parse_json_text(json, "loc.json").root());
}

std::string localizer_error_of(const std::string& extra) {
  return error_of([&] { (void)parse_localizer("{" + extra + "\"fuzzy\": " + kGood + "}"); });
}

TEST(LocalizerConfigFile, ShippedFileIsTheStructDefaultsEveryKey) {
  const auto path = resolve_data_file("localizer", "default");
  const auto json = test::read_json(path);
  EXPECT_EQ(test::keys_of(json), kEveryLocalizerKey);
  EXPECT_EQ(test::keys_of(json["fuzzy"]), kEveryFuzzyKey);
  const LocalizerConfig lc = load_localizer_config("default");
  EXPECT_TRUE(lc == LocalizerConfig{});
  EXPECT_TRUE(lc.fuzzy == FuzzyConfig{});
  // Spot values as documented in docs/LOCALIZER.md.
  EXPECT_EQ(lc.match_cost, MatchCost::kBounded);
  EXPECT_EQ(lc.crossing_cap_px, 16);
  EXPECT_EQ(lc.e_th, 8.0);
  EXPECT_EQ(lc.ambiguity_ratio, 1.25);
  EXPECT_EQ(LocalizerConfig::paper().match_cost, MatchCost::kPaperSad);
  EXPECT_EQ(LocalizerConfig::paper().e_th, 20.0);
  EXPECT_EQ(lc.reset_period_ms, 125.0);
  EXPECT_TRUE(lc.yaw_correction);
  EXPECT_FALSE(LocalizerConfig::paper().yaw_correction);
}

TEST(LocalizerConfigFile, EveryKeyReachesItsMember) {
  const LocalizerConfig c = parse_localizer(R"({
    "mode": "full", "match_cost": "bounded", "crossing_cap_px": 20, "e_th": 15, "ambiguity_ratio": 1.5,
    "reset_period_ms": 150, "history_ms": 800, "scan_rays_per_degree": 2,
    "refinement": "interpolate", "min_range_cm": 5, "refuse_ambiguous": false, "image_sigma_cm": 3.5,
    "image_sigma_yaw_deg": 0.75, "lost_after_bad_frames": 20, "check_period_ms": 200, "disagree_min_cm": 40,
    "disagree_sigmas": 3, "disagree_error_ratio": 0.6, "disagree_frames": 5, "gyro_yaw_known": false,
    "yaw_correction": false, "yaw_search_deg": 4, "yaw_gain": 0.1, "yaw_rate_gain": 0.01,
    "yaw_rate_max_deg_per_s": 1.5,
    "fuzzy": )" + replaced(kGood, "\"resolution_cm\": 0.01", "\"resolution_cm\": 0.05") +
                                            "}");
  EXPECT_EQ(c.mode, LocalizerMode::kFull);
  EXPECT_EQ(c.match_cost, MatchCost::kBounded);
  EXPECT_EQ(c.crossing_cap_px, 20);
  EXPECT_EQ(c.e_th, 15.0);
  EXPECT_EQ(c.ambiguity_ratio, 1.5);
  EXPECT_EQ(c.reset_period_ms, 150.0);
  EXPECT_EQ(c.history_ms, 800.0);
  EXPECT_EQ(c.scan_rays_per_degree, 2);
  EXPECT_EQ(c.refinement, Refinement::kInterpolate);
  EXPECT_EQ(c.min_range_cm, 5.0);
  EXPECT_FALSE(c.refuse_ambiguous);
  EXPECT_EQ(c.image_sigma_cm, 3.5);
  EXPECT_EQ(c.image_sigma_yaw_deg, 0.75);
  EXPECT_EQ(c.lost_after_bad_frames, 20);
  EXPECT_EQ(c.check_period_ms, 200.0);
  EXPECT_EQ(c.disagree_min_cm, 40.0);
  EXPECT_EQ(c.disagree_sigmas, 3.0);
  EXPECT_EQ(c.disagree_error_ratio, 0.6);
  EXPECT_EQ(c.disagree_frames, 5);
  EXPECT_FALSE(c.gyro_yaw_known);
  EXPECT_FALSE(c.yaw_correction);
  EXPECT_EQ(c.yaw_search_deg, 4.0);
  EXPECT_EQ(c.yaw_gain, 0.1);
  EXPECT_EQ(c.yaw_rate_gain, 0.01);
  EXPECT_EQ(c.yaw_rate_max_deg_per_s, 1.5);
  EXPECT_EQ(c.fuzzy.resolution_cm, 0.05);
  // "mode": "paper" starts from LocalizerConfig::paper(); the other keys still override it.
  const LocalizerConfig p = parse_localizer("{\"mode\": \"paper\", \"fuzzy\": " + kGood + "}");
  EXPECT_TRUE(p == LocalizerConfig::paper());
  EXPECT_EQ(p.mode, LocalizerMode::kPaper);
  EXPECT_EQ(p.refinement, Refinement::kNone);
  const LocalizerConfig q = parse_localizer(
      "{\"mode\": \"paper\", \"refinement\": \"raycast\", \"fuzzy\": " + kGood + "}");
  EXPECT_EQ(q.mode, LocalizerMode::kPaper);
  EXPECT_EQ(q.refinement, Refinement::kRayCast);
}

TEST(LocalizerConfigFile, EachKeyOfTheShippedFileMattersWhenChanged) {
  // Changing one key of the shipped file at a time changes the struct in that key's member only:
  // the table maps each key to its own member (a swapped or missing entry fails here).
  const auto shipped = test::read_json(resolve_data_file("localizer", "default"));
  const LocalizerConfig base = parse_localizer(shipped.dump());
  for (const std::string& k : kEveryLocalizerKey) {
    if (k == "fuzzy") continue;
    auto changed = shipped;
    auto& v = changed[k];
    if (v.is_boolean())
      v = !v.get<bool>();
    else if (v.is_number_integer())
      v = v.get<int>() + 1;
    else if (v.is_number())
      v = v.get<double>() * 0.9;
    else if (k == "mode")
      v = "paper";
    else if (k == "refinement")
      v = "interpolate";
    else if (k == "match_cost")
      v = "paper_sad";
    const LocalizerConfig c = parse_localizer(changed.dump());
    EXPECT_FALSE(c == base) << k << " made no difference";
  }
}

TEST(LocalizerConfigFile, ClearErrorsNameTheFileAndField) {
  EXPECT_EQ(localizer_error_of(""), "(no error)");
  auto expect_error = [](const std::string& extra, const std::string& path,
                         const std::string& why) {
    const std::string e = localizer_error_of(extra);
    EXPECT_EQ(e.rfind("loc.json:" + path + ": ", 0), 0u) << "got: " << e;
    EXPECT_NE(e.find(why), std::string::npos) << "want '" << why << "' in: " << e;
  };
  expect_error("\"yaw_gain\": 0, ", "yaw_gain", "must be in (0, 1] (got 0)");
  expect_error("\"yaw_gain\": 1.5, ", "yaw_gain", "(got 1.5)");
  // Upper bounds (issue 16 item 6): the history is kept in memory, periods are not 1e-300 ms.
  expect_error("\"history_ms\": 1e12, ", "history_ms", "must be at most 60000 ms");
  expect_error("\"reset_period_ms\": 1e-300, ", "reset_period_ms",
               "must be at least 1 ms (got 1e-300)");
  expect_error("\"min_range_cm\": 1e9, ", "min_range_cm",
               "must be at most 10000 cm (got 1000000000)");
  expect_error("\"image_sigma_yaw_deg\": 1000, ", "image_sigma_yaw_deg",
               "must be at most 180 degrees");
  expect_error("\"yaw_rate_gain\": 1, ", "yaw_rate_gain", "[0, 1)");
  expect_error("\"yaw_search_deg\": 45, ", "yaw_search_deg", "(0, 30]");
  expect_error("\"yaw_rate_max_deg_per_s\": -1, ", "yaw_rate_max_deg_per_s", ">= 0 (got -1)");
  expect_error("\"yaw_correction\": 2, ", "yaw_correction",
               "must be true or false, not a number (got 2)");
  expect_error("\"yaw_correction\": 1, ", "yaw_correction", "must be true or false");
  expect_error("\"e_th\": -3, ", "e_th", "positive");
  expect_error("\"e_th\": \"20\", ", "e_th", "must be a number, not a string");
  expect_error("\"e_th\": NaN, ", "e_th", "not valid JSON");
  expect_error("\"e_th\": 1e400, ", "e_th", "number out of range");
  expect_error("\"e_th\": 20, \"e_th\": 21, ", "e_th", "duplicate key");
  expect_error("\"crossing_cap_px\": 0, ", "crossing_cap_px", "must be 1..127 px");
  expect_error("\"crossing_cap_px\": 128, ", "crossing_cap_px", "(got 128)");
  expect_error("\"e_th\": 17, ", "e_th", "must not exceed crossing_cap_px");
  expect_error("\"match_cost\": \"sad\", ", "match_cost",
               "must be one of \"bounded\", \"paper_sad\" (got \"sad\")");
  expect_error("\"ambiguity_ratio\": 0.9, ", "ambiguity_ratio", ">= 1 (got 0.9)");
  expect_error("\"disagree_frames\": 0, ", "disagree_frames", ">= 1 (got 0)");
  expect_error("\"disagree_frames\": 2.5, ", "disagree_frames", "must be an integer");
  expect_error("\"mode\": \"fast\", ", "mode", "must be one of \"full\", \"paper\" (got \"fast\")");
  expect_error("\"refinement\": 1, ", "refinement", "must be a string");
  expect_error("\"yaw_corection\": true, ", "yaw_corection",
               "unknown key");  // a typo is not silently ignored
  EXPECT_EQ(error_of([] { (void)parse_localizer("{}"); }), "loc.json:fuzzy: missing (required)");
  // The fuzzy block's errors carry the path through the localizer file.
  const std::string e = error_of([] {
    (void)parse_localizer("{\"fuzzy\": " + replaced(kGood, "[0, 10, 20, 30]", "[0, 10, -20, 30]") +
                          "}");
  });
  EXPECT_EQ(e, "loc.json:fuzzy.snap_ranges_cm[2]: ranges must be finite and >= 0 (got -20)");
}

TEST(LocalizerConfigFile, MissingFileAndDirectoryAreNamed) {
  EXPECT_EQ(error_of([] { (void)load_localizer_config("/nonexistent/loc.json"); }),
            "/nonexistent/loc.json: no such file");
  const std::string dir = test::temp_dir().string();
  EXPECT_EQ(error_of([&] { (void)load_localizer_config(dir); }),
            dir + ": is a directory, not a JSON file");
}

}  // namespace
}  // namespace omniloc
