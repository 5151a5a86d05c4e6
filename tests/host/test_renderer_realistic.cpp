// Realistic renderer (issue 13 item 6): a frame through a TRUE hyperbolic-mirror camera, off
// centre and tilted, that is not the database's CameraModel. Checked against the optics' own
// formula (hand-computed values), by where field points land in a rendered frame, and by the
// scene's parts (rods, robots, goals, JPEG). Also the image analysis on the two RoboCup Junior
// frames of another venue and camera (tests/data/, MPL-2.0, see tests/data/README.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc/calibration.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/field.hpp"
#include "omniloc_sim/renderer.hpp"
#include "omniloc_sim/venue.hpp"
#include "short_mode.hpp"
#include "test_data_path.hpp"

namespace omniloc {
namespace {

using test::test_data;

cv::Vec3b hsv_at(const cv::Mat& bgr, const Eigen::Vector2d& px) {
  cv::Mat one(1, 1, CV_8UC3,
              bgr.at<cv::Vec3b>(static_cast<int>(std::lround(px.y())),
                                static_cast<int>(std::lround(px.x()))));
  cv::Mat hsv;
  cv::cvtColor(one, hsv, cv::COLOR_BGR2HSV);
  return hsv.at<cv::Vec3b>(0, 0);
}

// Realistic options without the random parts that would hide what a test looks at.
sim::RenderOptions clean(std::uint64_t seed) {
  sim::RenderOptions o = sim::realistic(seed);
  o.noise_sigma = 0.0;
  o.realism.jpeg_quality = 0;
  o.realism.robots = 0;
  o.realism.ball = false;
  return o;
}

TEST(TrueOptics, RadialMappingIsTheHyperbolicFormula) {
  sim::TrueOptics o;
  o.focal_px = 180.0;
  o.xi = 0.8;
  o.viewpoint_height_cm = 60.0;
  o.tilt_deg = 0.0;
  // By hand: r(100) = 180 * 100 / (60 + 0.8 sqrt(100^2 + 60^2)) = 18000 / 153.2952 = 117.421 px.
  EXPECT_NEAR(o.radius_px_at_ground(100.0), 117.421, 1e-3);
  EXPECT_NEAR(o.ground_cm_at_radius(117.421), 100.0, 1e-2);
  EXPECT_NEAR(o.ground_cm_at_radius(o.focal_px / o.xi - 1e-6) > 1e4, true,
              0);                                                           // towards the horizon
  EXPECT_TRUE(std::isnan(o.ground_cm_at_radius(o.focal_px / o.xi + 1.0)));  // above it
  // Untilted: a floor point projects at the formula's radius and at image angle bearing + yaw
  // offset.
  for (double b : {0.0, 77.0, 200.0}) {
    const Eigen::Vector3d p(250.0 * std::cos(deg_to_rad(b)), 250.0 * std::sin(deg_to_rad(b)), 0.0);
    const Eigen::Vector2d px = *o.pixel_of_robot_point(p);
    const Eigen::Vector2d d = px - o.centre_px;
    EXPECT_NEAR(d.norm(), o.radius_px_at_ground(250.0), 1e-9);
    EXPECT_NEAR(angle_diff_deg(rad_to_deg(std::atan2(-d.y(), d.x())), b + o.yaw_offset_deg), 0.0,
                1e-9);
    const Eigen::Vector3d ray = o.ray_of_pixel(px);
    EXPECT_NEAR((ray - Eigen::Vector3d(p.x(), p.y(), 60.0).normalized()).norm(), 0.0, 1e-9);
  }
}

TEST(TrueOptics, TiltMakesTheMappingDependOnBearingAndNominalCameraIgnoresIt) {
  const sim::TrueOptics o;  // the default: 1.5 deg tilt
  ASSERT_GT(o.tilt_deg, 1.0);
  double r_min = 1e9, r_max = 0.0;
  for (int b = 0; b < 360; b += 5) {
    const Eigen::Vector3d p(300.0 * std::cos(deg_to_rad(b)), 300.0 * std::sin(deg_to_rad(b)), 0.0);
    const double r = (*o.pixel_of_robot_point(p) - o.centre_px).norm();
    r_min = std::min(r_min, r);
    r_max = std::max(r_max, r);
    EXPECT_NEAR((o.ray_of_pixel(*o.pixel_of_robot_point(p)) -
                 Eigen::Vector3d(p.x(), p.y(), 60.0).normalized())
                    .norm(),
                0.0, 1e-9);
  }
  std::printf("300 cm away: radius %.2f..%.2f px round the tilted mirror (untilted %.2f)\n", r_min,
              r_max, o.radius_px_at_ground(300.0));
  EXPECT_GT(r_max - r_min, 2.0);
  const CameraModel cam = sim::nominal_camera(o);
  EXPECT_NO_THROW(cam.validate(config::Origin("nominal")));
  EXPECT_EQ(cam.center_px, o.centre_px);
  EXPECT_TRUE(cam.masts.empty());  // the rods are for the calibration to find
  EXPECT_NEAR(cam.ground_cm_at_radius(o.radius_px_at_ground(150.0)), 150.0, 1.0);
}

TEST(RealisticRenderer, FieldPointsLandWhereTheTrueOpticsProjectThem) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::TrueOptics o;
  const sim::RealisticRenderer rr(field, o);
  const Pose2 pose{300.0, 220.0, 25.0};
  const cv::Mat img = rr.render(pose, clean(4));
  // Along the centre line (x 375) and the halfway to the far touch line: the line, and 25 cm off it
  // the carpet.
  int lines = 0, carpets = 0;
  for (double y = 120.0; y <= 430.0; y += 10.0) {
    for (const auto& [x, white] : {std::pair{375.0, true}, std::pair{400.0, false}}) {
      const Eigen::Vector2d rel = Eigen::Vector2d(x - pose.x_cm, y - pose.y_cm);
      const double c = std::cos(deg_to_rad(-pose.yaw_deg)), s = std::sin(deg_to_rad(-pose.yaw_deg));
      const Eigen::Vector3d robot(c * rel.x() - s * rel.y(), s * rel.x() + c * rel.y(), 0.0);
      if (robot.head<2>().norm() > 170.0)
        continue;  // near enough that even a thin line covers a pixel
      // Not where the centre circle (r 60) crosses, nor under a rod.
      if (std::abs(Eigen::Vector2d(x - 375.0, y - 275.0).norm() - 60.0) < 15.0) continue;
      const Eigen::Vector2d px = *o.pixel_of_robot_point(robot);
      bool rod = false;
      for (const auto& r : o.rods)
        rod = rod || std::abs(angle_diff_deg(
                         rad_to_deg(std::atan2(o.centre_px.y() - px.y(), px.x() - o.centre_px.x())),
                         r.image_angle_deg)) < 4.0;
      if (rod) continue;
      const cv::Vec3b p = hsv_at(img, px);
      if (white) {
        EXPECT_GT(p[2], 150) << y;
        EXPECT_LT(p[1], 70) << y;
        ++lines;
      } else {
        EXPECT_GT(p[1], 100) << y;      // carpet: saturated green
        EXPECT_NEAR(p[0], 70, 8) << y;  // the carpet paint BGR (70, 140, 35): hue 140 deg
        ++carpets;
      }
    }
  }
  EXPECT_GT(lines, 10);
  EXPECT_GT(carpets, 10);
}

TEST(RealisticRenderer, RodsAreDarkAndNotInTheNominalMask) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::TrueOptics o;
  const cv::Mat img = sim::RealisticRenderer(field, o).render({375.0, 275.0, 0.0}, clean(5));
  for (const auto& rod : o.rods) {
    for (double r = 60.0; r < o.mirror_radius_px - 5.0; r += 20.0) {
      const Eigen::Vector2d px =
          o.centre_px + r * Eigen::Vector2d(std::cos(deg_to_rad(rod.image_angle_deg)),
                                            -std::sin(deg_to_rad(rod.image_angle_deg)));
      EXPECT_LT(hsv_at(img, px)[2], 50) << rod.image_angle_deg << " at " << r;
    }
  }
  EXPECT_TRUE(sim::nominal_camera(o).masts.empty());
}

