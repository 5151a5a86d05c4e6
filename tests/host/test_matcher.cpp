// Matcher: the fast SAD and the bounded cost against their scalar references, the normalised
// errors by hand, E_TH and the ambiguity ratio against rendered frames, global search
// against its reference, local-search windows, the right cell on noise-free images at every grid
// point, refinement below the grid, yaw from the scan, and the ambiguity report.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <random>

#include "omniloc/detail/vision_reference.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/matcher.hpp"
#include "omniloc_sim/renderer.hpp"
#include "short_mode.hpp"

namespace omniloc {
namespace {

class Matcher : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    renderer_ =
        std::make_unique<sim::OmniRenderer>(load_field("fira-robosot"), load_camera("default"));
    db_ = std::make_unique<FeatureDb>(build_feature_db(
        renderer_->field(), renderer_->camera(), GridSpec::covering(renderer_->field(), 10.0)));
  }
  static void TearDownTestSuite() {
    renderer_.reset();
    db_.reset();
  }
  static Scan db_scan(int cell) {
    Scan s;
    std::copy_n(db_->cell_features(cell), kFeatureBytes, s.radii_px.begin());
    s.ray_end_px.fill(kRayToViewEnd);
    return s;
  }
  // Renders a noise-free image at every grid point with the given parities and checks that the
  // global search returns that point. In the short mode (short_mode.hpp) every fourth such row.
  static void every_grid_point(int parity_i, int parity_j) {
    const GridSpec& g = db_->grid;
    const int rows = (g.ny - parity_j + 1) / 2;
    const int n_rows = test::full_or_short(rows, (rows + 3) / 4, "grid rows");
    const int row_step = (rows + n_rows - 1) / n_rows;
    int checked = 0, wrong = 0;
    for (int j = parity_j; j < g.ny; j += 2 * row_step) {
      for (int i = parity_i; i < g.nx; i += 2) {
        const Eigen::Vector2d p = g.position(i, j);
        const double yaw = static_cast<double>((i * 37 + j * 101) % 360) - 180.0;
        const Scan s = scan_image(renderer_->render({p.x(), p.y(), yaw}, sim::noise_free()),
                                  renderer_->camera(), yaw);
        const MatchResult m = global_search(*db_, s);
        ++checked;
        if (m.cell != j * g.nx + i) {
          ++wrong;
          ADD_FAILURE() << "grid point (" << p.x() << ", " << p.y() << ") yaw " << yaw
                        << " matched (" << m.grid_position_cm.x() << ", " << m.grid_position_cm.y()
                        << ")";
        }
      }
    }
    std::printf("%d grid points checked, %d wrong\n", checked, wrong);
  }
  // The field-frame scan of a noisy render at the truth's heading with `robots` other robots.
  static FieldScan noisy_field_scan(const Pose2& truth, std::uint64_t seed, int robots) {
    sim::RenderOptions opt;
    opt.seed = seed;
    opt.obstacles = sim::random_obstacles(renderer_->field(), truth, robots, seed);
    return make_field_scan(
        scan_image(renderer_->render(truth, opt), renderer_->camera(), truth.yaw_deg));
  }
  static std::unique_ptr<sim::OmniRenderer> renderer_;
  static std::unique_ptr<FeatureDb> db_;
};
std::unique_ptr<sim::OmniRenderer> Matcher::renderer_;
std::unique_ptr<FeatureDb> Matcher::db_;

TEST_F(Matcher, FastSadEqualsScalarReference) {
  const std::uint64_t seed = 4242;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255), cell(0, db_->grid.cells() - 1), coin(0, 3);
  for (int trial = 0; trial < 500; ++trial) {
    Scan s;
    for (auto& v : s.radii_px) v = static_cast<std::uint8_t>(byte(rng));
    for (auto& v : s.ray_end_px)
      v = coin(rng) == 0 ? kRayHidden : static_cast<std::uint8_t>(byte(rng));
    const int c = cell(rng);
    ASSERT_EQ(sad_fast(db_->cell_features(c), prepare_scan(s)),
              sad_reference(db_->cell_features(c), s))
        << trial;
  }
  // Worst case: every byte differs by 255.
  Scan zeros;
  zeros.ray_end_px.fill(kRayToViewEnd);
  std::vector<std::uint8_t> full(kFeatureBytes, 255);
  EXPECT_EQ(sad_fast(full.data(), prepare_scan(zeros)), 255u * 1440u);
  EXPECT_EQ(sad_reference(full.data(), zeros), 255u * 1440u);
}

