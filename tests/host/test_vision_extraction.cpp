// Line extraction (issue 13 item 2) against independent references: on the real TKU frame, the
// field model projected through the camera `omniloc calibrate` fitted to it
// (tests/data/tku-robosot-centre-spot.camera.json, see tests/data/README.md); on rendered frames
// (and darker, brighter, bluish-line, obstacle variants), the geometric scan (expected_scan); the
// old fixed-threshold scan on the same frames as the floor not to fall below; frames with nothing
// usable in them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/detail/config_reader.hpp"
#include "omniloc/detail/line_extractor.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/recording.hpp"
#include "omniloc/vision.hpp"
#include "omniloc_sim/renderer.hpp"
#include "test_data_path.hpp"

namespace omniloc {
namespace {

using test::test_data;

// Crossing agreement of a field-frame scan with the geometric truth, on the rays it saw, below
// each ray's end: recall (truth crossings found within tol) and precision (found crossings that
// are true within tol).
struct Agreement {
  int truth = 0, truth_found = 0, found = 0, found_true = 0;
  double abs_err_sum = 0.0, err_sum = 0.0;
  [[nodiscard]] double recall() const {
    return truth ? static_cast<double>(truth_found) / truth : 0.0;
  }
  [[nodiscard]] double precision() const {
    return found ? static_cast<double>(found_true) / found : 0.0;
  }
  [[nodiscard]] double mean_err() const { return truth_found ? abs_err_sum / truth_found : 0.0; }
  void add(const Agreement& o) {
    truth += o.truth;
    truth_found += o.truth_found;
    found += o.found;
    found_true += o.found_true;
    abs_err_sum += o.abs_err_sum;
    err_sum += o.err_sum;
  }
};

Agreement compare(const Scan& s, const Scan& truth, double tol) {
  Agreement a;
  for (int k = 0; k < kScanRays; ++k) {
    const int end = s.ray_end_px[static_cast<std::size_t>(k)];
    if (end == kRayHidden) continue;
    const std::uint8_t* x = s.radii_px.data() + k * kCrossingsPerRay;
    const std::uint8_t* y = truth.radii_px.data() + k * kCrossingsPerRay;
    auto nearest = [](const std::uint8_t* v, int r, int below) {
      int best = 1000;
      for (int n = 0; n < kCrossingsPerRay; ++n)
        if (v[n] != kNoCrossing && v[n] < below && std::abs(v[n] - r) < std::abs(best - r))
          best = v[n];
      return best;
    };
    // Truth crossings: the first four of the model, below the ray's end (a fifth one is cut off by
    // the format, so the last found one may be a truth crossing beyond the fourth: not counted).
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      if (y[n] == kNoCrossing || y[n] >= end) continue;
      ++a.truth;
      const int b = nearest(x, y[n], end);
      if (std::abs(b - y[n]) <= tol) {
        ++a.truth_found;
        a.abs_err_sum += std::abs(b - y[n]);
        a.err_sum += b - y[n];
      }
    }
    const int last_truth = y[kCrossingsPerRay - 1];
    for (int n = 0; n < kCrossingsPerRay; ++n) {
      if (x[n] == kNoCrossing) continue;
      if (last_truth != kNoCrossing && x[n] > last_truth + tol)
        continue;  // beyond the model's fourth
      ++a.found;
      a.found_true += std::abs(nearest(y, x[n], 255) - x[n]) <= tol;
    }
  }
  return a;
}

void print(const char* what, const Agreement& a) {
  std::printf(
      "%-34s truth %5d recall %5.1f %%  found %5d precision %5.1f %%  mean |err| %.2f px (signed "
      "%+.2f)\n",
      what, a.truth, 100 * a.recall(), a.found, 100 * a.precision(), a.mean_err(),
      a.truth_found ? a.err_sum / a.truth_found : 0.0);
}

// ---------------------------------------------------------------------------------------------
// The real frame.

struct RealFrame {
  cv::Mat image;
  CameraModel camera;
  nlohmann::json calibration;  // the camera file's "calibration" record
};

RealFrame real_frame() {
  RealFrame f;
  const auto img = test_data("tku-robosot-centre-spot.png");
  const auto cam = test_data("tku-robosot-centre-spot.camera.json");
  if (img.empty() || cam.empty()) return f;
  f.image = cv::imread(img.string(), cv::IMREAD_COLOR);
  f.camera = load_camera(cam.string());
  std::ifstream in(cam);
  f.calibration = nlohmann::json::parse(in)["calibration"];
  return f;
}

// The calibrated camera's lut extended along its fitted radial polynomial to the mirror's rim, so
// that the rays reach beyond where the carpet ends (the calibrated lut stops at the 10th
// percentile of the carpet's end): the extraction, not the table, must end them there.
CameraModel extended_to_rim(const RealFrame& f) {
  CameraModel c = f.camera;
  const auto a = f.calibration["radial_model"]["a"];
  const double rim = f.calibration["rim"]["radius_px"].get<double>() - 2.0;
  auto d = [&](double r) {
    return r * (a[0].get<double>() +
                r * (a[1].get<double>() + r * (a[2].get<double>() + r * a[3].get<double>())));
  };
  c.radius_lut.clear();
  for (double r = 0.0; r < rim; r += 4.0) c.radius_lut.push_back({r, d(r)});
  c.radius_lut.push_back({rim, d(rim)});
  c.validate(config::Origin("extended camera"));
  return c;
}

// OMNILOC_VISION_OVERLAY=dir: the frame with the model (green), the crossings (red), the ray ends
// at the carpet edge (cyan) and at obstacles (yellow), for looking at what the test measures.
void overlay(const std::string& name, const cv::Mat& img, const CameraModel& cam,
             const BearingScan& b, const ExtractionReport& rep, double yaw) {
  const char* dir = std::getenv("OMNILOC_VISION_OVERLAY");
  if (dir == nullptr) return;
  cv::Mat o = img.clone();
  const Scan truth = expected_scan(load_field("fira-robosot"), cam, {375.0, 275.0});
  const int n = static_cast<int>(b.ray_end_px.size());
  auto px = [&](double bearing, double r) {
    const double phi = deg_to_rad(cam.image_angle_deg(bearing));
    return cv::Point(static_cast<int>(std::lround(cam.center_px.x() +
                                                  (cam.mirrored ? -1 : 1) * r * std::cos(phi))),
                     static_cast<int>(std::lround(cam.center_px.y() - r * std::sin(phi))));
  };
  for (int j = 0; j < n; ++j) {
    const double bearing = static_cast<double>(j) / b.rays_per_degree;
    const int e = b.ray_end_px[static_cast<std::size_t>(j)];
    if (e != kRayHidden && e != kRayToViewEnd)
      cv::circle(o, px(bearing, e), 0,
                 rep.carpet_end_px[static_cast<std::size_t>(j)] == 255 ? cv::Scalar(0, 255, 255)
                                                                       : cv::Scalar(255, 255, 0),
                 -1);
    for (int k = 0; k < 4; ++k) {
      const int r = b.radii_px[static_cast<std::size_t>(j) * 4 + k];
      if (r != kNoCrossing) cv::circle(o, px(bearing, r), 0, {0, 0, 255}, -1);
    }
  }
  for (int k = 0; k < kScanRays; ++k)
    for (int c = 0; c < 4; ++c) {
      const int r = truth.radii_px[static_cast<std::size_t>(k) * 4 + c];
      if (r != kNoCrossing) cv::circle(o, px(k - yaw, r), 0, {0, 255, 0}, -1);
    }
  cv::imwrite(std::string(dir) + "/" + name + ".png", o);
}

// Best of the two headings the symmetric field allows (calibrate found 0, its twin is 180).
Agreement real_agreement(const BearingScan& b, const CameraModel& cam, double tol,
                         double* yaw_out) {
  const Scan truth = expected_scan(load_field("fira-robosot"), cam, {375.0, 275.0});
  Agreement best;
  for (double yaw : {0.0, 180.0}) {
    const Agreement a = compare(rotate_to_field(b, yaw), truth, tol);
    if (a.truth_found + a.found_true > best.truth_found + best.found_true) {
      best = a;
      if (yaw_out) *yaw_out = yaw;
    }
  }
  return best;
}

TEST(VisionRealFrame, CrossingsAgreeWithTheCalibratedProjection) {
  const RealFrame f = real_frame();
  ASSERT_FALSE(f.image.empty())
      << "tests/data/tku-robosot-centre-spot.png / .camera.json not found";
  ASSERT_FALSE(f.camera.vision.carpet_hsv.has_value());  // the carpet is estimated from the frame
  LineExtractor ex(f.camera);
  ExtractionReport rep;
  const BearingScan b = ex.extract(f.image, 4, &rep);
  double yaw = 0;
  const Agreement a = real_agreement(b, f.camera, 2.0, &yaw);
  std::printf(
      "real frame (calibrated view %.0f px): %d rays, %d seen, %d crossings, carpet %.0f %% (hue "
      "%.0f +- %.0f, S >= %.0f, "
      "V %.0f..%.0f), steps V %.1f S %.1f, %d ends at the carpet edge, %d at obstacles, %zu blobs, "
      "heading %.0f\n",
      f.camera.view_radius_px(), rep.rays, rep.rays_seen, rep.crossings, 100 * rep.carpet_fraction,
      rep.carpet.hue, rep.carpet.hue_half_width, rep.carpet.sat_min, rep.carpet.val_min,
      rep.carpet.val_max, rep.contrast.val_step, rep.contrast.sat_step,
      rep.rays_ended_at_carpet_edge, rep.rays_ended_at_obstacle, rep.obstacles.size(), yaw);
  print("real frame vs calibrated model", a);
  overlay("real", f.image, f.camera, b, rep, yaw);
  const Agreement old =
      real_agreement(scan_image_bearings(f.image, f.camera, 4), f.camera, 2.0, nullptr);
  print("real frame, fixed thresholds", old);
  EXPECT_TRUE(rep.usable) << rep.reason;
  EXPECT_GT(rep.rays_seen, rep.rays * 8 / 10);
  EXPECT_GT(a.recall(), 0.7);
  // Measured 57 %: the rest are real edges the model lacks (goal-area fringes, the ball's and the
  // rods' outlines, double edges of the thick fringed lines); see docs/VISION.md.
  EXPECT_GT(a.precision(), 0.5);
  EXPECT_GT(a.recall(), old.recall());
}

TEST(VisionRealFrame, RaysEndWhereTheCarpetEndsNotInTheWalls) {
  const RealFrame f = real_frame();
  ASSERT_FALSE(f.image.empty());
  const CameraModel cam = extended_to_rim(f);
  LineExtractor ex(cam);
  ExtractionReport rep;
  const BearingScan b = ex.extract(f.image, 4, &rep);
  // Independent reference for the carpet's end: the calibration's own view radius is the 10th
  // percentile of where the carpet ends; most rays must end near or beyond it, none at the rim.
  const double view = f.camera.view_radius_px();
  int ended = 0, beyond_view = 0, at_rim = 0, seen = 0;
  for (std::size_t j = 0; j < b.ray_end_px.size(); ++j) {
    const int e = b.ray_end_px[j];
    if (e == kRayHidden) continue;
    ++seen;
    if (e == kRayToViewEnd) {
      ++at_rim;
      continue;
    }
    ++ended;
    beyond_view += e >= view - 3.0;
  }
  std::printf(
      "extended to the rim (%.0f px): %d rays seen, %d ended (%d at or beyond the calibrated view "
      "%.0f px), %d reach the rim; "
      "%d crossings\n",
      cam.view_radius_px(), seen, ended, beyond_view, view, at_rim, rep.crossings);
  EXPECT_LT(at_rim, seen / 10);
  EXPECT_GT(beyond_view, ended * 8 / 10);
  // The crossings within the calibrated view still agree with the model.
  double yaw = 0;
  const Agreement a = real_agreement(b, cam, 2.0, &yaw);
  print("extended camera vs model", a);
  // The ball (orange: OpenCV hue <= 15, saturated, bright; an independent colour test) ends the
  // rays that meet it, at or before its nearest pixel on the ray.
  cv::Mat hsv;
  cv::cvtColor(f.image, hsv, cv::COLOR_BGR2HSV);
  int ball_rays = 0, ended_at_ball = 0;
  for (std::size_t j = 0; j < b.ray_end_px.size(); ++j) {
    if (b.ray_end_px[j] == kRayHidden) continue;
    const double phi = deg_to_rad(cam.image_angle_deg(static_cast<double>(j) / b.rays_per_degree));
    for (int r = static_cast<int>(cam.min_radius_px()) + 1; r < cam.view_radius_px(); ++r) {
      const int u = static_cast<int>(std::lround(cam.center_px.x() + r * std::cos(phi)));
      const int v = static_cast<int>(std::lround(cam.center_px.y() - r * std::sin(phi)));
      const cv::Vec3b h = hsv.at<cv::Vec3b>(v, u);
      if ((h[0] <= 15 || h[0] >= 170) && h[1] >= 150 && h[2] >= 150) {
        ++ball_rays;
        ended_at_ball += b.ray_end_px[j] <= r + 2;
        break;
      }
    }
  }
  std::printf("ball: %d rays meet it, %d end at it\n", ball_rays, ended_at_ball);
  EXPECT_GT(ball_rays, 20);
  EXPECT_GE(ended_at_ball, ball_rays * 9 / 10);
  overlay("real-extended", f.image, cam, b, rep, yaw);
}

// ---------------------------------------------------------------------------------------------
// Rendered frames.

class VisionRendered : public ::testing::Test {
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
sim::OmniRenderer* VisionRendered::renderer_ = nullptr;

enum class Perturb { kNone, kDark, kBright, kBluishLines, kRobots };

cv::Mat perturb(const cv::Mat& img, Perturb p) {
  cv::Mat out = img.clone();
  if (p == Perturb::kDark) img.convertTo(out, -1, 0.55, 0.0);
  if (p == Perturb::kBright) img.convertTo(out, -1, 1.35, 10.0);
  if (p == Perturb::kBluishLines) {
    // The real frame's lines: bluish white, saturation 68-89 (B 210, G 180, R 145 -> S 79).
    for (int v = 0; v < out.rows; ++v)
      for (int u = 0; u < out.cols; ++u) {
        auto& px = out.at<cv::Vec3b>(v, u);
        const int mx = std::max({px[0], px[1], px[2]}), mn = std::min({px[0], px[1], px[2]});
        if (mx >= 150 && mx - mn < 60)
          px = cv::Vec3b(static_cast<std::uint8_t>(mx * 210 / 255),
                         static_cast<std::uint8_t>(mx * 180 / 255),
                         static_cast<std::uint8_t>(mx * 145 / 255));
      }
  }
  return out;
}

struct Compared {
  Agreement fresh, old;
  int unusable = 0;
};

Compared run(const sim::OmniRenderer& r, Perturb p, std::uint64_t seed, int frames) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(60, 690), uy(60, 490), uyaw(-180, 180);
  Compared c;
  LineExtractor ex(r.camera());
  for (int i = 0; i < frames; ++i) {
    const Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    sim::RenderOptions opt;
    opt.seed = seed + static_cast<std::uint64_t>(i);
    opt.gradient_direction_deg = 23.0 * i;
    if (p == Perturb::kRobots) opt.obstacles = sim::random_obstacles(r.field(), pose, 4, opt.seed);
    const cv::Mat img = perturb(r.render(pose, opt), p);
    const Scan truth = expected_scan(r.field(), r.camera(), {pose.x_cm, pose.y_cm});
    ExtractionReport rep;
    const BearingScan b = ex.extract(img, 4, &rep);
    c.unusable += !rep.usable;
    c.fresh.add(compare(rotate_to_field(b, pose.yaw_deg), truth, 1.0));
    c.old.add(compare(scan_image(img, r.camera(), pose.yaw_deg), truth, 1.0));
  }
  return c;
}

TEST_F(VisionRendered, CrossingsMatchTheGeometryAndAreNoWorseThanFixedThresholds) {
  const std::uint64_t seed = 1302;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const std::pair<Perturb, const char*> cases[] = {
      {Perturb::kNone, "rendered"},
      {Perturb::kDark, "rendered, 55 % light"},
      {Perturb::kBright, "rendered, 135 % light"},
      {Perturb::kBluishLines, "rendered, bluish lines"},
      {Perturb::kRobots, "rendered, 4 robots"}};
  for (const auto& [p, name] : cases) {
    const Compared c = run(*renderer_, p, seed, 12);
    print((std::string(name) + ": extractor").c_str(), c.fresh);
    print((std::string(name) + ": fixed").c_str(), c.old);
    EXPECT_EQ(c.unusable, 0) << name;
    EXPECT_GT(c.fresh.recall(), 0.9) << name;
    EXPECT_GT(c.fresh.precision(), 0.9) << name;
    // Against the fixed thresholds on the frames they were made for. Measured: recall equal or
    // better except at 135 % light (-3 points), precision 2-3 points lower (cause not found yet,
    // docs/VISION.md). Bounded here so that it cannot get worse unnoticed.
    EXPECT_GE(c.fresh.recall(), c.old.recall() - 0.04) << name;
    EXPECT_GE(c.fresh.precision(), c.old.precision() - 0.035) << name;
  }
}

TEST_F(VisionRendered, RobotOnTheCarpetEndsTheRaysItCovers) {
  const Pose2 pose{375, 275, 40};
  sim::RenderOptions opt = sim::noise_free();
  opt.obstacles = {{Eigen::Vector2d(375 + 100, 275), 20.0}};  // 100 cm along field +x
  const CameraModel& cam = renderer_->camera();
  LineExtractor ex(cam);
  ExtractionReport rep;
  const Scan s = rotate_to_field(ex.extract(renderer_->render(pose, opt), 1, &rep), pose.yaw_deg);
  for (int k = -10; k <= 10; ++k) {
    const double a = deg_to_rad(k);
    const double hit_cm = 100.0 * std::cos(a) - std::sqrt(400.0 - std::pow(100.0 * std::sin(a), 2));
    EXPECT_NEAR(s.ray_end_px[static_cast<std::size_t>((k + 360) % 360)],
                cam.radius_px_at_ground(hit_cm), 2.5)
        << k;
  }
  EXPECT_LT(s.radii_px[0], s.ray_end_px[0]);  // the centre circle before it is kept
  ASSERT_EQ(rep.obstacles.size(), 1u);
  EXPECT_GE(rep.rays_ended_at_obstacle, 19);
}

TEST_F(VisionRendered, ThinLineBetweenIntegerSamplesIsFound) {
  // A 1 px diagonal line drawn on a plain carpet: every ray crossing it must see it, whatever
  // the angle (a nearest-pixel walk at integer radii jumps over it on diagonal rays).
  const CameraModel& cam = renderer_->camera();
  cv::Mat img(cam.height_px, cam.width_px, CV_8UC3, cv::Scalar(60, 140, 40));  // green carpet
  const cv::Point2d c(cam.center_px.x(), cam.center_px.y());
  // The line x + y = const at 120 px from the centre (perpendicular to the 45 deg diagonal).
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u)
      if (static_cast<int>(std::lround((u - c.x) - (v - c.y))) == 170)
        img.at<cv::Vec3b>(v, u) = cv::Vec3b(200, 200, 200);
  CameraModel no_mast = cam;
  no_mast.masts.clear();
  LineExtractor ex(no_mast);
  ExtractionReport rep;
  const BearingScan b = ex.extract(img, 4, &rep);
  int rays = 0, hits = 0;
  for (int j = -40 * 4; j <= 40 * 4;
       ++j) {  // bearings within 40 deg of the line's normal (+45 deg image angle)
    const int ray = ((j + 45 * 4) % 1440 + 1440) % 1440;
    const double phi = deg_to_rad(j / 4.0);
    const double r = 170.0 / std::sqrt(2.0) / std::cos(phi);
    if (r > cam.view_radius_px() - 2) continue;
    ++rays;
    bool hit = false;
    for (int n = 0; n < kCrossingsPerRay; ++n)
      hit = hit || std::abs(b.radii_px[static_cast<std::size_t>(ray) * 4 + n] - r) <= 1.5;
    hits += hit;
  }
  std::printf("thin diagonal line: found on %d of %d rays\n", hits, rays);
  EXPECT_EQ(hits, rays);
}