TEST(RealisticRenderer, RobotsHideWhatIsBehindThemAndGoalsArePainted) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::TrueOptics o;
  const sim::RealisticRenderer rr(field, o);
  const Pose2 pose{375.0, 275.0, 0.0};
  sim::RenderOptions opt = clean(6);
  opt.obstacles = {{{375.0 + 90.0, 275.0}, 22.0}};  // in front, on the line to the x = max goal
  const cv::Mat img = rr.render(pose, opt);
  // The centre circle's line 60 cm ahead is seen; the penalty area line 225 cm ahead is behind the
  // robot.
  EXPECT_GT(hsv_at(img, *o.pixel_of_robot_point({60.0, 0.0, 0.0}))[2], 150);
  EXPECT_LT(hsv_at(img, *o.pixel_of_robot_point({225.0, 0.0, 0.0}))[2], 60);
  // Goals: blue at x = max (the preset's choice for a field that does not say), yellow at x = min,
  // seen 20 cm up their back walls (the side seen past the robot: 40 cm to the side of the axis).
  const cv::Mat open = rr.render(pose, clean(6));
  const cv::Vec3b blue = hsv_at(open, *o.pixel_of_robot_point({375.0 + 30.0, 30.0, 20.0}));
  const cv::Vec3b yellow = hsv_at(open, *o.pixel_of_robot_point({-375.0 - 30.0, 30.0, 20.0}));
  std::printf("goal pixels: blue HSV (%d %d %d), yellow HSV (%d %d %d)\n", blue[0], blue[1],
              blue[2], yellow[0], yellow[1], yellow[2]);
  EXPECT_NEAR(blue[0], 109, 8);
  EXPECT_NEAR(yellow[0], 26, 8);
  EXPECT_GT(blue[1], 120);
  EXPECT_GT(yellow[1], 120);
}