// The bounded cost's three kernels agree bit for bit, on random bytes (kNoCrossing often) and
// random ray ends, at every cap the config allows.
TEST_F(Matcher, BoundedCostKernelsEqualTheScalarReference) {
  const std::uint64_t seed = 4343;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255), cell(0, db_->grid.cells() - 1), coin(0, 3),
      cap(1, 127);
  for (int trial = 0; trial < 500; ++trial) {
    Scan s;
    for (auto& v : s.radii_px)
      v = coin(rng) == 0 ? kNoCrossing : static_cast<std::uint8_t>(byte(rng));
    for (auto& v : s.ray_end_px)
      v = coin(rng) == 0 ? kRayHidden : static_cast<std::uint8_t>(byte(rng));
    const std::uint8_t* entry = db_->cell_features(cell(rng));
    const int c = trial < 2 ? (trial == 0 ? 1 : 127) : cap(rng);
    const CostTerms ref = bounded_cost_reference(entry, s, c);
    const PreparedScan p = prepare_scan(s);
    ASSERT_EQ(bounded_cost_portable(entry, p, c), ref) << trial;
    ASSERT_EQ(bounded_cost_fast(entry, p, c), ref) << trial;
  }
  // Worst case: every slot of the entry is a crossing and the scan has none: each costs the cap.
  Scan none;
  none.radii_px.fill(kNoCrossing);
  none.ray_end_px.fill(kRayToViewEnd);
  const std::vector<std::uint8_t> all(kFeatureBytes, 100);
  EXPECT_EQ(bounded_cost_fast(all.data(), prepare_scan(none), 127),
            (CostTerms{127u * 1440u, 1440u}));
  EXPECT_EQ(bounded_cost_reference(all.data(), none, 127), (CostTerms{127u * 1440u, 1440u}));
}

// The bounded cost by hand on one ray: each crossing against the nearest on the other side of
// the ray, capped; a crossing with no counterpart costs the cap, wherever it lies on the ray.
TEST(MatcherBoundedCost, NearestCrossingCappedAndNormalisedByTheCrossingsCompared) {
  std::vector<std::uint8_t> db(kFeatureBytes, kNoCrossing);
  Scan s;
  s.radii_px.fill(kNoCrossing);
  s.ray_end_px.fill(kRayHidden);
  s.ray_end_px[3] = kRayToViewEnd;
  const std::uint8_t entry[] = {40, 90, 150, kNoCrossing};
  std::copy_n(entry, 4, db.begin() + 4 * 3);
  // Seen: 42 and 150 match (2 px, 0 px), a spurious 60 comes first, 90 was not seen.
  const std::uint8_t seen[] = {42, 60, 150, kNoCrossing};
  std::copy_n(seen, 4, s.radii_px.begin() + 4 * 3);
  const int cap = 16;
  // Database side: 40 -> 2, 90 -> min(|90 - 60|, 16) = 16, 150 -> 0. Scan side: 42 -> 2,
  // 60 -> min(|60 - 40|, 16) = 16, 150 -> 0. Six crossings.
  EXPECT_EQ(bounded_cost_reference(db.data(), s, cap), (CostTerms{36u, 6u}));
  EXPECT_EQ(bounded_cost_fast(db.data(), prepare_scan(s), cap), (CostTerms{36u, 6u}));
  MatchOptions mo;
  mo.crossing_cap_px = cap;
  EXPECT_DOUBLE_EQ(match_error(db.data(), prepare_scan(s), mo), 6.0);
  // The paper's slot-by-slot SAD: |40-42| + |90-60| + |150-150| + 0 = 32 over one ray.
  mo.cost = MatchCost::kPaperSad;
  EXPECT_DOUBLE_EQ(match_error(db.data(), prepare_scan(s), mo), 32.0);
  mo.cost = MatchCost::kBounded;
  // An obstacle at 100 ends the ray: 150 on both sides is unknown, 90 still unseen.
  s.ray_end_px[3] = 100;
  EXPECT_EQ(bounded_cost_reference(db.data(), s, cap), (CostTerms{36u, 4u}));
  EXPECT_EQ(bounded_cost_fast(db.data(), prepare_scan(s), cap), (CostTerms{36u, 4u}));
  // Near the end of the radius range a missing crossing still costs the full cap.
  s.ray_end_px[3] = kRayToViewEnd;
  const std::uint8_t far_entry[] = {250, kNoCrossing, kNoCrossing, kNoCrossing};
  const std::uint8_t far_seen[] = {kNoCrossing, kNoCrossing, kNoCrossing, kNoCrossing};
  std::copy_n(far_entry, 4, db.begin() + 4 * 3);
  std::copy_n(far_seen, 4, s.radii_px.begin() + 4 * 3);
  EXPECT_EQ(bounded_cost_fast(db.data(), prepare_scan(s), cap), (CostTerms{16u, 1u}));
  // Nothing on either side: nothing to compare.
  std::fill_n(db.begin() + 4 * 3, 4, kNoCrossing);
  EXPECT_EQ(match_error(db.data(), prepare_scan(s), mo), kNoError);
}

