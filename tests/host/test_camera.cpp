// Camera model: radius table, projection both ways (round trip), yaw offset, mirroring, mask, and
// validation errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "config_test_util.hpp"
#include "omniloc/camera.hpp"
#include "omniloc/detail/config_reader.hpp"

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
          const Eigen::Vector2d p(d * std::cos(b * 3.14159265358979 / 180),
                                  d * std::sin(b * 3.14159265358979 / 180));
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

// --- camera files
// ---------------------------------------------------------------------------------

using test::error_of;

const std::vector<std::string> kEveryKey = {"description", "width",      "height",
                                            "center_px",   "radius_lut", "yaw_offset_deg",
                                            "mirrored",    "mask"};

CameraModel parse_block(const std::string& json) {
  return camera_from_json(config::parse_json_text(json, "meta.json").root() / "camera");
}

TEST(CameraFile, ShippedDefaultFileHasEveryKey) {
  const auto json = test::read_json(resolve_data_file("cameras", "default"));
  EXPECT_EQ(test::keys_of(json), kEveryKey);
  EXPECT_EQ(test::keys_of(json["mask"]), (std::vector<std::string>{"body_radius_px", "masts"}));
  // The values, by hand from the file.
  const CameraModel cam = load_camera("default");
  EXPECT_EQ(cam.center_px, Eigen::Vector2d(320, 240));
  EXPECT_EQ(cam.radius_lut.size(), 26u);
  EXPECT_TRUE(cam.radius_lut[1] == (RadiusMark{24.7, 20.0}));
  EXPECT_TRUE(cam.radius_lut[25] == (RadiusMark{238.7, 500.0}));
  EXPECT_EQ(cam.yaw_offset_deg, 0.0);
  EXPECT_FALSE(cam.mirrored);
  EXPECT_EQ(cam.body_radius_px, 31.0);
  ASSERT_EQ(cam.masts.size(), 1u);
  EXPECT_TRUE(cam.masts[0] == (MastSector{180.0, 4.0}));
}

TEST(CameraFile, EveryKeyReachesItsMember) {
  const std::string file = test::write_file("cam.json", R"({"description": "a test camera",
      "width": 800, "height": 600, "center_px": [401.5, 298.25],
      "radius_lut": [[0, 0], [100, 90], [250, 450]], "yaw_offset_deg": -2.5, "mirrored": true,
      "mask": {"body_radius_px": 12.5, "masts": [{"bearing_deg": 90, "half_width_deg": 3}, {"bearing_deg": -45.5, "half_width_deg": 0}]}})")
                               .string();
  const CameraModel cam = load_camera(file);
  EXPECT_EQ(cam.width_px, 800);
  EXPECT_EQ(cam.height_px, 600);
  EXPECT_EQ(cam.center_px, Eigen::Vector2d(401.5, 298.25));
  ASSERT_EQ(cam.radius_lut.size(), 3u);
  EXPECT_TRUE(cam.radius_lut[0] == (RadiusMark{0, 0}));
  EXPECT_TRUE(cam.radius_lut[1] == (RadiusMark{100, 90}));
  EXPECT_TRUE(cam.radius_lut[2] == (RadiusMark{250, 450}));
  EXPECT_EQ(cam.yaw_offset_deg, -2.5);
  EXPECT_TRUE(cam.mirrored);
  EXPECT_EQ(cam.body_radius_px, 12.5);
  ASSERT_EQ(cam.masts.size(), 2u);
  EXPECT_EQ(cam.masts[0].bearing_deg, 90.0);
  EXPECT_EQ(cam.masts[0].half_width_deg, 3.0);
  EXPECT_EQ(cam.masts[1].bearing_deg, -45.5);
  EXPECT_EQ(cam.masts[1].half_width_deg, 0.0);
}

TEST(CameraFile, ReadsTheMetaJsonCameraBlockWithoutAMask) {
  const CameraModel cam =
      parse_block(R"({"camera": {"width": 640, "height": 480, "center_px": [321.5, 238],
      "radius_lut": [[0, 0], [100, 100], [230, 500]], "yaw_offset_deg": -2.5, "mirrored": true}})");
  EXPECT_DOUBLE_EQ(cam.center_px.x(), 321.5);
  EXPECT_DOUBLE_EQ(cam.yaw_offset_deg, -2.5);
  EXPECT_TRUE(cam.mirrored);
  EXPECT_TRUE(cam.masts.empty());
  EXPECT_EQ(cam.body_radius_px, 0.0);
  EXPECT_DOUBLE_EQ(cam.ground_cm_at_radius(165.0), 300.0);
  EXPECT_DOUBLE_EQ(cam.view_radius_px(), 230.0);
}