TEST(RealisticRenderer, JpegIsTheLastStepAndTheDefaultRendererIsUnchanged) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::RealisticRenderer rr(field, sim::TrueOptics{});
  sim::RenderOptions with = sim::realistic(7), without = with;
  without.realism.jpeg_quality = 0;
  const cv::Mat a = rr.render({200.0, 300.0, 70.0}, with),
                b = rr.render({200.0, 300.0, 70.0}, without);
  std::vector<std::uint8_t> buf;
  cv::imencode(".jpg", b, buf, {cv::IMWRITE_JPEG_QUALITY, 70});
  const cv::Mat b70 = cv::imdecode(buf, cv::IMREAD_COLOR);
  EXPECT_EQ(cv::norm(a, b70, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, b, cv::NORM_L1), 0.0);
  // The idealised renderer refuses realistic options (it has no true optics) ...
  const sim::OmniRenderer plain(field, load_camera("default"));
  EXPECT_THROW((void)plain.render({375.0, 275.0, 0.0}, with), std::invalid_argument);
  // ... and its default frame is what it was: a hand check of three pixels of the noise-free image.
  const cv::Mat ideal = plain.render({375.0, 275.0, 0.0}, sim::noise_free());
  EXPECT_EQ(ideal.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));                // beyond the mirror
  EXPECT_EQ(ideal.at<cv::Vec3b>(240, 320), cv::Vec3b(60, 55, 55));         // the body
  EXPECT_EQ(ideal.at<cv::Vec3b>(240, 320 + 100), cv::Vec3b(45, 140, 40));  // carpet
}

// A seed names one scene and one venue, whichever compiler built the simulator: draws that were
// arguments of one call (whose order C++ leaves open) once gave clang another scene than gcc for
// the same seed. The values below are the gcc build's, the scenes every test was written on.
TEST(RealisticRenderer, ASeedNamesTheSameSceneWhateverTheCompiler) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::Scene sc = sim::realistic_scene(field, {348.0, 392.0, 324.0}, sim::realistic(1404));
  ASSERT_EQ(sc.columns.size(), 15u);  // 3 robots, the ball, 6 people, 5 pieces of furniture
  const sim::Column& person = sc.columns[4];
  EXPECT_NEAR(person.position_cm.x(), 193.001037, 1e-4);
  EXPECT_NEAR(person.position_cm.y(), 577.828581, 1e-4);
  EXPECT_NEAR(person.top_colour[0], 148.4398, 1e-3);  // the shirt, blue
  EXPECT_NEAR(person.top_colour[2], 137.3250, 1e-3);  // red
  const sim::SceneLook look = sim::sample_venue(sim::venue_seed(1, 0)).render.realism.look;
  EXPECT_NEAR(look.carpet[0], 34.8932, 1e-3);
  EXPECT_NEAR(look.carpet[2], 21.5294, 1e-3);
  EXPECT_NEAR(look.colour_cast[0], 1.12538, 1e-5);
  EXPECT_NEAR(look.colour_cast[2], 0.95943, 1e-5);
}

