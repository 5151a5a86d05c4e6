// Harness: the feature-database reader (load_feature_db: the file checks, the checksum, the
// fingerprints, the grid check) and a search on what it accepts, for the 40 x 30 cm field of
// tests/fuzz/feature_db_field.json and common/cameras/default.json (databases of a few kB; its grid
// has 1 x 1 points at 30 cm and 2 x 1 at 20 cm, which the reader must refuse).
//
// Input: byte 0 is the mode, the rest is the file.
//   bit 0   fix-up: before writing, overwrite the two fingerprints with the field's and the
//           camera's and recompute the trailing FNV-1a 64 checksum (when the file holds a header
//           and a checksum), so that mutations of the grid reach the grid check instead of stopping
//           at the checksum
//   bit 1   refinement after the searches: kRayCast (else kInterpolate)
//   bits 2-3 local search range: 0, 10, 20 or 30 cm
//   bits 4-7 which cell's own entry is searched for (modulo the cell count)
// Expected errors: std::runtime_error naming the path. Besides, the harness reads the file itself
// (the layout of docs/VISION.md "Database", its own FNV-1a and its own statement of the grid the
// builder lays over the carpet) and checks that the reader accepts exactly what that reading says
// is valid (inputs within 1e-7 of a tolerance edge may go either way), that an accepted database
// holds the header's grid and the file's payload, and that searches on it end at a grid point of
// the database with a finite position near it (a global search for a cell's own entry finds error
// 0).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_common.hpp"
#include "omniloc/camera.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/matcher.hpp"

#ifndef OMNILOC_FUZZ_SOURCE_DIR
#error "OMNILOC_FUZZ_SOURCE_DIR (the source tree, for the field and camera files) must be defined"
#endif