// ---------------------------------------------------------------------------------------------
// No measurement.

TEST(VisionNoMeasurement, BlackFrameAndWallsOnlyAreNotUsable) {
  const CameraModel cam = load_camera("default");
  LineExtractor ex(cam);
  ExtractionReport rep;
  (void)ex.extract(cv::Mat(cam.height_px, cam.width_px, CV_8UC3, cv::Scalar::all(0)), 4, &rep);
  std::printf("black frame: %s\n", rep.reason.c_str());
  EXPECT_FALSE(rep.usable);
  EXPECT_NE(rep.reason.find("no carpet"), std::string::npos) << rep.reason;
  // Walls only: the real frame's outer ring (walls, furniture, people, black floor) filling the
  // view, as if the robot stood off the field facing a wall.
  const RealFrame f = real_frame();
  ASSERT_FALSE(f.image.empty());
  cv::Mat walls = f.image.clone();
  const cv::Point2d c(f.camera.center_px.x(), f.camera.center_px.y());
  for (int v = 0; v < walls.rows; ++v)
    for (int u = 0; u < walls.cols; ++u) {
      const double du = u - c.x, dv = v - c.y, r = std::hypot(du, dv);
      if (r >= 180.0) continue;
      // The ring 180..210 px (beyond the carpet all round) repeated into the inner disc.
      const double rr = 180.0 + std::fmod(180.0 - r, 30.0);
      const int su = static_cast<int>(std::lround(c.x + du / std::max(r, 1.0) * rr)),
                sv = static_cast<int>(std::lround(c.y + dv / std::max(r, 1.0) * rr));
      walls.at<cv::Vec3b>(v, u) = f.image.at<cv::Vec3b>(std::clamp(sv, 0, walls.rows - 1),
                                                        std::clamp(su, 0, walls.cols - 1));
    }
  LineExtractor ex2(f.camera);
  (void)ex2.extract(walls, 4, &rep);
  std::printf("walls only: %s (carpet %.0f %%, %d rays seen, %d crossings)\n", rep.reason.c_str(),
              100 * rep.carpet_fraction, rep.rays_seen, rep.crossings);
  EXPECT_FALSE(rep.usable);
}

