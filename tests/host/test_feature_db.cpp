// Feature database: entries equal the geometric scan and the scan of a noise-free image rendered
// at the grid point; the file round-trips; truncated, corrupt, foreign or stale files are refused
// with a clear error.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "omniloc/feature_db.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

class FeatureDbTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    field_ = std::make_unique<FieldGeometry>(load_field("fira-robosot"));
    camera_ = std::make_unique<CameraModel>(load_camera("default"));
    const auto t0 = std::chrono::steady_clock::now();
    int calls = 0, last_done = 0;
    db_ = std::make_unique<FeatureDb>(build_feature_db(*field_, *camera_, GridSpec::covering(*field_, 10.0),
                                                       [&](int done, int total) {
                                                         ++calls;
                                                         EXPECT_GT(done, last_done);
                                                         EXPECT_EQ(total, 75 * 55);
                                                         last_done = done;
                                                       }));
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("full 75 x 55 database: %.0f ms to build (informational), %zu bytes\n", ms, db_->bytes_in_memory());
    EXPECT_EQ(calls, 55);
    EXPECT_EQ(last_done, 75 * 55);
  }
  static void TearDownTestSuite() {
    field_.reset();
    camera_.reset();
    db_.reset();
  }
  void SetUp() override {
    path_ = (fs::temp_directory_path() / ("omniloc_db_" + std::to_string(::getpid()) + ".bin")).string();
  }
  void TearDown() override { fs::remove(path_); }

  std::vector<char> read_file() const {
    std::ifstream in(path_, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  void write_file(const std::vector<char>& bytes) const {
    std::ofstream(path_, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  void expect_refused(const std::string& what, const FieldGeometry& field, const CameraModel& camera) const {
    try {
      (void)load_feature_db(path_, field, camera);
      FAIL() << "loaded a database that should be refused (" << what << ")";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path_), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }

  static std::unique_ptr<FieldGeometry> field_;
  static std::unique_ptr<CameraModel> camera_;
  static std::unique_ptr<FeatureDb> db_;
  std::string path_;
};
std::unique_ptr<FieldGeometry> FeatureDbTest::field_;
std::unique_ptr<CameraModel> FeatureDbTest::camera_;
std::unique_ptr<FeatureDb> FeatureDbTest::db_;

TEST_F(FeatureDbTest, GridCoversTheCarpetAtCellCentres) {
  const GridSpec& g = db_->grid;
  EXPECT_EQ(g.nx, 75);
  EXPECT_EQ(g.ny, 55);
  EXPECT_EQ(g.position(0, 0), Eigen::Vector2d(5, 5));
  EXPECT_EQ(g.position(74, 54), Eigen::Vector2d(745, 545));
  EXPECT_EQ(g.position(37, 27), Eigen::Vector2d(375, 275));  // the field centre is a grid point
  EXPECT_EQ(db_->features.size(), 75u * 55u * 1440u);
  const GridSpec coarse = GridSpec::covering(*field_, 20.0);
  EXPECT_EQ(coarse.nx, 37);
  EXPECT_EQ(coarse.ny, 27);
  EXPECT_DOUBLE_EQ(coarse.x0_cm, 15.0);  // (750 - 36 * 20) / 2
  EXPECT_THROW((void)GridSpec::covering(*field_, 0.0), std::invalid_argument);
}

TEST_F(FeatureDbTest, EntriesAreTheGeometricScan) {
  for (const int cell : {0, 1, 74, 2000, 2062, 3000, 4124}) {
    const Scan s = expected_scan(*field_, *camera_, db_->grid.position(cell));
    EXPECT_TRUE(std::equal(s.radii_px.begin(), s.radii_px.end(), db_->cell_features(cell))) << "cell " << cell;
  }
}

TEST_F(FeatureDbTest, EntriesMatchNoiseFreeRenderedImages) {
  const sim::OmniRenderer renderer(*field_, *camera_);
  int compared = 0, within = 0;
  for (int cell = 17; cell < db_->grid.cells(); cell += 211) {
    const Eigen::Vector2d p = db_->grid.position(cell);
    const double yaw = static_cast<double>(cell % 360);
    const Scan s = scan_image(renderer.render({p.x(), p.y(), yaw}, sim::noise_free()), *camera_, yaw);
    int c = 0, w = 0;
    for (int i = 0; i < kFeatureBytes; ++i) {
      if (s.ray_valid[static_cast<std::size_t>(i / kCrossingsPerRay)] == 0) continue;
      ++c;
      w += std::abs(int{s.radii_px[static_cast<std::size_t>(i)]} - int{db_->cell_features(cell)[i]}) <= 1;
    }
    EXPECT_GE(w, c * 90 / 100) << "cell " << cell;
    compared += c;
    within += w;
  }
  std::printf("database vs noise-free images: %.1f %% of %d crossings within 1 px\n", 100.0 * within / compared, compared);
  EXPECT_GE(within, compared * 95 / 100);
}

TEST_F(FeatureDbTest, FileRoundTrip) {
  save_feature_db(*db_, path_);
  const FeatureDb back = load_feature_db(path_, *field_, *camera_);
  EXPECT_EQ(back.grid.nx, db_->grid.nx);
  EXPECT_EQ(back.grid.ny, db_->grid.ny);
  EXPECT_EQ(back.grid.x0_cm, db_->grid.x0_cm);
  EXPECT_EQ(back.grid.step_cm, db_->grid.step_cm);
  EXPECT_EQ(back.features, db_->features);
  EXPECT_EQ(fs::file_size(path_), 80u + 75u * 55u * 1440u + 8u);
}

TEST_F(FeatureDbTest, RefusesTruncatedCorruptAndForeignFiles) {
  save_feature_db(*db_, path_);
  const std::vector<char> good = read_file();

  std::vector<char> bytes(good.begin(), good.end() - 100);
  write_file(bytes);
  expect_refused("truncated", *field_, *camera_);

  bytes.assign(good.begin(), good.begin() + 40);
  write_file(bytes);
  expect_refused("truncated", *field_, *camera_);

  bytes = good;
  bytes[80 + 123456] ^= 0x01;
  write_file(bytes);
  expect_refused("checksum", *field_, *camera_);

  bytes = good;
  bytes[0] = 'X';
  write_file(bytes);
  expect_refused("not an omniloc feature database", *field_, *camera_);

  bytes = good;
  bytes[8] = 9;  // version
  write_file(bytes);
  expect_refused("version 9", *field_, *camera_);

  write_file(good);
  expect_refused("different field geometry", load_field("robocup-msl"), *camera_);
  CameraModel other = *camera_;
  other.radius_lut[5].ground_cm += 1.0;
  expect_refused("different camera", *field_, other);
  // The yaw offset and mirroring do not change the database: it still loads.
  other = *camera_;
  other.yaw_offset_deg = 12.0;
  other.mirrored = true;
  EXPECT_NO_THROW((void)load_feature_db(path_, *field_, other));

  fs::remove(path_);
  expect_refused("cannot open", *field_, *camera_);
}

TEST(FeatureDbSmall, MslFieldBuildsOnACoarseGrid) {
  const FieldGeometry msl = load_field("robocup-msl");
  const CameraModel cam = load_camera("default");
  const FeatureDb db = build_feature_db(msl, cam, GridSpec::covering(msl, 50.0), {}, 1);
  EXPECT_EQ(db.grid.nx, 48);
  EXPECT_EQ(db.grid.ny, 32);
  const Scan s = expected_scan(msl, cam, db.grid.position(100));
  EXPECT_TRUE(std::equal(s.radii_px.begin(), s.radii_px.end(), db.cell_features(100)));
}

}  // namespace
}  // namespace omniloc