namespace {

using omniloc::fuzz::fuzz_check;

// docs/VISION.md "Database": 88-byte header, payload nx ny x 1440, FNV-1a 64 of everything before
// it.
constexpr std::size_t kHeaderBytes = 88;
constexpr std::size_t kEntryBytes = 360 * 4;

template <class T>
T read_at(std::string_view bytes, std::size_t offset) {
  T v{};
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

enum class Verdict { kRefuse, kAccept, kEither };

struct Reading {
  Verdict verdict = Verdict::kRefuse;
  std::int32_t nx = 0, ny = 0;
  double x0 = 0, y0 = 0, step = 0;
};

/// Points of a grid of `step` centred on a carpet side of `total` cm: the most n with n step <=
/// total, a side short of a whole multiple by less than 1e-9 steps counting as the multiple (the
/// builder's cell centres step/2 .. total - step/2 when the side is a whole multiple). `near_edge`
/// is set when total / step lies within 1e-11 of that tolerance's edge.
long long points_on(double total, double step, bool& near_edge) {
  const double q = total / step;
  near_edge = near_edge || std::abs(q + 1e-9 - std::round(q + 1e-9)) < 1e-11;
  long long n = 0;
  while ((static_cast<double>(n) + 1.0) * step <= total + 1e-9 * step && n < 1000000) ++n;
  return n;
}

/// What a reading of the format says about the file.
Reading read_independently(std::string_view f, const omniloc::FieldGeometry& field,
                           std::uint64_t field_fp, std::uint64_t camera_fp) {
  Reading r;
  if (f.size() < kHeaderBytes) return r;
  if (std::memcmp(f.data(), "OMNIFDB\0", 8) != 0) return r;
  if (read_at<std::uint32_t>(f, 8) != 2 || read_at<std::uint32_t>(f, 12) != kHeaderBytes) return r;
  r.nx = read_at<std::int32_t>(f, 16);
  r.ny = read_at<std::int32_t>(f, 20);
  r.x0 = read_at<double>(f, 24);
  r.y0 = read_at<double>(f, 32);
  r.step = read_at<double>(f, 40);
  if (read_at<std::uint32_t>(f, 48) != 360 || read_at<std::uint32_t>(f, 52) != 4) return r;
  if (r.nx <= 0 || r.ny <= 0) return r;
  const std::uint64_t payload = read_at<std::uint64_t>(f, 72);
  const unsigned long long cells =
      static_cast<unsigned long long>(r.nx) * static_cast<unsigned long long>(r.ny);
  if (payload != cells * kEntryBytes) return r;
  if (f.size() != kHeaderBytes + payload + 8) return r;
  if (read_at<std::uint64_t>(f, kHeaderBytes + payload) !=
      fnv1a64(f.substr(0, kHeaderBytes + payload)))
    return r;
  if (read_at<std::uint64_t>(f, 56) != field_fp || read_at<std::uint64_t>(f, 64) != camera_fp)
    return r;
  // The default camera's view (under 254 px) is sampled every pixel.
  if (read_at<double>(f, 80) != 1.0) return r;
  if (!std::isfinite(r.step) || !std::isfinite(r.x0) || !std::isfinite(r.y0) || r.step < 1.0 ||
      r.step > 100.0)
    return r;
  if (r.nx < 2 || r.ny < 2) return r;  // one point along a side cannot localise along it
  bool near_edge = false;
  const long long nx = points_on(field.total_x_cm(), r.step, near_edge);
  const long long ny = points_on(field.total_y_cm(), r.step, near_edge);
  // Centred: the same margin before the first point and after the last one.
  const double x0 = (field.total_x_cm() - static_cast<double>(nx - 1) * r.step) / 2.0;
  const double y0 = (field.total_y_cm() - static_cast<double>(ny - 1) * r.step) / 2.0;
  const double dx = std::abs(x0 - r.x0), dy = std::abs(y0 - r.y0);
  near_edge = near_edge || std::abs(dx - 1e-6) < 1e-7 || std::abs(dy - 1e-6) < 1e-7;
  const bool valid = nx == r.nx && ny == r.ny && dx <= 1e-6 && dy <= 1e-6;
  r.verdict = near_edge ? Verdict::kEither : (valid ? Verdict::kAccept : Verdict::kRefuse);
  return r;
}

struct Fixture {
  omniloc::FieldGeometry field =
      omniloc::load_field(OMNILOC_FUZZ_SOURCE_DIR "/tests/fuzz/feature_db_field.json");
  omniloc::CameraModel camera =
      omniloc::load_camera(OMNILOC_FUZZ_SOURCE_DIR "/common/cameras/default.json");
  std::uint64_t field_fp = field.fingerprint();
  std::uint64_t camera_fp = camera.fingerprint();
};

/// Searches on an accepted database: they must end, at a cell of the grid, with a finite position.
void search(const omniloc::FeatureDb& db, const Fixture& fx, std::uint8_t mode) {
  const int cells = db.grid.cells();
  const int cell = (mode >> 4) % cells;
  omniloc::Scan scan;
  std::memcpy(scan.radii_px.data(), db.cell_features(cell), kEntryBytes);
  scan.ray_end_px.fill(omniloc::kRayToViewEnd);
  bool any_crossing = false;
  for (const std::uint8_t r : scan.radii_px)
    any_crossing = any_crossing || r != omniloc::kNoCrossing;
  omniloc::MatchOptions opt;
  opt.refinement =
      (mode & 2) != 0 ? omniloc::Refinement::kRayCast : omniloc::Refinement::kInterpolate;
  const omniloc::FieldScan fs = omniloc::make_field_scan(scan);
  const double reach =
      opt.refine_reach_cm + db.grid.step_cm;  // interpolation: half a step; ray cast: the reach
  auto check = [&](const omniloc::MatchResult& m, const char* what) {
    if (m.cell < 0) return;  // nothing comparable (no crossing anywhere)
    fuzz_check(m.cell < cells, what);
    const Eigen::Vector2d g = db.grid.position(m.cell);
    fuzz_check(m.grid_position_cm == g, what);
    fuzz_check(std::isfinite(m.position_cm.x()) && std::isfinite(m.position_cm.y()), what);
    fuzz_check((m.position_cm - g).cwiseAbs().maxCoeff() <= reach, what);
  };
  omniloc::MatchResult global = omniloc::global_search(db, fs, opt);
  if (any_crossing) {
    fuzz_check(global.cell >= 0 && global.error == 0.0,
               "a global search for a cell's own entry did not find error 0");
  }
  omniloc::apply_refinement(db, fx.field, fx.camera, fs, global, opt);
  check(global,
        "global search + refinement: not a cell of the grid, or a position not finite or far from "
        "it");
  const double range = 10.0 * ((mode >> 2) & 3);
  omniloc::MatchResult local =
      omniloc::local_search(db, fs, db.grid.position(cells - 1 - cell), range, opt);
  omniloc::apply_refinement(db, fx.field, fx.camera, fs, local, opt);
  check(
      local,
      "local search + refinement: not a cell of the grid, or a position not finite or far from it");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const Fixture fx;
  static const omniloc::fuzz::ScratchFile file("input.db");
  const std::uint8_t mode = data[0];
  std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  if ((mode & 1) != 0 && bytes.size() >= kHeaderBytes + 8) {
    std::memcpy(bytes.data() + 56, &fx.field_fp, 8);
    std::memcpy(bytes.data() + 64, &fx.camera_fp, 8);
    const std::uint64_t sum = fnv1a64(std::string_view(bytes).substr(0, bytes.size() - 8));
    std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
  }
  const std::string path = file.write(bytes).string();
  const Reading expected = read_independently(bytes, fx.field, fx.field_fp, fx.camera_fp);

  fuzz_check(omniloc::is_feature_db_file(path) ==
                 (bytes.size() >= 8 && std::memcmp(bytes.data(), "OMNIFDB\0", 8) == 0),
             "is_feature_db_file disagrees with the magic");
  std::optional<omniloc::FeatureDb> db;
  try {
    db = omniloc::load_feature_db(path, fx.field, fx.camera);
  } catch (const std::runtime_error& e) {
    fuzz_check(std::string_view(e.what()).find(path) != std::string_view::npos,
               "a refusal that does not name the file");
    fuzz_check(expected.verdict != Verdict::kAccept,
               "a valid database (by the format's own reading) was refused");
    return 0;
  }
  fuzz_check(expected.verdict != Verdict::kRefuse,
             "a database the format's reading refuses was accepted");
  const omniloc::GridSpec& g = db->grid;
  fuzz_check(g.nx == expected.nx && g.ny == expected.ny && g.x0_cm == expected.x0 &&
                 g.y0_cm == expected.y0 && g.step_cm == expected.step,
             "the loaded grid is not the header's");
  fuzz_check(std::isfinite(g.x0_cm) && std::isfinite(g.y0_cm) && std::isfinite(g.step_cm) &&
                 g.step_cm >= 1.0,
             "a loaded grid that is not finite");
  // Every point on the carpet.
  const Eigen::Vector2d last = g.position(g.nx - 1, g.ny - 1);
  fuzz_check(g.x0_cm > 0 && g.y0_cm > 0 && last.x() < fx.field.total_x_cm() &&
                 last.y() < fx.field.total_y_cm(),
             "a loaded grid with points off the carpet");
  fuzz_check(db->field_fingerprint == fx.field_fp && db->camera_fingerprint == fx.camera_fp,
             "fingerprints");
  fuzz_check(
      db->features.size() == static_cast<std::size_t>(g.cells()) * kEntryBytes &&
          std::memcmp(db->features.data(), bytes.data() + kHeaderBytes, db->features.size()) == 0,
      "the loaded entries are not the file's payload");
  search(*db, fx, mode);
  return 0;
}
