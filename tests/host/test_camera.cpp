// Camera model: radius table, projection both ways (round trip), yaw offset, mirroring, mask, and
// validation errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <opencv2/core/persistence.hpp>

#include "omniloc/camera.hpp"

namespace omniloc {
namespace {

TEST(Camera, DefaultFileAndTableByHand) {
  const CameraModel cam = load_camera("default");
  EXPECT_EQ(cam.width_px, 640);
  EXPECT_EQ(cam.height_px, 480);
  EXPECT_DOUBLE_EQ(cam.view_radius_px(), 238.7);  // last table row; the image allows 239
  EXPECT_DOUBLE_EQ(cam.min_radius_px(), 31.0);
  EXPECT_NEAR(cam.ground_cm_at_radius(24.7), 20.0, 1e-12);
  EXPECT_NEAR(cam.ground_cm_at_radius(35.9), 30.0, 1e-12);  // halfway between rows 1 and 2
  EXPECT_NEAR(cam.radius_px_at_ground(30.0), 35.9, 1e-12);
  EXPECT_TRUE(std::isnan(cam.ground_cm_at_radius(250.0)));
  EXPECT_TRUE(cam.bearing_hidden(180.0));
  EXPECT_TRUE(cam.bearing_hidden(-176.5));
  EXPECT_FALSE(cam.bearing_hidden(175.0));
}

TEST(Camera, ProjectionByHand) {
  CameraModel cam = load_camera("default");
  // d 100 cm -> r 102.3 px.
  auto px = cam.pixel_of_robot_point({100, 0});
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x(), 422.3, 1e-9);
  EXPECT_NEAR(px->y(), 240.0, 1e-9);
  px = cam.pixel_of_robot_point({0, 100});  // to the left: up in the image
  EXPECT_NEAR(px->x(), 320.0, 1e-9);
  EXPECT_NEAR(px->y(), 137.7, 1e-9);
  cam.mirrored = true;
  px = cam.pixel_of_robot_point({100, 0});
  EXPECT_NEAR(px->x(), 217.7, 1e-9);
  cam.mirrored = false;
  cam.yaw_offset_deg = 90.0;
  px = cam.pixel_of_robot_point({100, 0});
  EXPECT_NEAR(px->x(), 320.0, 1e-9);
  EXPECT_NEAR(px->y(), 137.7, 1e-9);
  EXPECT_FALSE(cam.pixel_of_robot_point({600, 0}));  // beyond the table
}

TEST(Camera, RoundTripPixelToFloorAndBack) {
  for (const bool mirrored : {false, true}) {
    for (const double offset : {0.0, 7.5, -123.0}) {
      CameraModel cam = load_camera("default");
      cam.mirrored = mirrored;
      cam.yaw_offset_deg = offset;
      for (double d = 5.0; d <= 500.0; d += 12.5) {
        for (double b = -180.0; b < 180.0; b += 11.0) {
          const Eigen::Vector2d p(d * std::cos(b * 3.14159265358979 / 180), d * std::sin(b * 3.14159265358979 / 180));
          const auto px = cam.pixel_of_robot_point(p);
          ASSERT_TRUE(px);
          const auto back = cam.robot_point_of_pixel(*px);
          ASSERT_TRUE(back);
          EXPECT_NEAR((*back - p).norm(), 0.0, 1e-9) << "d " << d << " b " << b;
        }
      }
    }
  }
}

class CameraJson : public ::testing::Test {
 protected:
  CameraModel parse(const std::string& body) {
    path_ = (std::filesystem::temp_directory_path() / ("omniloc_cam_" + std::to_string(::getpid()) + ".json")).string();
    std::ofstream(path_) << body;
    cv::FileStorage fs(path_, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON);
    return camera_from_json(fs["camera"], "meta.json: camera");
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::string path_;
};

TEST_F(CameraJson, ReadsTheMetaJsonCameraBlock) {
  const CameraModel cam = parse(R"({"camera": {"width": 640, "height": 480, "center_px": [321.5, 238],
      "radius_lut": [[0, 0], [100, 100], [230, 500]], "yaw_offset_deg": -2.5, "mirrored": true}})");
  EXPECT_DOUBLE_EQ(cam.center_px.x(), 321.5);
  EXPECT_DOUBLE_EQ(cam.yaw_offset_deg, -2.5);
  EXPECT_TRUE(cam.mirrored);
  EXPECT_TRUE(cam.masts.empty());
  EXPECT_DOUBLE_EQ(cam.ground_cm_at_radius(165.0), 300.0);
  EXPECT_DOUBLE_EQ(cam.view_radius_px(), 230.0);
}

TEST_F(CameraJson, RejectsBadInputWithContext) {
  auto expect_error = [&](const std::string& body, const std::string& what) {
    try {
      (void)parse(body);
      FAIL() << "no error for " << what;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("meta.json: camera"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_error(R"({"camera": {"width": 640, "height": 480, "center_px": [320, 240],
      "radius_lut": [[0, 0], [100, 100], [90, 200]], "yaw_offset_deg": 0, "mirrored": false}})", "row 2");
  expect_error(R"({"camera": {"width": 640, "height": 480, "center_px": [700, 240],
      "radius_lut": [[0, 0], [100, 100]], "yaw_offset_deg": 0, "mirrored": false}})", "center_px");
  expect_error(R"({"camera": {"width": 640, "height": 480, "center_px": [320, 240],
      "radius_lut": [[0, 0], [100, 100]], "yaw_offset_deg": 0}})", "mirrored");
  expect_error(R"({"camera": {"width": 640, "height": 480, "center_px": [320, 240],
      "radius_lut": [[0, 0]], "yaw_offset_deg": 0, "mirrored": false}})", "radius_lut");
  expect_error(R"({"camera": {"width": 640, "height": 480, "center_px": [320, 240],
      "radius_lut": [[0, 0], [100, 100]], "yaw_offset_deg": 0, "mirrored": false,
      "mask": {"body_radius_px": 120}}})", "no visible floor");
}

}  // namespace
}  // namespace omniloc
