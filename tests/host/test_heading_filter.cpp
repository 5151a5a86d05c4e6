// The alpha-beta image-heading filter against hand-worked sequences: prediction with the learnt
// rate only between recent fixes, the correction by `gain` of the residual, the rate learnt by
// `rate_gain` of residual / dt and clamped, residuals across the +-180 seam.
#include <gtest/gtest.h>

#include "omniloc/conventions.hpp"
#include "omniloc/heading_filter.hpp"

namespace omniloc {
namespace {

HeadingFilterConfig cfg(double gain, double rate_gain, double rate_max = 2.0) {
  HeadingFilterConfig c;
  c.gain = gain;
  c.rate_gain = rate_gain;
  c.rate_max_deg_per_s = rate_max;
  c.max_rate_gap_s = 1.0;
  return c;
}

TEST(HeadingFilter, FirstFixCorrectsByTheGainAndLearnsNoRate) {
  HeadingFilter f(cfg(0.05, 0.005));
  // No fix yet: the prediction is the gyro heading.
  EXPECT_DOUBLE_EQ(f.predict(1000.0, 30.0), 30.0);
  // Image says 32: residual 2, corrected 30 + 0.05 * 2 = 30.1; no earlier fix, so no rate.
  EXPECT_NEAR(f.correct(1000.0, 30.0, 32.0), 30.1, 1e-12);
  EXPECT_DOUBLE_EQ(f.rate_deg_per_s(), 0.0);
}

TEST(HeadingFilter, RateIsLearntFromRecentFixesAndUsedToPredict) {
  HeadingFilter f(cfg(0.5, 0.1));
  (void)f.correct(0.0, 10.0, 10.0);
  // 0.5 s later: prediction = gyro (rate 0); residual 1 -> rate 0.1 * 1 / 0.5 = 0.2 deg/s,
  // heading 20 + 0.5 * 1 = 20.5.
  EXPECT_DOUBLE_EQ(f.predict(500.0, 20.0), 20.0);
  EXPECT_NEAR(f.correct(500.0, 20.0, 21.0), 20.5, 1e-12);
  EXPECT_NEAR(f.rate_deg_per_s(), 0.2, 1e-12);
  // 0.25 s on: predicted 40 + 0.2 * 0.25 = 40.05.
  const double p = f.predict(750.0, 40.0);
  EXPECT_NEAR(p, 40.05, 1e-12);
  // A measurement equal to the prediction changes nothing.
  EXPECT_NEAR(f.correct(750.0, p, p), 40.05, 1e-12);
  EXPECT_NEAR(f.rate_deg_per_s(), 0.2, 1e-12);
  // More than max_rate_gap_s (1 s) after the last fix the rate is neither used nor learnt.
  EXPECT_DOUBLE_EQ(f.predict(1751.0, 40.0), 40.0);
  EXPECT_NEAR(f.correct(1751.0, 40.0, 44.0), 42.0, 1e-12);
  EXPECT_NEAR(f.rate_deg_per_s(), 0.2, 1e-12);
  // Exactly 1 s is still recent: predicted 40 + 0.2 = 40.2.
  EXPECT_NEAR(f.predict(2751.0, 40.0), 40.2, 1e-12);
}

TEST(HeadingFilter, RateIsClampedAndTheSeamIsCrossedTheShortWay) {
  HeadingFilter f(cfg(0.5, 0.9, 2.0));
  (void)f.correct(0.0, 0.0, 0.0);
  // Residual 10 over 0.1 s would make 90 deg/s: clamped to 2.
  (void)f.correct(100.0, 0.0, 10.0);
  EXPECT_DOUBLE_EQ(f.rate_deg_per_s(), 2.0);
  HeadingFilter g(cfg(0.5, 0.0));
  // Predicted 179, measured -179: the residual is +2 (not -358); corrected 180.
  EXPECT_NEAR(angle_diff_deg(g.correct(0.0, 179.0, -179.0), 180.0), 0.0, 1e-12);
  EXPECT_NEAR(g.correct(10.0, -179.0, 179.0), 180.0, 1e-12);  // -179 - 1 = -180, wrapped
}

}  // namespace
}  // namespace omniloc