// A ray cut short by an obstacle is compared up to its end only: a database crossing at or
// beyond the end is unknown, not missing (hand-computed sums).
TEST(MatcherRayEnd, DatabaseCrossingsBeyondTheRayEndAreNotCompared) {
  std::vector<std::uint8_t> db(kFeatureBytes, kNoCrossing);
  Scan s;
  s.radii_px.fill(kNoCrossing);
  s.ray_end_px.fill(kRayHidden);
  const std::uint8_t entry[] = {50, 120, 200, kNoCrossing};
  std::copy_n(entry, 4, db.begin() + 4 * 7);
  s.ray_end_px[7] = 100;
  s.radii_px[4 * 7] = 52;
  EXPECT_EQ(sad_reference(db.data(), s), 2u);  // |50 - 52|; 120 and 200 lie beyond the end
  EXPECT_EQ(sad_fast(db.data(), prepare_scan(s)), 2u);
  s.ray_end_px[7] = 121;  // now 120 is in view but was not seen: |120 - 255|
  EXPECT_EQ(sad_reference(db.data(), s), 2u + 135u);
  EXPECT_EQ(sad_fast(db.data(), prepare_scan(s)), 2u + 135u);
  s.ray_end_px[7] = 50;  // the obstacle starts at the first line: nothing of the ray is compared
  EXPECT_EQ(sad_fast(db.data(), prepare_scan(s)), 0u);
  EXPECT_EQ(prepare_scan(s).rays_used, 1);
}

TEST_F(Matcher, PaperSadIsNormalisedByTheRaysUsed) {
  const int cell = 27 * 75 + 37;  // (375, 275)
  Scan s = db_scan(cell);
  for (auto& v : s.radii_px)
    v = v == kNoCrossing ? 254 : static_cast<std::uint8_t>(v + 1);  // every slot off by 1
  MatchOptions paper;
  paper.cost = MatchCost::kPaperSad;
  MatchResult m = local_search(*db_, s, {375, 275}, 0.0, paper);
  EXPECT_EQ(m.cells_searched, 1);
  EXPECT_EQ(m.rays_used, 360);
  EXPECT_DOUBLE_EQ(m.error, 4.0);  // 4 crossings x 1 px per ray
  for (int k = 0; k < kScanRays; k += 2) s.ray_end_px[static_cast<std::size_t>(k)] = kRayHidden;
  for (int k = 100; k < 140; ++k) s.ray_end_px[static_cast<std::size_t>(k)] = kRayHidden;
  m = local_search(*db_, s, {375, 275}, 0.0, paper);
  EXPECT_EQ(m.rays_used, 160);
  EXPECT_DOUBLE_EQ(m.error, 4.0);  // same E with a third of the rays hidden
  // Nothing seen: no match.
  s.ray_end_px.fill(kRayHidden);
  m = global_search(*db_, s, paper);
  EXPECT_EQ(m.cell, -1);
  EXPECT_EQ(m.error, kNoError);
}

TEST_F(Matcher, BoundedErrorIsThePixelsPerCrossingWhateverIsHidden) {
  const int cell = 27 * 75 + 37;  // (375, 275)
  Scan s = db_scan(cell);
  int crossings = 0;
  for (auto& v : s.radii_px) {
    if (v == kNoCrossing) continue;
    ASSERT_LT(v, 254);
    v = static_cast<std::uint8_t>(v + 1);  // every crossing off by 1 px
    ++crossings;
  }
  ASSERT_GT(crossings, 300);
  MatchResult m = local_search(*db_, s, {375, 275}, 0.0);
  EXPECT_DOUBLE_EQ(m.error, 1.0);  // 1 px per crossing, both sides
  for (int k = 0; k < kScanRays; k += 2) s.ray_end_px[static_cast<std::size_t>(k)] = kRayHidden;
  for (int k = 100; k < 140; ++k) s.ray_end_px[static_cast<std::size_t>(k)] = kRayHidden;
  m = local_search(*db_, s, {375, 275}, 0.0);
  EXPECT_EQ(m.rays_used, 160);
  EXPECT_DOUBLE_EQ(m.error, 1.0);  // the same with a third of the rays hidden
  // Nothing seen: no match.
  s.ray_end_px.fill(kRayHidden);
  m = global_search(*db_, s);
  EXPECT_EQ(m.cell, -1);
  EXPECT_EQ(m.error, kNoError);
}

