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

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>

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
      {30.0, {{0, 2.0 / 3}, {14.0 / 3, 2.0 / 3}, {19.0 / 3, 1.0 / 3}, {46.0 / 3, 1.0 / 3}, {17, 0}, {30, 0}}, 10.0},
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
  c.rules = {FuzzyTerm::kVeryHigh, FuzzyTerm::kVeryHigh, FuzzyTerm::kVeryHigh, FuzzyTerm::kVeryHigh};
  const FuzzyResult vh = fuzzy_search_range(c, 60.0);
  EXPECT_NEAR(vh.crisp_cm, exact_centroid({{0, 0}, {22, 0}, {27, 1}, {30, 1}}), 1e-3);
  EXPECT_EQ(vh.output_clip[3], 1.0);
  EXPECT_THROW((void)fuzzy_search_range(c, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
}

TEST(Fuzzy, SnapToRanges) {
  const std::vector<double> r{0, 10, 20, 30};
  EXPECT_EQ(snap_to_ranges(4.99, r), 0.0);
  EXPECT_EQ(snap_to_ranges(5.0, r), 10.0);  // ties go up: search wider when unsure
  EXPECT_EQ(snap_to_ranges(15.0 - 1e-12, r), 20.0);  // a tie up to rounding is still a tie
  EXPECT_EQ(snap_to_ranges(14.9, r), 10.0);
  EXPECT_EQ(snap_to_ranges(26.0, r), 30.0);
  EXPECT_EQ(snap_to_ranges(-3.0, r), 0.0);
  EXPECT_EQ(snap_to_ranges(99.0, r), 30.0);
}

cv::FileNode parse(cv::FileStorage& fs, const std::string& json) {
  fs.open(json, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_JSON);
  return fs.root();
}

const std::string kGood =
    R"({"speed_max_cm_per_s": 300,
        "speed_terms": {"VL": [0, 0, 20, 50], "L": [20, 50, 80, 120], "H": [80, 120, 150, 200], "VH": [150, 200, 300, 300]},
        "range_max_cm": 30,
        "range_terms": {"VL": [0, 0, 3, 8], "L": [3, 8, 12, 17], "H": [12, 17, 22, 27], "VH": [22, 27, 30, 30]},
        "rules": {"VL": "VL", "L": "L", "H": "H", "VH": "VH"},
        "resolution_cm": 0.01, "snap_ranges_cm": [0, 10, 20, 30]})";

