// Line scan: scans of rendered images against scans computed directly from the geometry (the ray
// caster), the fast scan against the OpenCV whole-image reference, the mast and obstacles as
// missing rays, and the yaw rotation.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "omniloc/detail/vision_reference.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc {
namespace {

struct Agreement {
  int compared = 0;
  int exact = 0;
  int within_1px = 0;
};

// Compares a scan's valid rays with the geometric scan crossing by crossing.
Agreement compare(const Scan& image, const Scan& geometry) {
  Agreement a;
  for (int k = 0; k < kScanRays; ++k) {
    const int end = image.ray_end_px[static_cast<std::size_t>(k)];
    if (end == kRayHidden) continue;
    // Beyond the ray's end both are unknown (kNoCrossing), as the matcher compares them.
    auto clip = [end](int r) { return r >= end ? int{kNoCrossing} : r; };
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      const int i = k * kCrossingsPerRay + n;
      const int x = clip(image.radii_px[static_cast<std::size_t>(i)]),
                y = clip(geometry.radii_px[static_cast<std::size_t>(i)]);
      ++a.compared;
      a.exact += x == y;
      a.within_1px += std::abs(x - y) <= 1;
    }
  }
  return a;
}

class LineScan : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    renderer_ = new sim::OmniRenderer(load_field("fira-robosot"), load_camera("default"));
  }
  static void TearDownTestSuite() {
    delete renderer_;
    renderer_ = nullptr;
  }
  static sim::OmniRenderer* renderer_;
};
sim::OmniRenderer* LineScan::renderer_ = nullptr;

TEST_F(LineScan, NoiseFreeImagesMatchTheGeometricScan) {
  const std::uint64_t seed = 20261122;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(20, 730), uy(20, 530), uyaw(-180, 180);
  Agreement total;
  for (int i = 0; i < 40; ++i) {
    const Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    const Scan img =
        scan_image(renderer_->render(pose, sim::noise_free()), renderer_->camera(), pose.yaw_deg);
    const Scan geo = expected_scan(renderer_->field(), renderer_->camera(), {pose.x_cm, pose.y_cm});
    const Agreement a = compare(img, geo);
    // Exactly the mast's rays are missing on a noise-free image without obstacles: the field
    // directions k whose bearing k - yaw lies within 180 +- 4 deg.
    int mast_rays = 0;
    for (int k = 0; k < kScanRays; ++k)
      mast_rays += std::abs(angle_diff_deg(k - pose.yaw_deg, 180.0)) <= 4.0;
    EXPECT_EQ(img.rays_valid(), kScanRays - mast_rays) << "pose " << pose.x_cm << ", " << pose.y_cm;
    EXPECT_GE(a.within_1px, a.compared * 90 / 100) << "pose " << pose.x_cm << ", " << pose.y_cm;
    total.compared += a.compared;
    total.exact += a.exact;
    total.within_1px += a.within_1px;
  }
  std::printf("noise-free: %d crossings, %.1f %% exact, %.1f %% within 1 px\n", total.compared,
              100.0 * total.exact / total.compared, 100.0 * total.within_1px / total.compared);
  EXPECT_GE(total.within_1px, total.compared * 95 / 100);
}

TEST(LineScanCamera, MirroredCameraWithYawOffsetGivesTheSameFieldFrameScan) {
  // The field-frame feature must not depend on how the camera is mounted: render and scan with a
  // mirrored camera turned by 17.5 deg, compare with the same geometric scan.
  CameraModel cam = load_camera("default");
  cam.mirrored = true;
  cam.yaw_offset_deg = 17.5;
  const FieldGeometry field = load_field("fira-robosot");
  const sim::OmniRenderer renderer(field, cam);
  Agreement total;
  for (int i = 0; i < 8; ++i) {
    const Pose2 pose{90.0 + 80 * i, 60.0 + 55 * i, -170.0 + 43 * i};
    const Scan img = scan_image(renderer.render(pose, sim::noise_free()), cam, pose.yaw_deg);
    const Agreement a = compare(img, expected_scan(field, cam, {pose.x_cm, pose.y_cm}));
    total.compared += a.compared;
    total.within_1px += a.within_1px;
    // The mast is at robot bearing 180: field directions yaw + 180 +- 4 are missing.
    EXPECT_EQ(img.ray_end_px[static_cast<std::size_t>(
                  std::lround(wrap_deg(pose.yaw_deg + 180.0) + 360.0) % 360)],
              kRayHidden);
  }
  EXPECT_GE(total.within_1px, total.compared * 95 / 100);
}

TEST_F(LineScan, NoisyImagesWithGradientStillMatchMostly) {
  const std::uint64_t seed = 77;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(20, 730), uy(20, 530), uyaw(-180, 180);
  Agreement total;
  for (int i = 0; i < 20; ++i) {
    const Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    sim::RenderOptions opt;
    opt.seed = seed + static_cast<std::uint64_t>(i);
    opt.gradient_direction_deg = 17.0 * i;
    const Scan img = scan_image(renderer_->render(pose, opt), renderer_->camera(), pose.yaw_deg);
    const Agreement a = compare(
        img, expected_scan(renderer_->field(), renderer_->camera(), {pose.x_cm, pose.y_cm}));
    total.compared += a.compared;
    total.exact += a.exact;
    total.within_1px += a.within_1px;
  }
  std::printf("noisy: %d crossings, %.1f %% exact, %.1f %% within 1 px\n", total.compared,
              100.0 * total.exact / total.compared, 100.0 * total.within_1px / total.compared);
  EXPECT_GE(total.within_1px, total.compared * 85 / 100);
}