TEST_F(Matcher, GlobalSearchEqualsReference) {
  const std::uint64_t seed = 99;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(20, 730), uy(20, 530), uyaw(-180, 180);
  for (int trial = 0; trial < 5; ++trial) {
    const Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    sim::RenderOptions opt;
    opt.seed = seed + static_cast<std::uint64_t>(trial);
    opt.obstacles = sim::random_obstacles(renderer_->field(), pose, 3, opt.seed);
    const Scan s = scan_image(renderer_->render(pose, opt), renderer_->camera(), pose.yaw_deg);
    const MatchResult a = global_search(*db_, s), b = global_search_reference(*db_, s);
    EXPECT_EQ(a.cell, b.cell);
    EXPECT_EQ(a.error, b.error);
    EXPECT_EQ(a.second_error, b.second_error);
    EXPECT_EQ(a.ambiguous, b.ambiguous);
    EXPECT_EQ(a.cells_searched, 75 * 55);
    EXPECT_LT((a.grid_position_cm - Eigen::Vector2d(pose.x_cm, pose.y_cm)).norm(),
              7.1);  // the nearest grid point
  }
}

TEST_F(Matcher, LocalSearchWindows) {
  const Scan s = db_scan(0);
  const int expected[] = {1, 9, 25, 49};
  for (int r = 0; r < 4; ++r) {
    EXPECT_EQ(local_search(*db_, s, {376, 273}, 10.0 * r).cells_searched, expected[r])
        << "range " << 10 * r;
  }
  EXPECT_EQ(local_search(*db_, s, {5, 5}, 20.0).cells_searched, 9);  // clipped at the corner
  const MatchResult m = local_search(*db_, db_scan(27 * 75 + 40), {376, 273}, 30.0);
  EXPECT_EQ(m.cell, 27 * 75 + 40);  // (405, 275), inside the 7 x 7 window
  EXPECT_EQ(m.error, 0.0);
  EXPECT_THROW((void)local_search(*db_, s, {376, 273}, -1.0), std::invalid_argument);
}

// Issue 16 item 1: every search and the refinement end, without undefined behaviour, on any input
// (the checks load_feature_db makes on a file are repeated for a database made in memory).
TEST_F(Matcher, SearchesAndRefinementAreBoundedOnHostileInput) {
  const Scan s = db_scan(27 * 75 + 40);
  // A finite but huge centre used to convert 1e300 / 10 to int (undefined): clamped to the corner.
  const MatchResult far = local_search(*db_, s, {1e300, -1e300}, 10.0);
  EXPECT_EQ(far.cells_searched, 4);
  EXPECT_EQ(local_search(*db_, s, {376, 273}, 1e300).cells_searched, db_->grid.cells())
      << "range beyond the grid";
  EXPECT_EQ(local_search(*db_, s, {376, 273}, INFINITY).cells_searched, db_->grid.cells());
  EXPECT_THROW((void)local_search(*db_, s, {NAN, 273}, 10.0), std::invalid_argument);
  // A grid that is not one: refused before any cell is indexed.
  for (const auto& bad :
       {GridSpec{NAN, 5, 10, 75, 55}, GridSpec{5, INFINITY, 10, 75, 55},
        GridSpec{5, 5, 0.0, 75, 55}, GridSpec{5, 5, -10, 75, 55}, GridSpec{5, 5, 10, 0, 55},
        GridSpec{5, 5, 10, 75, -1}, GridSpec{5, 5, 10, 65536, 65536}}) {
    FeatureDb db = *db_;
    db.grid = bad;
    EXPECT_THROW((void)global_search(db, s), std::invalid_argument)
        << bad.x0_cm << " " << bad.step_cm << " " << bad.nx;
    EXPECT_THROW((void)local_search(db, s, {376, 273}, 10.0), std::invalid_argument);
  }
  // refine_match from a non-finite start (what a NaN grid origin gave) returns at once, unchanged.
  MatchResult m = global_search(*db_, s);
  ASSERT_GE(m.cell, 0);
  m.position_cm = {NAN, 100.0};
  refine_match(renderer_->field(), renderer_->camera(), s, m);
  EXPECT_TRUE(std::isnan(m.position_cm.x()));
  EXPECT_EQ(m.refine_probes, 0);
  // Absurd options end too: a NaN step never starts, a minimum step of 1e-300 or below zero stops
  // at the move cap; the position stays within the reach of the grid point.
  for (const auto& [start, min] :
       {std::pair{std::nan(""), 0.625}, std::pair{2.5, 1e-300}, std::pair{2.5, -1.0}}) {
    MatchOptions opt;
    opt.refine_start_step_cm = start;
    opt.refine_min_step_cm = min;
    MatchResult r = global_search(*db_, s);
    refine_match(renderer_->field(), renderer_->camera(), s, r, opt);
    EXPECT_TRUE(r.position_cm.allFinite());
    EXPECT_LE((r.position_cm - r.grid_position_cm).cwiseAbs().maxCoeff(),
              opt.refine_reach_cm + 1e-9);
  }
}

