// Feature database: entries equal an independent ray-caster written here (sampling the field's
// line geometry ray by ray, sharing no code with expected_features or WhiteLineIndex) and the scan
// of a noise-free image rendered at the grid point; the file round-trips; truncated, corrupt,
// foreign or stale files are refused with a clear error.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
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

// ---------------------------------------------------------------------------------------------
// The independent reference: what the database entry means, computed the slow, obvious way.
// For field direction k (degrees, counter-clockwise from +x) walk the integer pixel radii from
// ceil(min_radius_px) to floor(view_radius_px); radius r sees the floor at the ground distance of
// the camera's radius table, linearly interpolated (done here, not by CameraModel); the floor point
// is white when it lies on a line of FieldGeometry (a segment's rectangle with its ends extended
// by half the line width, an arc's ring within its sweep, a disc); a crossing is a white sample
// after at least min_gap_px non-white ones (counted from the first sample); the first four
// crossings are kept, the rest of the four bytes are kNoCrossing.
//
// Tolerance: none on the radii. The library finds the white stretches analytically and takes the
// integer radii inside them; the two agree exactly except where a sample lies on a line's edge to
// within rounding. Such samples are found (|margin| < 1e-6 cm, the margin being how far inside the
// nearest white shape the point lies) and their rays left out of the comparison; the test asserts
// they are rare (< 1 % of rays), so a real error cannot hide there.

struct Shade {
  bool white = false;
  bool on_edge = false;  // within 1e-6 cm of an edge: rounding decides
};

/// How far inside (>= 0) or outside (< 0) of the field's white shapes the point lies, in cm.
double white_margin_cm(const FieldGeometry& f, const Eigen::Vector2d& q) {
  const double hw = f.line_width_cm / 2.0;
  double best = -1e300;
  for (const FieldSegment& s : f.segments) {
    const Eigen::Vector2d ab = s.b_cm - s.a_cm;
    const double len = std::sqrt(ab.x() * ab.x() + ab.y() * ab.y());
    const double ux = ab.x() / len, uy = ab.y() / len;
    const double px = q.x() - s.a_cm.x(), py = q.y() - s.a_cm.y();
    const double along = px * ux + py * uy;
    const double across = ux * py - uy * px;
    best = std::max(best, std::min({hw - std::abs(across), along + hw, len + hw - along}));
  }
  for (const FieldArc& a : f.arcs) {
    const double dx = q.x() - a.centre_cm.x(), dy = q.y() - a.centre_cm.y();
    const double r = std::sqrt(dx * dx + dy * dy);
    double m = hw - std::abs(r - a.radius_cm);
    const double span = a.end_deg - a.start_deg;
    if (span < 360.0) {
      double rel =
          std::fmod(std::atan2(dy, dx) * 180.0 / 3.14159265358979323846 - a.start_deg, 360.0);
      if (rel < 0.0) rel += 360.0;
      const double ang_deg =
          rel <= span ? std::min(rel, span - rel) : -std::min(rel - span, 360.0 - rel);
      m = std::min(m, ang_deg * 3.14159265358979323846 / 180.0 * std::max(r, 1e-9));
    }
    best = std::max(best, m);
  }
  for (const FieldDisc& d : f.discs) best = std::max(best, d.radius_cm - (q - d.centre_cm).norm());
  return best;
}

/// Ground distance (cm) at pixel radius r from the camera's table, linear between rows.
double ground_cm(const CameraModel& cam, double r) {
  const auto& lut = cam.radius_lut;
  for (std::size_t i = 0; i + 1 < lut.size(); ++i) {
    if (r <= lut[i + 1].radius_px || i + 2 == lut.size()) {
      const double f = (r - lut[i].radius_px) / (lut[i + 1].radius_px - lut[i].radius_px);
      return lut[i].ground_cm + f * (lut[i + 1].ground_cm - lut[i].ground_cm);
    }
  }
  return NAN;
}

struct ReferenceRay {
  std::array<std::uint8_t, kCrossingsPerRay> radii{};
  bool on_edge = false;
};

ReferenceRay reference_ray(const FieldGeometry& f, const CameraModel& cam, const Eigen::Vector2d& p,
                           int k) {
  const double a = k * 3.14159265358979323846 / 180.0;
  const Eigen::Vector2d dir(std::cos(a), std::sin(a));
  const int r0 = static_cast<int>(std::ceil(cam.min_radius_px()));
  const int r1 = static_cast<int>(std::floor(cam.view_radius_px()));
  const int min_gap = ScanParams{}.min_gap_px;
  ReferenceRay out;
  out.radii.fill(kNoCrossing);
  int found = 0, gap = 0;
  for (int r = r0; r <= r1; ++r) {
    const double m = white_margin_cm(f, p + ground_cm(cam, r) * dir);
    out.on_edge = out.on_edge || std::abs(m) < 1e-6;
    if (m >= 0.0) {
      if (gap >= min_gap && found < kCrossingsPerRay)
        out.radii[static_cast<std::size_t>(found++)] = static_cast<std::uint8_t>(r);
      gap = 0;
    } else {
      ++gap;
    }
  }
  return out;
}