TEST_F(LineScan, FastScanEqualsOpenCvReference) {
  for (int i = 0; i < 6; ++i) {
    const Pose2 pose{100.0 + 100 * i, 120.0 + 60 * i, -150.0 + 55 * i};
    sim::RenderOptions opt;
    opt.seed = 1000 + static_cast<std::uint64_t>(i);
    opt.obstacles = sim::random_obstacles(renderer_->field(), pose, 3, opt.seed);
    const cv::Mat image = renderer_->render(pose, opt);
    const Scan fast = scan_image(image, renderer_->camera(), pose.yaw_deg);
    const Scan ref = scan_image_reference(image, renderer_->camera(), pose.yaw_deg);
    EXPECT_EQ(fast.radii_px, ref.radii_px) << "pose " << i;
    EXPECT_EQ(fast.ray_end_px, ref.ray_end_px) << "pose " << i;
  }
}

TEST_F(LineScan, MastHidesRaysAndObstaclesEndThem) {
  const Pose2 pose{375, 275, 40};
  sim::RenderOptions opt = sim::noise_free();
  const sim::Obstacle robot{Eigen::Vector2d(375 + 100, 275), 20.0};  // 100 cm along field +x
  opt.obstacles = {robot};
  const Scan s = scan_image(renderer_->render(pose, opt), renderer_->camera(), pose.yaw_deg);
  const CameraModel& cam = renderer_->camera();
  const Scan geometry = expected_scan(renderer_->field(), cam, {pose.x_cm, pose.y_cm});
  // The obstacle subtends asin(20 / 100) = 11.5 deg on each side of field direction 0; each of
  // those rays ends where it meets the cylinder, at 100 cos(k) - sqrt(20^2 - (100 sin(k))^2) cm,
  // and keeps the crossings before it.
  for (int k = -11; k <= 11; ++k) {
    const double a = deg_to_rad(k);
    const double hit_cm = 100.0 * std::cos(a) - std::sqrt(400.0 - std::pow(100.0 * std::sin(a), 2));
    const std::size_t ray = static_cast<std::size_t>((k + 360) % 360);
    EXPECT_NEAR(s.ray_end_px[ray], cam.radius_px_at_ground(hit_cm), 1.5) << k;
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      const std::size_t i = ray * kCrossingsPerRay + static_cast<std::size_t>(n);
      if (geometry.radii_px[i] < s.ray_end_px[ray])
        EXPECT_NEAR(s.radii_px[i], geometry.radii_px[i], 1.0) << k;
      else
        EXPECT_EQ(s.radii_px[i], kNoCrossing) << k;
    }
  }
  EXPECT_GT(s.radii_px[0], 0);  // the centre circle, 60 cm away, is before the obstacle
  EXPECT_LT(s.radii_px[0], s.ray_end_px[0]);
  for (int k : {-14, 14, 90, 180})
    EXPECT_EQ(s.ray_end_px[static_cast<std::size_t>((k + 360) % 360)], kRayToViewEnd) << k;
  // The mast is at bearing 180 +- 4: field directions 40 + 180 +- 4.
  for (int k = 216; k <= 224; ++k)
    EXPECT_EQ(s.ray_end_px[static_cast<std::size_t>(k)], kRayHidden) << k;
  EXPECT_EQ(s.ray_end_px[215], kRayToViewEnd);
  EXPECT_EQ(s.ray_end_px[225], kRayToViewEnd);
  // Hidden rays carry the sentinel, never zero radii.
  for (int i = 0; i < kCrossingsPerRay; ++i)
    EXPECT_EQ(s.radii_px[220 * kCrossingsPerRay + i], kNoCrossing);
  EXPECT_EQ(s.rays_valid(), 360 - 9);  // all but the mast's 9
}

TEST_F(LineScan, BearingScanRotatesIntoTheFieldFrame) {
  const Pose2 pose{300, 200, 23.0};
  const cv::Mat image = renderer_->render(pose, sim::noise_free());
  const BearingScan b = scan_image_bearings(image, renderer_->camera(), 1);
  // With one ray per degree and an integer yaw, the rotation picks exactly the direct scan's rays.
  const Scan direct = scan_image(image, renderer_->camera(), pose.yaw_deg);
  const Scan rotated = rotate_to_field(b, pose.yaw_deg);
  EXPECT_EQ(direct.radii_px, rotated.radii_px);
  EXPECT_EQ(direct.ray_end_px, rotated.ray_end_px);
}

TEST_F(LineScan, RejectsImagesThatDoNotFitTheCamera) {
  EXPECT_THROW((void)scan_image(cv::Mat(), renderer_->camera(), 0.0), std::invalid_argument);
  EXPECT_THROW((void)scan_image(cv::Mat(100, 100, CV_8UC3), renderer_->camera(), 0.0),
               std::invalid_argument);
  EXPECT_THROW((void)scan_image(cv::Mat(480, 640, CV_8UC1), renderer_->camera(), 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace omniloc