TEST_F(Matcher, RightCellOnNoiseFreeImagesEverywhereEvenEven) {
  every_grid_point(0, 0);
}
TEST_F(Matcher, RightCellOnNoiseFreeImagesEverywhereOddEven) {
  every_grid_point(1, 0);
}
TEST_F(Matcher, RightCellOnNoiseFreeImagesEverywhereEvenOdd) {
  every_grid_point(0, 1);
}
TEST_F(Matcher, RightCellOnNoiseFreeImagesEverywhereOddOdd) {
  every_grid_point(1, 1);
}

TEST_F(Matcher, RefinementGoesBelowTheGrid) {
  const Eigen::Vector2d points[] = {{228.7, 171.2}, {461.4, 333.3}, {102.5, 487.5},
                                    {640.9, 96.1},  {371.0, 279.0}, {533.3, 216.6}};
  double sum_grid = 0, sum_interp = 0, sum_ray = 0;
  for (const auto& p : points) {
    const Scan s = scan_image(renderer_->render({p.x(), p.y(), 12.0}, sim::noise_free()),
                              renderer_->camera(), 12.0);
    MatchResult m = global_search(*db_, s);
    const double grid_err = (m.grid_position_cm - p).norm();
    interpolate_match(*db_, s, m);
    const double interp_err = (m.position_cm - p).norm();
    EXPECT_LE((m.position_cm - m.grid_position_cm).cwiseAbs().maxCoeff(), 5.0);
    refine_match(renderer_->field(), renderer_->camera(), s, m);
    const double ray_err = (m.position_cm - p).norm();
    std::printf(
        "(%.1f, %.1f): grid point %.1f cm away, interpolated %.2f cm, ray-cast %.2f cm (E %.2f -> "
        "%.2f)\n",
        p.x(), p.y(), grid_err, interp_err, ray_err, m.error, m.refined_error);
    EXPECT_LT(ray_err, 1.5);
    EXPECT_LE(m.refined_error, m.error);
    sum_grid += grid_err;
    sum_interp += interp_err;
    sum_ray += ray_err;
  }
  EXPECT_LT(sum_interp, sum_grid * 0.75);
  EXPECT_LT(sum_ray, sum_grid / 3.0);
}

TEST_F(Matcher, YawFromTheScan) {
  const Pose2 truth{300.0, 210.0, 33.3};
  sim::RenderOptions opt;
  opt.seed = 5;
  const cv::Mat image = renderer_->render(truth, opt);
  const BearingScan b = scan_image_bearings(image, renderer_->camera(), 4);
  // A gyro that drifted by 9 degrees; the scan brings it back to within the 0.25 deg step.
  const YawEstimate y =
      estimate_yaw(renderer_->field(), renderer_->camera(), b, {300.0, 210.0}, 24.3, 15.0);
  std::printf("yaw: truth %.2f, estimate %.2f (E %.2f)\n", truth.yaw_deg, y.yaw_deg, y.error);
  EXPECT_NEAR(y.yaw_deg, truth.yaw_deg, 0.5);
  // Without any gyro (hint 0, full circle) it still finds it.
  const YawEstimate z =
      estimate_yaw(renderer_->field(), renderer_->camera(), b, {300.0, 210.0}, 0.0, 180.0);
  EXPECT_NEAR(z.yaw_deg, truth.yaw_deg, 0.5);
}