struct Comparison {
  int rays = 0, on_edge = 0, differing = 0;
};

/// Compares the database entries of `cells` with the reference ray by ray.
Comparison compare_with_reference(const FeatureDb& db, const FieldGeometry& f,
                                  const CameraModel& cam, const std::vector<int>& cells) {
  Comparison c;
  for (const int cell : cells) {
    const Eigen::Vector2d p = db.grid.position(cell);
    const std::uint8_t* entry = db.cell_features(cell);
    for (int k = 0; k < kScanRays; ++k) {
      const ReferenceRay ref = reference_ray(f, cam, p, k);
      ++c.rays;
      if (ref.on_edge) {
        ++c.on_edge;
        continue;
      }
      const bool same =
          std::equal(ref.radii.begin(), ref.radii.end(), entry + k * kCrossingsPerRay);
      if (!same && c.differing++ < 5) {
        ADD_FAILURE() << "cell " << cell << " at (" << p.x() << ", " << p.y() << ") ray " << k
                      << ": database " << int{entry[4 * k]} << " " << int{entry[4 * k + 1]} << " "
                      << int{entry[4 * k + 2]} << " " << int{entry[4 * k + 3]} << ", reference "
                      << int{ref.radii[0]} << " " << int{ref.radii[1]} << " " << int{ref.radii[2]}
                      << " " << int{ref.radii[3]};
      }
    }
  }
  std::printf(
      "%zu cells, %d rays: %d identical, %d left out (a sample on a line edge), %d differing\n",
      cells.size(), c.rays, c.rays - c.on_edge - c.differing, c.on_edge, c.differing);
  return c;
}

class FeatureDbTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    field_ = std::make_unique<FieldGeometry>(load_field("fira-robosot"));
    camera_ = std::make_unique<CameraModel>(load_camera("default"));
    const auto t0 = std::chrono::steady_clock::now();
    int calls = 0, last_done = 0;
    db_ = std::make_unique<FeatureDb>(build_feature_db(
        *field_, *camera_, GridSpec::covering(*field_, 10.0), [&](int done, int total) {
          ++calls;
          EXPECT_GT(done, last_done);
          EXPECT_EQ(total, 75 * 55);
          last_done = done;
        }));
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("full 75 x 55 database: %.0f ms to build (informational), %zu bytes\n", ms,
                db_->bytes_in_memory());
    EXPECT_EQ(calls, 55);
    EXPECT_EQ(last_done, 75 * 55);
  }
  static void TearDownTestSuite() {
    field_.reset();
    camera_.reset();
    db_.reset();
  }
  void SetUp() override {
    path_ = (fs::temp_directory_path() / ("omniloc_db_" + std::to_string(::getpid()) + ".bin"))
                .string();
  }
  void TearDown() override { fs::remove(path_); }

  std::vector<char> read_file() const {
    std::ifstream in(path_, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  void write_file(const std::vector<char>& bytes) const {
    std::ofstream(path_, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  void expect_refused(const std::string& what, const FieldGeometry& field,
                      const CameraModel& camera) const {
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

// Corners, edges, the centre circle, the goal areas and a spread of cells in between.
TEST_F(FeatureDbTest, EntriesMatchAnIndependentRayCaster) {
  std::vector<int> cells = {0, 1, 74, 75 * 54, 75 * 55 - 1, 27 * 75 + 37, 2000, 2062, 3000, 4124};
  for (int cell = 13; cell < db_->grid.cells(); cell += 97) cells.push_back(cell);
  const Comparison c = compare_with_reference(*db_, *field_, *camera_, cells);
  EXPECT_EQ(c.differing, 0);
  EXPECT_LT(c.on_edge, c.rays / 100);
  EXPECT_GT(c.rays, 50 * kScanRays);
}

TEST_F(FeatureDbTest, EntriesMatchNoiseFreeRenderedImages) {
  const sim::OmniRenderer renderer(*field_, *camera_);
  int compared = 0, within = 0;
  for (int cell = 17; cell < db_->grid.cells(); cell += 211) {
    const Eigen::Vector2d p = db_->grid.position(cell);
    const double yaw = static_cast<double>(cell % 360);
    const Scan s =
        scan_image(renderer.render({p.x(), p.y(), yaw}, sim::noise_free()), *camera_, yaw);
    int c = 0, w = 0;
    for (int i = 0; i < kFeatureBytes; ++i) {
      if (s.ray_end_px[static_cast<std::size_t>(i / kCrossingsPerRay)] != kRayToViewEnd) continue;
      ++c;
      w += std::abs(int{s.radii_px[static_cast<std::size_t>(i)]} -
                    int{db_->cell_features(cell)[i]}) <= 1;
    }
    EXPECT_GE(w, c * 90 / 100) << "cell " << cell;
    compared += c;
    within += w;
  }
  std::printf("database vs noise-free images: %.1f %% of %d crossings within 1 px\n",
              100.0 * within / compared, compared);
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
  EXPECT_EQ(back.radius_step_px, 1.0);  // the default camera's view is under 254 px
  EXPECT_EQ(fs::file_size(path_), 88u + 75u * 55u * 1440u + 8u);
}

// The disk filling up, for one scope: a file size limit (RLIMIT_FSIZE, which binds root too) with
// SIGXFSZ ignored, so that write() fails part-way (EFBIG) as on a full disk (ENOSPC).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{bytes, old_.rlim_max};
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit old_{};
  void (*old_handler_)(int) = nullptr;
};

// Files in the database's directory named after it, but for itself: temporaries left behind.
std::vector<std::string> leftovers(const fs::path& path) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(path.parent_path())) {
    const std::string name = e.path().filename().string();
    if (name != path.filename().string() &&
        name.find(path.filename().string()) != std::string::npos)
      found.push_back(name);
  }
  return found;
}

// Issue (hostile input): a full disk while the database was written left a partial file at its
// path, which replay and locate then refused to overwrite ("not overwriting it") until removed by
// hand. Now the write goes to a temporary file beside it, renamed into place when complete: a
// failure part-way leaves the path as it was (an older database, still loading; or nothing) and no
// temporary behind, and the error names the path and the system's error.
TEST_F(FeatureDbTest, AWriteFailingPartWayLeavesThePathAsItWasAndNoTemporary) {
  const FeatureDb older =
      build_feature_db(*field_, *camera_, GridSpec::covering(*field_, 50.0), {}, 1);
  save_feature_db(older, path_);
  const std::vector<char> before = read_file();
  for (const bool existed : {true, false}) {
    if (!existed) fs::remove(path_);
    {
      const FileSizeLimit full(64 << 10);  // the database is 5.9 MB
      try {
        save_feature_db(*db_, path_);
        ADD_FAILURE() << "saved past the file size limit";
      } catch (const std::runtime_error& e) {
        EXPECT_EQ(std::string(e.what()).rfind(path_ + ": ", 0), 0u) << e.what();
        EXPECT_NE(std::string(e.what()).find(std::strerror(EFBIG)), std::string::npos) << e.what();
        std::printf("refused: %s\n", e.what());
      }
    }
    if (existed) {
      EXPECT_EQ(read_file(), before);
      EXPECT_EQ(load_feature_db(path_, *field_, *camera_).grid.nx, older.grid.nx);
    } else {
      EXPECT_FALSE(fs::exists(path_)) << fs::file_size(path_) << " bytes left";
    }
    EXPECT_TRUE(leftovers(path_).empty()) << leftovers(path_).front();
  }
  save_feature_db(*db_, path_);  // the path is not blocked
  EXPECT_EQ(load_feature_db(path_, *field_, *camera_).features, db_->features);
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
  expect_refused("no such file", *field_, *camera_);
}

TEST(FeatureDbSmall, MslFieldBuildsOnACoarseGrid) {
  const FieldGeometry msl = load_field("robocup-msl");
  const CameraModel cam = load_camera("default");
  const FeatureDb db = build_feature_db(msl, cam, GridSpec::covering(msl, 50.0), {}, 1);
  EXPECT_EQ(db.grid.nx, 48);
  EXPECT_EQ(db.grid.ny, 32);
  std::vector<int> cells;
  for (int cell = 0; cell < db.grid.cells(); cell += 37) cells.push_back(cell);
  const Comparison c = compare_with_reference(db, msl, cam, cells);
  EXPECT_EQ(c.differing, 0);
  EXPECT_LT(c.on_edge, c.rays / 100);
}

/// Rewrites one header field of a saved database and its checksum, so only the field is wrong.
template <class T>
void patch_with_valid_checksum(std::vector<char>& bytes, std::size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof value);
  const std::size_t body = bytes.size() - sizeof(std::uint64_t);
  // FNV-1a 64, written out here as the file format documents it (docs/VISION.md).
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < body; ++i) {
    h ^= static_cast<unsigned char>(bytes[i]);
    h *= 0x100000001b3ULL;
  }
  std::memcpy(bytes.data() + body, &h, sizeof h);
}