// Frames from which nothing usable comes leave nothing behind, and a jump of the light is read
// again: on realistic frames through a camera with only today's keys (no "vision" block), a white
// frame and a blown-out one first (their "carpet" would be a grey window at the sensor's top that
// held every later frame), then a normal frame, which estimates the green carpet afresh; then the
// exposure jumping from 0.6x to 1.6x between two frames (the followed light is 2.7x too dark).
TEST(VisionNoMeasurement, WhiteAndBlownOutFramesLeaveNoCarpetBehindAndALightJumpIsReadAgain) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::TrueOptics optics;
  const sim::RealisticRenderer rr(field, optics);
  const CameraModel cam = sim::nominal_camera(optics);
  ASSERT_FALSE(cam.vision.carpet_hsv.has_value());
  const Pose2 pose{310.0, 240.0, 35.0};
  auto frame = [&](std::uint64_t seed, double exposure) {
    sim::RenderOptions o = sim::realistic(seed);
    o.realism.look.colour_cast = cv::Vec3f(1.0f, 1.0f, 1.0f) * static_cast<float>(exposure);
    return rr.render(pose, o);
  };
  LineExtractor ex(cam);
  ExtractionReport rep;
  (void)ex.extract(cv::Mat(cam.height_px, cam.width_px, CV_8UC3, cv::Scalar::all(255)), 2, &rep);
  std::printf("white frame: %s\n", rep.reason.c_str());
  EXPECT_FALSE(rep.usable);
  (void)ex.extract(frame(11, 12.0), 2, &rep);
  std::printf("blown out (exposure x12): %s\n", rep.reason.c_str());
  EXPECT_FALSE(rep.usable);
  EXPECT_NE(rep.reason.find("no carpet"), std::string::npos) << rep.reason;
  (void)ex.extract(frame(12, 1.0), 2, &rep);
  std::printf("then a normal frame: %s, carpet hue %.0f +- %.1f, V %.0f..%.0f, %d crossings\n",
              rep.usable ? "usable" : rep.reason.c_str(), rep.carpet.hue, rep.carpet.hue_half_width,
              rep.carpet.val_min, rep.carpet.val_max, rep.crossings);
  EXPECT_TRUE(rep.usable) << rep.reason;
  EXPECT_NEAR(rep.carpet.hue, 70.0, 8.0);  // the renderer's carpet paint, not a grey window
  EXPECT_FALSE(is_grey_carpet(rep.carpet.hue_half_width));
  LineExtractor ex2(cam);  // the light jump on its own
  for (std::uint64_t seed = 13; seed < 16; ++seed) {
    (void)ex2.extract(frame(seed, 0.6), 2, &rep);
    EXPECT_TRUE(rep.usable) << rep.reason;
  }
  (void)ex2.extract(frame(16, 1.6), 2, &rep);
  std::printf("exposure 0.6x -> 1.6x: %s, %d rays seen, %d crossings\n",
              rep.usable ? "usable" : rep.reason.c_str(), rep.rays_seen, rep.crossings);
  EXPECT_TRUE(rep.usable) << rep.reason;
}