// The heading the localizer feeds back into the gyro: over random poses on the field (noisy
// rendered images, other robots in view), with a hint up to 2 degrees off and the position known
// to 1 cm, the estimate (below the 0.25 degree step) is within a fraction of a degree.
TEST_F(Matcher, YawFromTheScanOverRandomPoses) {
  const std::uint64_t seed = 19;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(100.0, 650.0), uy(100.0, 450.0), uyaw(-180.0, 180.0),
      u1(-1.0, 1.0);
  double sum = 0.0, worst = 0.0;
  const int n = 40;
  for (int i = 0; i < n; ++i) {
    const Pose2 truth{ux(rng), uy(rng), uyaw(rng)};
    sim::RenderOptions opt;
    opt.seed = seed + static_cast<std::uint64_t>(i);
    const BearingScan b =
        scan_image_bearings(renderer_->render(truth, opt), renderer_->camera(), 4);
    const double dy_cm = u1(rng);  // y first: the order gcc took as constructor arguments
    const Eigen::Vector2d position(truth.x_cm + u1(rng), truth.y_cm + dy_cm);
    const YawEstimate y = estimate_yaw(renderer_->field(), renderer_->camera(), b, position,
                                       truth.yaw_deg + 2.0 * u1(rng), 3.0);
    const double e = std::abs(angle_diff_deg(y.yaw_deg, truth.yaw_deg));
    sum += e;
    worst = std::max(worst, e);
  }
  std::printf("yaw from the scan over %d poses: mean error %.3f deg, worst %.3f deg\n", n, sum / n,
              worst);
  EXPECT_LT(sum / n, 0.25);
  EXPECT_LT(worst, 1.0);
}

TEST_F(Matcher, WithoutHeadingTheFieldSymmetryIsReportedAsAmbiguous) {
  const Pose2 truth{225.0, 173.0, 63.7};
  sim::RenderOptions opt;
  opt.seed = 8;
  const BearingScan b = scan_image_bearings(renderer_->render(truth, opt), renderer_->camera(), 4);
  const PoseMatch pm = global_search_any_yaw(*db_, renderer_->field(), renderer_->camera(), b, 2.0);
  // The point-symmetric pose sees the same lines: both must come out, flagged ambiguous.
  const Eigen::Vector2d p(truth.x_cm, truth.y_cm),
      mirror = 2.0 * renderer_->field().centre_cm() - p;
  std::printf("best (%.1f, %.1f) yaw %.2f E %.2f; second (%.1f, %.1f) yaw %.2f E %.2f\n",
              pm.match.position_cm.x(), pm.match.position_cm.y(), pm.yaw_deg, pm.match.error,
              pm.match.second_position_cm.x(), pm.match.second_position_cm.y(), pm.second_yaw_deg,
              pm.match.second_error);
  EXPECT_TRUE(pm.match.ambiguous);
  const bool best_is_truth = (pm.match.position_cm - p).norm() < 10.0;
  const Eigen::Vector2d other = best_is_truth ? mirror : p;
  EXPECT_LT((pm.match.position_cm - (best_is_truth ? p : mirror)).norm(), 5.0);
  EXPECT_LT((pm.match.second_position_cm - other).norm(), 10.0);
  const double best_yaw = best_is_truth ? truth.yaw_deg : truth.yaw_deg + 180.0;
  EXPECT_NEAR(angle_diff_deg(pm.yaw_deg, best_yaw), 0.0, 1.0);
  EXPECT_NEAR(angle_diff_deg(pm.second_yaw_deg, best_yaw + 180.0), 0.0, 2.0);
}

TEST_F(Matcher, AmbiguityWhenLittleIsSeen) {
  const Pose2 truth{225.0, 175.0, 0.0};
  Scan s =
      scan_image(renderer_->render(truth, sim::noise_free()), renderer_->camera(), truth.yaw_deg);
  MatchResult m = global_search(*db_, s);
  EXPECT_FALSE(m.ambiguous) << "E " << m.error << " second " << m.second_error;
  EXPECT_GT(m.second_error, 3.0 * m.error + 0.25 * MatchOptions{}.crossing_cap_px);
  // Only the rays looking straight at the bottom boundary (field directions 265..275) are left:
  // they see one line 100 cm away, as they would from anywhere along y = 175.
  for (int k = 0; k < kScanRays; ++k)
    s.ray_end_px[static_cast<std::size_t>(k)] = (k >= 265 && k <= 275) ? kRayToViewEnd : kRayHidden;
  m = global_search(*db_, s);
  EXPECT_TRUE(m.ambiguous) << "E " << m.error << " second " << m.second_error;
  EXPECT_NEAR(m.second_position_cm.y(), 175.0, 10.0);
  EXPECT_GE((m.second_position_cm - m.grid_position_cm).norm(), 50.0);
}