std::string error_of(const std::string& json) {
  cv::FileStorage fs;
  try {
    (void)parse_fuzzy_config(parse(fs, json), "cfg.json: fuzzy");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

TEST(FuzzyConfig, ParsesTheDefaultsAndTheShippedFile) {
  cv::FileStorage fs;
  const FuzzyConfig c = parse_fuzzy_config(parse(fs, kGood), "x");
  const FuzzyConfig d = FuzzyConfig::defaults();
  for (int i = 0; i < kFuzzyTerms; ++i) {
    EXPECT_EQ(c.speed_terms[i].b, d.speed_terms[i].b);
    EXPECT_EQ(c.range_terms[i].d, d.range_terms[i].d);
    EXPECT_EQ(c.rules[i], d.rules[i]);
  }
  const LocalizerConfig lc = load_localizer_config("default");
  EXPECT_EQ(lc.e_th, 20.0);
  EXPECT_EQ(lc.reset_period_ms, 125.0);
  for (int i = 0; i < kFuzzyTerms; ++i) {
    EXPECT_EQ(lc.fuzzy.speed_terms[i].a, d.speed_terms[i].a);
    EXPECT_EQ(lc.fuzzy.speed_terms[i].c, d.speed_terms[i].c);
    EXPECT_EQ(lc.fuzzy.range_terms[i].b, d.range_terms[i].b);
  }
}

TEST(FuzzyConfig, ClearErrorsNameTheField) {
  EXPECT_EQ(error_of(kGood), "");
  auto expect_error = [](const std::string& json, const std::string& needle) {
    const std::string e = error_of(json);
    EXPECT_NE(e.find(needle), std::string::npos) << "got: " << e;
    EXPECT_NE(e.find("cfg.json: fuzzy"), std::string::npos) << "got: " << e;
  };
  expect_error(replaced(kGood, "\"L\": [20, 50, 80, 120]", "\"L\": [20, 90, 80, 120]"), "speed_terms.L");
  expect_error(replaced(kGood, "\"VH\": [150, 200, 300, 300]", "\"VH\": [150, 200, 300, 400]"), "speed_terms.VH");
  // A gap between L and H: speeds 121..129 would fire no rule.
  expect_error(replaced(kGood, "\"H\": [80, 120, 150, 200]", "\"H\": [130, 140, 150, 200]"), "uncovered");
  expect_error(replaced(kGood, "\"H\": \"H\"", "\"H\": \"XX\""), "rules.H");
  expect_error(replaced(kGood, "\"L\": [3, 8, 12, 17]", "\"L\": [3, 8, 12]"), "range_terms.L");
  expect_error(replaced(kGood, "\"resolution_cm\": 0.01", "\"resolution_cm\": 0"), "resolution_cm");
  expect_error(replaced(kGood, "[0, 10, 20, 30]", "[0, 20, 10, 30]"), "snap_ranges_cm");
  expect_error(replaced(kGood, "\"range_max_cm\": 30", "\"range_max_cm\": 30, \"speed_maximum\": 1"), "speed_maximum");
  expect_error(replaced(kGood, "\"range_max_cm\": 30,", ""), "range_max_cm");
}

std::string localizer_error_of(const std::string& extra) {
  cv::FileStorage fs;
  try {
    (void)parse_localizer_config(parse(fs, "{" + extra + "\"fuzzy\": " + kGood + "}"), "loc.json");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(LocalizerConfigFile, ShippedFileEnablesTheImageHeadingAndPaperModeDoesNot) {
  const LocalizerConfig lc = load_localizer_config("default");
  EXPECT_TRUE(lc.yaw_correction);
  EXPECT_EQ(lc.yaw_search_deg, 3.0);
  EXPECT_EQ(lc.yaw_gain, 0.05);
  EXPECT_EQ(lc.yaw_rate_gain, 0.005);
  EXPECT_FALSE(LocalizerConfig::paper().yaw_correction);
  EXPECT_EQ(localizer_error_of(""), "");
  cv::FileStorage fs;
  const LocalizerConfig p = parse_localizer_config(parse(fs, "{\"mode\": \"paper\", \"fuzzy\": " + kGood + "}"), "x");
  EXPECT_FALSE(p.yaw_correction);
  const LocalizerConfig q = parse_localizer_config(
      parse(fs, "{\"yaw_correction\": false, \"yaw_gain\": 0.5, \"fuzzy\": " + kGood + "}"), "x");
  EXPECT_FALSE(q.yaw_correction);
  EXPECT_EQ(q.yaw_gain, 0.5);
}

TEST(LocalizerConfigFile, ClearErrorsNameTheFileAndField) {
  auto expect_error = [](const std::string& extra, const std::string& field) {
    const std::string e = localizer_error_of(extra);
    EXPECT_NE(e.find("loc.json"), std::string::npos) << "got: " << e;
    EXPECT_NE(e.find("'" + field + "'"), std::string::npos) << "got: " << e;
  };
  expect_error("\"yaw_gain\": 0, ", "yaw_gain");
  expect_error("\"yaw_gain\": 1.5, ", "yaw_gain");
  expect_error("\"yaw_rate_gain\": 1, ", "yaw_rate_gain");
  expect_error("\"yaw_search_deg\": 45, ", "yaw_search_deg");
  expect_error("\"yaw_rate_max_deg_per_s\": -1, ", "yaw_rate_max_deg_per_s");
  expect_error("\"yaw_correction\": 2, ", "yaw_correction");
  expect_error("\"e_th\": -3, ", "e_th");
  expect_error("\"disagree_frames\": 0, ", "disagree_frames");
  expect_error("\"yaw_corection\": true, ", "yaw_corection");  // a typo is not silently ignored
}

}  // namespace
}  // namespace omniloc
