// Generality of the camera front end on sampled venues (issue [1/4] item 4, the short version of
// `bench_venues`): 30 venues of a fixed seed list through calibrate (known spot, heading unknown)
// and locate (a second frame at a random pose), judged against the venues' true cameras and poses.
// The floors are what the front end reaches today (the goal, 28 calibrated and 27 located, is
// bench_venues's to measure): a change that loses a venue fails here. Seeds that failed once
// and were mended join kRegressions.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "short_mode.hpp"
#include "venue_trial.hpp"

namespace omniloc {
namespace {

constexpr std::uint64_t kSeed = 2026;
constexpr int kVenues = 30;
// What the front end reached on these venues when the floors were set (docs/CALIBRATION.md,
// "Generality"): raise them as it improves, never lower them.
// 11: two of the 13 counted before the self-check refused (step 8) were wrong cameras within the
// rms and centre goal (venues 18273785850258396930 and 2539317775091407530, mapping 157 % and 181 %
// off the truth): refusing them is what the issue asks; they are the test below.
constexpr int kMinCalibrated = 11;
constexpr int kMinLocated = 1;
// Accepted more than 20 cm off (the goal is 0): venue 11331608226358829653 (18 x 12 m, centre
// spot; its calibrated camera locates the second frame 575 cm off and the localizer accepts it).
// Lower it as the front end improves, never raise it.
constexpr int kMaxWild = 1;

// In the short mode (short_mode.hpp) the first 10 venues: the wild bound holds for them as it holds
// for all 30; the floors are what the front end reaches on those 10 today (Release, 2026-12-07:
// 2 calibrated within the goal, 1 located; raise them with the full floors, never lower them).
constexpr int kShortVenues = 10;
constexpr int kMinCalibratedShort = 2;
constexpr int kMinLocatedShort = 1;
TEST(VenueGenerality, ThirtySampledVenuesCalibrateAndLocate) {
  std::printf("venues %d of seed %llu (bench_venues: VENUES_COUNT=%d VENUES_SEED=%llu)\n", kVenues,
              static_cast<unsigned long long>(kSeed), kVenues,
              static_cast<unsigned long long>(kSeed));
  const int n = test::full_or_short(kVenues, kShortVenues, "venues");
  int calib_good = 0, located = 0, wild = 0, reference = 0;
  for (int i = 0; i < n; ++i) {
    const test::VenueOutcome o =
        test::run_venue(sim::venue_seed(kSeed, static_cast<std::uint64_t>(i)));
    test::print_outcome(o);
    calib_good += o.calib_good;
    located += o.located_good();
    wild += o.wild();
    reference += o.reference_good();
  }
  std::printf(
      "calibrated within the goal %d of %d, located %d of %d, accepted more than 20 cm off %d; "
      "with the true cameras located %d\n",
      calib_good, n, located, n, wild, reference);
  EXPECT_GE(calib_good, n == kVenues ? kMinCalibrated : kMinCalibratedShort);
  EXPECT_GE(located, n == kVenues ? kMinLocated : kMinLocatedShort);
  EXPECT_LE(wild, kMaxWild);
}

// Cameras that fit their frame's line pixels but are wrong: calibrate's self-check refuses them,
// naming itself (venues 18273785850258396930 and 2539317775091407530: 29 % and 38 % of the fitted
// camera's line points seen as lines, at least 40 % asked). Judged against the sampler's true
// cameras (measured with the check off: docs/CALIBRATION.md, step 8). Venue 17316000990051603176,
// whose low-contrast rim is found wrong, was the third the self-check refused (its rim then a
// 370 px circle, the centre 186 px off); since the rim must enclose the best-supported circle its
// rim is 47 px off and the carpet step refuses it first: no camera is written either way.
TEST(VenueGenerality, SelfCheckRefusesWrongCamerasThatFitTheirPixels) {
  for (const std::uint64_t seed : {18273785850258396930ull, 2539317775091407530ull}) {
    const test::VenueOutcome o = test::run_venue(seed);
    test::print_outcome(o);
    EXPECT_FALSE(o.calibrated) << seed;
    EXPECT_EQ(o.calib_step, "self-check") << seed << ": " << o.calib_error;
  }
  const test::VenueOutcome o = test::run_venue(17316000990051603176ull);
  test::print_outcome(o);
  EXPECT_FALSE(o.calibrated) << o.calib_step << ": " << o.calib_error;
}

}  // namespace
}  // namespace omniloc