// One frame's scan is rotated and prepared once (FieldScan) and every step takes it: the results
// are those of the steps given the plain field-frame Scan (rotated by hand here, ray by ray).
TEST_F(Matcher, FieldScanIsTheBearingsRotatedOnceWithTheSameResults) {
  const Pose2 truth{461.4, 333.3, -71.6};
  sim::RenderOptions opt;
  opt.seed = 9;
  const BearingScan b = scan_image_bearings(renderer_->render(truth, opt), renderer_->camera(), 4);
  const FieldScan f = make_field_scan(b, truth.yaw_deg);
  EXPECT_EQ(f.yaw_deg, truth.yaw_deg);
  // Field ray k is robot bearing k - yaw: the nearest of the 4-per-degree robot rays.
  for (int k = 0; k < kScanRays; ++k) {
    long j = std::lround((k - truth.yaw_deg) * 4.0) % 1440;
    if (j < 0) j += 1440;
    ASSERT_EQ(f.scan.ray_end_px[static_cast<std::size_t>(k)],
              b.ray_end_px[static_cast<std::size_t>(j)])
        << k;
    for (int n = 0; n < kCrossingsPerRay; ++n)
      ASSERT_EQ(f.scan.radii_px[static_cast<std::size_t>(4 * k + n)],
                b.radii_px[static_cast<std::size_t>(4 * j + n)])
          << k;
  }
  EXPECT_EQ(f.prepared.rays_used, f.scan.rays_valid());
  const Scan s = f.scan;
  MatchOptions mo;
  mo.refinement = Refinement::kRayCast;
  const MatchResult g1 = global_search(*db_, f, mo), g2 = global_search(*db_, s, mo);
  EXPECT_EQ(g1.cell, g2.cell);
  EXPECT_EQ(g1.error, g2.error);
  EXPECT_EQ(g1.second_error, g2.second_error);
  MatchResult l1 = local_search(*db_, f, {460.0, 330.0}, 20.0, mo),
              l2 = local_search(*db_, s, {460.0, 330.0}, 20.0, mo);
  EXPECT_EQ(l1.cell, l2.cell);
  EXPECT_EQ(l1.error, l2.error);
  // Robot ray j0 = round(71.6 * 4) = 286 became field ray 0: it points at 286 / 4 - 71.6 = -0.1
  // deg.
  EXPECT_NEAR(f.bearing_offset_deg, -0.1, 1e-9);
  FieldScan by_hand = make_field_scan(s);
  by_hand.bearing_offset_deg = -0.1;
  apply_refinement(*db_, renderer_->field(), renderer_->camera(), f, l1, mo);
  interpolate_match(*db_, s, l2);
  refine_match(renderer_->field(), renderer_->camera(), by_hand, l2, mo);
  EXPECT_EQ(l1.position_cm, l2.position_cm);
  EXPECT_EQ(l1.refined_error, l2.refined_error);
  EXPECT_LT((l1.position_cm - truth.position_cm()).norm(), 2.0);
}

// A robot-frame scan at 2 rays per degree turned into the field frame at a heading of 10.3 deg:
// field ray k is robot ray 2k - 21 (the nearest), which points at k - 0.2 deg. Cast at whole
// degrees the refinement is pulled off by the 0.2 deg (up to ~1.5 cm at the boundary, where the
// lines are far); cast where the rays point it is not. Noise-free frames, the paper's scan.
TEST_F(Matcher, RefinementCastsWhereTheRotatedRaysPoint) {
  const Eigen::Vector2d points[] = {{75.0, 75.0},  {380.0, 74.0},  {678.0, 71.0},
                                    {90.0, 466.0}, {375.0, 475.0}, {662.0, 467.0}};
  const double yaw = 10.3;
  MatchOptions mo;
  mo.refinement = Refinement::kRayCast;
  double sum_at = 0.0, sum_whole = 0.0;
  for (const auto& p : points) {
    const BearingScan b = scan_image_bearings(
        renderer_->render({p.x(), p.y(), yaw}, sim::noise_free()), renderer_->camera(), 2);
    const FieldScan at = make_field_scan(b, yaw);
    ASSERT_NEAR(at.bearing_offset_deg, -0.2, 1e-9);
    FieldScan whole = at;
    whole.bearing_offset_deg = 0.0;
    MatchResult m1 = global_search(*db_, at, mo), m2 = m1;
    apply_refinement(*db_, renderer_->field(), renderer_->camera(), at, m1, mo);
    apply_refinement(*db_, renderer_->field(), renderer_->camera(), whole, m2, mo);
    const double e1 = (m1.position_cm - p).norm(), e2 = (m2.position_cm - p).norm();
    std::printf("(%.0f, %.0f): cast where the rays point %.2f cm, at whole degrees %.2f cm\n",
                p.x(), p.y(), e1, e2);
    sum_at += e1;
    sum_whole += e2;
  }
  std::printf("mean: %.2f cm vs %.2f cm\n", sum_at / 6.0, sum_whole / 6.0);
  EXPECT_LT(sum_at, sum_whole);
  EXPECT_LT(sum_at / 6.0, 0.5);
}