TEST(CameraFile, RejectsBadInputWithFileAndFieldPath) {
  const std::string v = R"({"width": 640, "height": 480, "center_px": [320, 240],
      "radius_lut": [[0, 0], [100, 100], [200, 200]], "yaw_offset_deg": 0, "mirrored": false,
      "mask": {"body_radius_px": 10, "masts": [{"bearing_deg": 180, "half_width_deg": 4}]}})";
  using test::replaced;
  test::expect_errors(
      [](const std::string& f) { (void)load_camera(f); },
      {
          {replaced(v, "[200, 200]", "[90, 200]"), "radius_lut[2]",
           "strictly increasing in both radius and distance"},
          {replaced(v, "[200, 200]", "[200]"), "radius_lut[2]", "must be an array of 2 elements"},
          {replaced(v, "[320, 240]", "[700, 240]"), "center_px",
           "outside the 640 x 480 image (got [700, 240])"},
          {replaced(v, ", \"mirrored\": false", ""), "mirrored", "missing (required)"},
          {replaced(v, "\"mirrored\": false", "\"mirrored\": 0"), "mirrored",
           "must be true or false, not a number"},
          // Issue 16 item 6: 7 was once taken as true and every frame was then rejected silently.
          {replaced(v, "\"mirrored\": false", "\"mirrored\": 7"), "mirrored",
           "must be true or false, not a number (got 7)"},
          {replaced(v, "\"yaw_offset_deg\": 0", "\"yaw_offset_deg\": 1e9"), "yaw_offset_deg",
           "must be an angle within [-360, 360] degrees (got 1000000000)"},
          {replaced(v, "\"width\": 640", "\"width\": 640.0"), "width", "must be an integer"},
          {replaced(v, "\"width\": 640", "\"width\": 20000"), "width", "1..16384 (got 20000)"},
          {replaced(v, "\"width\": 640", "\"width\": \"640\""), "width",
           "must be an integer, not a string"},
          {replaced(v, "\"yaw_offset_deg\": 0", "\"yaw_offset_deg\": true"), "yaw_offset_deg",
           "not a boolean"},
          {replaced(v, "\"yaw_offset_deg\": 0", "\"yaw_offset_deg\": NaN"), "yaw_offset_deg",
           "not valid JSON"},
          {replaced(v, "\"yaw_offset_deg\": 0", "\"yaw_offset_deg\": -1e400"), "yaw_offset_deg",
           "number out of range"},
          {replaced(v, "[[0, 0], [100, 100], [200, 200]]", "[[0, 0]]"), "radius_lut",
           "at least two"},
          {replaced(v, "\"body_radius_px\": 10", "\"body_radius_px\": 199"), "",
           "no visible floor ring"},
          {replaced(v, "\"half_width_deg\": 4", "\"half_width_deg\": 90"),
           "mask.masts[0].half_width_deg", "must be in [0, 90) (got 90)"},
          {replaced(v, "\"half_width_deg\": 4", "\"half_width\": 4"), "mask.masts[0].half_width",
           "unknown key"},
          {replaced(v, "\"body_radius_px\": 10", "\"body_radius_px\": 10, \"body_radius_px\": 11"),
           "mask.body_radius_px", "duplicate key"},
          {replaced(v, "\"mirrored\": false", "\"mirrored\": false, \"mirror\": true"), "mirror",
           "unknown key"},
      });
}

TEST(CameraFile, MissingFileAndDirectoryAreNamed) {
  EXPECT_EQ(error_of([] { (void)load_camera("/nonexistent/cam.json"); }),
            "/nonexistent/cam.json: no such file");
  const std::string dir = test::temp_dir().string();
  EXPECT_EQ(error_of([&] { (void)load_camera(dir); }), dir + ": is a directory, not a JSON file");
}

}  // namespace
}  // namespace omniloc