TEST(VisionModelConfig, BlockRoundTripsAndBadValuesNameTheField) {
  CameraModel cam = load_camera("default");
  cam.vision.carpet_hsv = CarpetHsv{93.0, 5.0, 110.0, 30.0, 100.0};
  cam.vision.line_contrast = LineContrast{8.0, 9.0};
  cam.vision.extraction.end_run_px = 5;
  const config::Json j = config::write_keys(cam, camera_keys());
  const config::Document d = config::parse_json_text(j.dump(), "cam.json");
  EXPECT_EQ(camera_from_json(d.root()), cam);
  // Absent block: defaults, nothing estimated is written.
  const CameraModel plain = load_camera("default");
  EXPECT_FALSE(plain.vision.carpet_hsv.has_value());
  EXPECT_EQ(plain.vision.extraction, ExtractionParams{});
  auto error_of = [&](const std::string& vision) {
    config::Json jj = config::write_keys(load_camera("default"), camera_keys());
    jj["vision"] = config::Json::parse(vision);
    try {
      (void)camera_from_json(config::parse_json_text(jj.dump(), "cam.json").root());
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(
      error_of(
          R"({"carpet_hsv": {"hue": 200, "hue_half_width": 5, "sat_min": 1, "val_min": 1, "val_max": 9}})")
          .find("cam.json:vision.carpet_hsv.hue: must be an OpenCV hue in [0, 180) (got 200)"),
      std::string::npos)
      << error_of(
             R"({"carpet_hsv": {"hue": 200, "hue_half_width": 5, "sat_min": 1, "val_min": 1, "val_max": 9}})");
  EXPECT_NE(error_of(R"({"extraction": {"end_run_px": 0}})").find("vision.extraction.end_run_px"),
            std::string::npos);
  EXPECT_NE(
      error_of(R"({"carpet_hsv": {"hue": 20}})").find("vision.carpet_hsv.hue_half_width: missing"),
      std::string::npos);
  EXPECT_NE(error_of(R"({"colour": 1})").find("unknown key"), std::string::npos);
  // The vision block does not move the floor: not in the fingerprint.
  EXPECT_EQ(cam.fingerprint(), plain.fingerprint());
}

TEST(VisionModelConfig, RecordingMetaCarriesTheVisionBlock) {
  RecordingMeta meta;
  meta.camera = load_camera("default");
  meta.camera.vision.carpet_hsv = CarpetHsv{93.0, 5.0, 110.0, 30.0, 100.0};
  meta.camera.vision.extraction.min_crossings = 33;
  const auto path = std::filesystem::temp_directory_path() /
                    ("omniloc_vision_meta_" + std::to_string(::getpid()) + ".json");
  write_meta(path, meta);
  const RecordingMeta back = read_meta(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.camera.vision, meta.camera.vision);
}

// A 1280 x 1024 camera whose view ends at 477 px (the default table at twice the scale): the
// feature's one-byte radii are sample indices every view / 254 px, so the whole view is scanned
// (before, such a camera was refused). The extraction's crossings against the geometric scan of
// the same camera, and crossings found beyond the old 254 px end.
TEST(VisionLargeView, ViewBeyond254PxIsScannedToItsEnd) {
  CameraModel big = load_camera("default");
  big.width_px = 1280;
  big.height_px = 1024;
  big.center_px = {640, 512};
  for (auto& m : big.radius_lut) m.radius_px *= 2.0;
  big.body_radius_px *= 2.0;
  big.validate(config::Origin("big.json"));
  ASSERT_NEAR(big.view_radius_px(), 2.0 * load_camera("default").view_radius_px(), 1e-9);
  EXPECT_NEAR(big.scan_step_px(), big.view_radius_px() / 254.0, 1e-12);
  EXPECT_EQ(big.last_scan_sample(), 254);
  EXPECT_EQ(big.first_scan_sample(),
            static_cast<int>(std::ceil(big.body_radius_px / big.scan_step_px())));

  const sim::OmniRenderer r(load_field("fira-robosot"), big);
  const std::uint64_t seed = 4771;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(60, 690), uy(60, 490), uyaw(-180, 180);
  LineExtractor ex(big);
  Agreement all;
  int beyond_old_end = 0;
  for (int i = 0; i < 6; ++i) {
    const Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    sim::RenderOptions opt;
    opt.seed = seed + static_cast<std::uint64_t>(i);
    const cv::Mat img = r.render(pose, opt);
    ExtractionReport rep;
    const Scan got = rotate_to_field(ex.extract(img, 4, &rep), pose.yaw_deg);
    ASSERT_TRUE(rep.usable) << rep.reason;
    all.add(compare(got, expected_scan(r.field(), big, {pose.x_cm, pose.y_cm}), 1.0));
    for (const std::uint8_t k : got.radii_px)
      beyond_old_end += k != kNoCrossing && k * big.scan_step_px() > 254.0;
  }
  print("1280 x 1024, view 477 px", all);
  std::printf("crossings beyond 254 px: %d\n", beyond_old_end);
  EXPECT_GT(all.recall(), 0.9);
  EXPECT_GT(all.precision(), 0.9);
  EXPECT_GT(beyond_old_end, 100);
}

// ---------------------------------------------------------------------------------------------
// The fast walk (LineExtractor::extract) against its reference (extract_reference: every pixel's
// HSV recomputed on every ray): byte-identical scans and identical reports, frame after frame (the
// adaptation state must evolve the same), on rendered frames (plain, dark, bright, robots), the
// real frame with its calibrated camera and extended to the rim (walls, the ball), with the carpet
// estimated and given, at several ray densities.

void expect_same(const BearingScan& a, const ExtractionReport& ra, const BearingScan& b,
                 const ExtractionReport& rb, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(a.rays_per_degree, b.rays_per_degree);
  EXPECT_TRUE(a.radii_px == b.radii_px);
  EXPECT_TRUE(a.ray_end_px == b.ray_end_px);
  EXPECT_EQ(ra.usable, rb.usable);
  EXPECT_EQ(ra.reason, rb.reason);
  EXPECT_EQ(ra.rays, rb.rays);
  EXPECT_EQ(ra.rays_seen, rb.rays_seen);
  EXPECT_EQ(ra.crossings, rb.crossings);
  EXPECT_EQ(ra.rays_ended_at_carpet_edge, rb.rays_ended_at_carpet_edge);
  EXPECT_EQ(ra.rays_ended_at_obstacle, rb.rays_ended_at_obstacle);
  EXPECT_EQ(ra.carpet_fraction, rb.carpet_fraction);  // bit-exact, not near
  EXPECT_TRUE(ra.carpet_end_px == rb.carpet_end_px);
  ASSERT_EQ(ra.obstacles.size(), rb.obstacles.size());
  for (std::size_t k = 0; k < ra.obstacles.size(); ++k) {
    EXPECT_EQ(ra.obstacles[k].first_ray, rb.obstacles[k].first_ray);
    EXPECT_EQ(ra.obstacles[k].last_ray, rb.obstacles[k].last_ray);
    EXPECT_EQ(ra.obstacles[k].near_radius_px, rb.obstacles[k].near_radius_px);
  }
  EXPECT_EQ(ra.carpet, rb.carpet);
  EXPECT_EQ(ra.contrast, rb.contrast);
  EXPECT_EQ(ra.carpet_estimated, rb.carpet_estimated);
}

// Three extractors of one camera, the fast walk (extract), the scalar bin walk and the reference,
// fed the same frames in order.
int expect_same_sequence(const CameraModel& cam, const std::vector<cv::Mat>& frames, int rpd,
                         const std::string& what) {
  LineExtractor fast(cam), bins(cam), ref(cam);
  int crossings = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    ExtractionReport rf, rb, rr;
    const BearingScan bf = fast.extract(frames[i], rpd, &rf);
    const BearingScan bb = detail::LineExtractorAccess::extract_with(
        bins, detail::LineExtractorAccess::Walk::kBinWalk, frames[i], rpd, &rb);
    const BearingScan br = detail::LineExtractorAccess::extract_reference(ref, frames[i], rpd, &rr);
    const std::string at =
        ", frame " + std::to_string(i) + ", " + std::to_string(rpd) + " rays/deg";
    expect_same(bf, rf, br, rr, what + at + ", fast walk");
    expect_same(bb, rb, br, rr, what + at + ", scalar bin walk");
    crossings += rr.crossings;
  }
  return crossings;
}

TEST_F(VisionRendered, FastExtractionEqualsTheReferenceByteForByte) {
  const std::uint64_t seed = 1313;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(60, 690), uy(60, 490), uyaw(-180, 180);
  std::vector<cv::Mat> frames;
  const Perturb kinds[] = {Perturb::kNone,   Perturb::kRobots, Perturb::kDark,
                           Perturb::kBright, Perturb::kRobots, Perturb::kNone};
  for (std::size_t i = 0; i < std::size(kinds); ++i) {
    const Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    sim::RenderOptions opt;
    opt.seed = seed + i;
    opt.gradient_direction_deg = 41.0 * static_cast<double>(i);
    if (kinds[i] == Perturb::kRobots)
      opt.obstacles = sim::random_obstacles(renderer_->field(), pose, 4, opt.seed);
    frames.push_back(perturb(renderer_->render(pose, opt), kinds[i]));
  }
  frames.push_back(cv::Mat(frames[0].size(), CV_8UC3,
                           cv::Scalar(0, 0, 0)));  // no carpet: estimated again next frame
  frames.push_back(frames[1]);
  const CameraModel& cam = renderer_->camera();
  int crossings = 0;
  for (int rpd : {4, 2, 1, 3})
    crossings += expect_same_sequence(cam, frames, rpd, "rendered, carpet estimated");
  // The carpet and the steps given by the camera (no estimation, the value window per sector).
  CameraModel given = cam;
  {
    LineExtractor ex(cam);
    ExtractionReport rep;
    (void)detail::LineExtractorAccess::extract_reference(ex, frames[0], 4, &rep);
    given.vision.carpet_hsv = rep.carpet;
    given.vision.line_contrast = rep.contrast;
  }
  crossings += expect_same_sequence(given, frames, 4, "rendered, carpet given");
  crossings += expect_same_sequence(given, frames, 2, "rendered, carpet given");
  EXPECT_GT(crossings, 1000);  // the frames do have lines in them
}

TEST(VisionRealFrame, FastExtractionEqualsTheReferenceByteForByte) {
  const RealFrame f = real_frame();
  ASSERT_FALSE(f.image.empty());
  const std::vector<cv::Mat> frames{f.image, f.image, f.image};
  EXPECT_GT(expect_same_sequence(f.camera, frames, 4, "real frame"), 100);
  EXPECT_GT(expect_same_sequence(extended_to_rim(f), frames, 4, "real frame extended to the rim"),
            100);
  EXPECT_GT(expect_same_sequence(f.camera, frames, 2, "real frame"), 50);
}

}  // namespace
}  // namespace omniloc