// Where the shipped E_TH and ambiguity ratio come from (docs/VISION.md "Match error"): on noisy
// rendered frames with 0-4 other robots at random poses the global search finds the right cell
// or its neighbour, whose error stays below E_TH, and the second minimum elsewhere is always more
// than the ambiguity ratio above it. A second minimum can come close to E_TH (printed): the
// ambiguity test, not E_TH, tells a wrong place apart. The paper's SAD is measured beside it.
TEST_F(Matcher, ShippedThresholdsSeparateRightFromWrongOnRenderedFrames) {
  const std::uint64_t seed = 77;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(10, 740), uy(10, 540), uyaw(-180, 180);
  const LocalizerConfig shipped;
  MatchOptions bounded, paper;
  bounded.crossing_cap_px = shipped.crossing_cap_px;
  bounded.ambiguity_ratio = shipped.ambiguity_ratio;
  paper.cost = MatchCost::kPaperSad;
  struct Stats {
    double worst_right = 0.0, best_second = kNoError, min_ratio = kNoError;
    int wrong = 0;
  } sb, sp;
  const auto record = [&](Stats& st, const MatchResult& m, const Pose2& truth) {
    const double off = (m.grid_position_cm - truth.position_cm()).cwiseAbs().maxCoeff();
    if (off > 1.5 * db_->grid.step_cm) {  // beyond the neighbouring cell: a wrong place
      ++st.wrong;
      return;
    }
    st.worst_right = std::max(st.worst_right, m.error);
    st.best_second = std::min(st.best_second, m.second_error);
    st.min_ratio = std::min(st.min_ratio, m.second_error / m.error);
  };
  const int n = 60;
  for (int i = 0; i < n; ++i) {
    const Pose2 truth{ux(rng), uy(rng), uyaw(rng)};
    const FieldScan f = noisy_field_scan(truth, seed * 1000 + static_cast<std::uint64_t>(i), i % 5);
    record(sb, global_search(*db_, f, bounded), truth);
    record(sp, global_search(*db_, f, paper), truth);
  }
  for (const auto& [name, st] : {std::pair{"bounded", sb}, std::pair{"paper SAD", sp}}) {
    std::printf(
        "%-9s over %d frames: right cell's error <= %.2f, second minima >= %.2f, ratio >= %.2f, %d "
        "wrong cells\n",
        name, n, st.worst_right, st.best_second, st.min_ratio, st.wrong);
  }
  EXPECT_EQ(sb.wrong, 0);
  EXPECT_LT(sb.worst_right, shipped.e_th);
  EXPECT_GT(sb.min_ratio, shipped.ambiguity_ratio);
}

// The refinement (linearised ray cast) reaches the reference pattern search's accuracy with a
// fraction of its full ray casts.
TEST_F(Matcher, RefinementMatchesThePatternSearchWithFewerRayCasts) {
  const std::uint64_t seed = 78;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(10, 740), uy(10, 540), uyaw(-180, 180);
  const int n = 40;
  double sum_fast = 0.0, sum_ref = 0.0;
  int probes_fast = 0, probes_ref = 0;
  for (int i = 0; i < n; ++i) {
    const Pose2 truth{ux(rng), uy(rng), uyaw(rng)};
    const FieldScan f = noisy_field_scan(truth, seed * 1000 + static_cast<std::uint64_t>(i), i % 3);
    MatchResult a = local_search(*db_, f, truth.position_cm(), 20.0);
    interpolate_match(*db_, f, a);
    MatchResult b = a;
    refine_match(renderer_->field(), renderer_->camera(), f, a);
    refine_match_reference(renderer_->field(), renderer_->camera(), f, b);
    sum_fast += (a.position_cm - truth.position_cm()).norm();
    sum_ref += (b.position_cm - truth.position_cm()).norm();
    probes_fast += a.refine_casts;
    probes_ref += b.refine_casts;
    // The reported error is the exact ray-cast error at the reported position.
    EXPECT_EQ(a.refined_error,
              error_at(renderer_->field(), renderer_->camera(), f.prepared, a.position_cm));
  }
  std::printf(
      "refine_match: mean error %.2f cm, %.1f ray casts; reference pattern search %.2f cm, %.1f "
      "ray casts\n",
      sum_fast / n, static_cast<double>(probes_fast) / n, sum_ref / n,
      static_cast<double>(probes_ref) / n);
  EXPECT_LE(sum_fast / n, sum_ref / n + 0.1);
  EXPECT_LT(probes_fast, probes_ref);
}

}  // namespace
}  // namespace omniloc