// The image analysis on realistic frames at spread poses: the rim (where the true optics put the
// mirror's edge), the rods, line pixels, on 40 seeded frames (12 in the short mode), of which at
// least 95 % must be right. Tall robots, dark walls and textured rooms at the rim once made the rim
// finder take a large circle along one arc of the rim or the centre circle (35 of these 40 right;
// 251 of 300 on seeds 1400-1699, 296 of 300 now); the frame of seed 1404 was one on clang's scene.
TEST(RealisticRenderer, AnalysisFindsTheTrueRimOnSpreadPoses) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::TrueOptics o;
  const sim::RealisticRenderer rr(field, o);
  const int n = test::full_or_short(40, 12, "frames");
  int right = 0;
  for (std::uint64_t seed = 1400; seed < 1400 + static_cast<std::uint64_t>(n); ++seed) {
    const Pose2 pose{100.0 + static_cast<double>((seed * 37) % 550),
                     80.0 + static_cast<double>((seed * 53) % 390),
                     static_cast<double>((seed * 71) % 360)};
    std::printf("seed %llu at (%.0f, %.0f, %.0f): ", static_cast<unsigned long long>(seed),
                pose.x_cm, pose.y_cm, pose.yaw_deg);
    try {
      const FrameAnalysis a = analyse_frame(rr.render(pose, sim::realistic(seed)), "realistic");
      const double off_px = (a.rim.centre_px - o.centre_px).norm();
      const double dr_px = a.rim.radius_px - o.mirror_radius_px;
      const bool ok = off_px < 1.5 && std::abs(dr_px) < 1.5 &&
                      a.masts_image.size() >= o.rods.size() && a.line_pixels.size() > 2000u;
      std::printf("rim %.1f px off, radius %+.1f px, %zu masts, %zu line pixels%s\n", off_px, dr_px,
                  a.masts_image.size(), a.line_pixels.size(), ok ? "" : ": WRONG");
      right += ok ? 1 : 0;
    } catch (const std::runtime_error& e) {
      std::printf("refused: %s\n", e.what());
    }
  }
  std::printf("%d of %d frames right\n", right, n);
  EXPECT_GE(right, static_cast<int>(std::ceil(0.95 * n)));
}

// --- the image analysis on another venue's frames
// ---------------------------------------------------

// Both frames show the two goals (frame9 the yellow one large and the blue one far off).
class RcjFrames : public ::testing::TestWithParam<const char*> {};

TEST_P(RcjFrames, AnalysisFindsRimCarpetLinesAndGoals) {
  const auto path = test_data(GetParam());
  ASSERT_FALSE(path.empty()) << GetParam();
  const cv::Mat img = cv::imread(path.string(), cv::IMREAD_COLOR);
  ASSERT_EQ(img.cols, 791);
  const FrameAnalysis a = analyse_frame(img, GetParam());
  const GoalColours g = measure_goal_colours(img, a);
  std::printf(
      "%s: rim (%.1f, %.1f) r %.1f on %d rays; carpet hue %.0f +- %.0f S >= %.0f; %zu line pixels; "
      "body %.1f, view %.1f px; "
      "%zu masts; blue %d px, yellow %d px\n",
      GetParam(), a.rim.centre_px.x(), a.rim.centre_px.y(), a.rim.radius_px, a.rim.rays_on_circle,
      a.carpet.hue, a.carpet.hue_half_width, a.carpet.sat_min, a.line_pixels.size(),
      a.body_radius_px, a.view_radius_px, a.masts_image.size(), g.blue ? g.blue->pixels : 0,
      g.yellow ? g.yellow->pixels : 0);
  // The frames are cropped to the mirror circle: the rim is about half the short side.
  EXPECT_NEAR(a.rim.radius_px, 0.5 * std::min(img.cols, img.rows), 0.12 * img.rows);
  EXPECT_NEAR(a.carpet.hue, 60, 20);  // green (OpenCV hue 60 = 120 deg)
  EXPECT_GT(a.line_pixels.size(), 500u);
  ASSERT_TRUE(g.blue.has_value());
  ASSERT_TRUE(g.yellow.has_value());
  EXPECT_NEAR(g.blue->colour.hue, 110, 15);
  EXPECT_NEAR(g.yellow->colour.hue, 28, 12);
}

INSTANTIATE_TEST_SUITE_P(Rcj, RcjFrames,
                         ::testing::Values("rcj-omicam-goals-frame9.jpg", "rcj-omicam-frame6.jpg"),
                         [](const auto& info) {
                           return info.index == 0 ? std::string("goals_frame9")
                                                  : std::string("frame6");
                         });

}  // namespace
}  // namespace omniloc