// Files whose checksum is valid but whose grid is nonsense for the field (a NaN or shifted origin,
// an infinite or tiny step, a 1 x 1 grid) used to load, and a NaN origin then hung refine_match;
// a directory or a device is refused by name before anything is read.
TEST_F(FeatureDbTest, RefusesAValidChecksumOverANonsenseGridAndFilesThatAreNotFiles) {
  save_feature_db(*db_, path_);
  const std::vector<char> good = read_file();
  // Header offsets: magic 0, version 8, header_bytes 12, nx 16, ny 20, x0 24, y0 32, step 40,
  // payload_bytes 72, radius_step_px 80 (88 bytes).
  struct Case {
    const char* what;
    std::size_t offset;
    double value;
    const char* message;
  };
  const Case cases[] = {
      {"NaN origin", 24, std::nan(""), "corrupt grid"},
      {"infinite step", 40, INFINITY, "corrupt grid"},
      {"tiny step", 40, 1e-300, "corrupt grid"},
      {"shifted origin", 24, 25.0, "is not the grid of field"},
      {"other step", 40, 20.0, "is not the grid of field"},
      {"other radius step", 80, 2.0,
       "radii sampled every 2.000000 px, the camera in use samples every 1.000000 px"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    std::vector<char> bytes = good;
    patch_with_valid_checksum(bytes, c.offset, c.value);
    write_file(bytes);
    expect_refused(c.message, *field_, *camera_);
  }
  // A 1 x 1 grid with a payload of one point and a valid checksum.
  {
    std::vector<char> bytes(good.begin(), good.begin() + 88 + kFeatureBytes);
    bytes.resize(bytes.size() + 8);
    std::int32_t one = 1;
    std::memcpy(bytes.data() + 16, &one, 4);
    std::memcpy(bytes.data() + 20, &one, 4);
    const std::uint64_t payload = kFeatureBytes;
    patch_with_valid_checksum(bytes, 72, payload);  // payload_bytes, before radius_step_px (80)
    write_file(bytes);
    expect_refused("fewer than 2 points along a side", *field_, *camera_);
  }
  // Not files.
  const fs::path dir = fs::path(path_ + ".d");
  fs::create_directories(dir);
  try {
    (void)load_feature_db(dir.string(), *field_, *camera_);
    ADD_FAILURE() << "a directory loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(dir.string() + ": is a directory"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
  try {
    (void)load_feature_db("/dev/zero", *field_, *camera_);
    ADD_FAILURE() << "/dev/zero loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero: not a regular file"), std::string::npos)
        << e.what();
  }
}

// A grid with one point along a side (a step above half the carpet's side) cannot localise along
// it; it used to load when it was the field's own covering grid (found by fuzz_feature_db, issue
// 16; regression input tests/fuzz/regressions/feature_db/). Field: 40 x 30 cm carpet, as the
// harness's.
TEST_F(FeatureDbTest, RefusesAGridWithOnePointAlongASideEvenWhenItIsTheFieldsOwnGrid) {
  FieldSpec spec = field_->spec;
  spec.name = "tiny";
  spec.field_length_cm = 30;
  spec.field_width_cm = 20;
  spec.border_cm = 5;
  spec.line_width_cm = 2;
  spec.centre_circle_radius_cm = 5;
  spec.goal = {8, 4, GoalColour::kUnknown};
  spec.goal_area = {3, 10};
  spec.penalty_area = {6, 14};
  spec.penalty_arc = {0, 0};
  spec.corner_arc_radius_cm = 0;
  spec.marks_from_centre_cm.clear();
  spec.validate("tiny");
  const FieldGeometry tiny = build_field(spec, "tiny");
  struct Case {
    double step_cm;
    int nx, ny;
    bool loads;
  };
  for (const Case& c :
       {Case{30, 1, 1, false}, Case{20, 2, 1, false}, Case{15, 2, 2, true}, Case{10, 4, 3, true}}) {
    SCOPED_TRACE(c.step_cm);
    const GridSpec g = GridSpec::covering(tiny, c.step_cm);
    ASSERT_EQ(g.nx, c.nx);
    ASSERT_EQ(g.ny, c.ny);
    save_feature_db(build_feature_db(tiny, *camera_, g, {}, 1), path_);
    if (c.loads) {
      EXPECT_EQ(load_feature_db(path_, tiny, *camera_).grid.cells(), c.nx * c.ny);
    } else {
      expect_refused("fewer than 2 points along a side", tiny, *camera_);
    }
  }
}

}  // namespace
}  // namespace omniloc
