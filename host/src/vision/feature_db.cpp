#include "omniloc/feature_db.hpp"

#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <stdexcept>
#include <string_view>
#include <thread>
#include <vector>

#include "fnv.hpp"
#include "omniloc/detail/file_read.hpp"
#include "omniloc/detail/file_write.hpp"

namespace omniloc {

namespace {

constexpr char kMagic[8] = {'O', 'M', 'N', 'I', 'F', 'D', 'B', '\0'};

// Fixed little-endian header; the payload follows, then an FNV-1a 64 checksum of everything before
// it.
struct Header {
  char magic[8];
  std::uint32_t version;
  std::uint32_t header_bytes;
  std::int32_t nx;
  std::int32_t ny;
  double x0_cm;
  double y0_cm;
  double step_cm;
  std::uint32_t rays;
  std::uint32_t crossings;
  std::uint64_t field_fingerprint;
  std::uint64_t camera_fingerprint;
  std::uint64_t payload_bytes;
  double radius_step_px;  // version 2: px between a ray's samples (CameraModel::scan_step_px)
};
static_assert(std::endian::native == std::endian::little, "the database format is little-endian");

std::string hex(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

}  // namespace

GridSpec GridSpec::covering(const FieldGeometry& field, double step_cm) {
  if (!(step_cm >= 1.0) || step_cm > 100.0) {
    throw std::invalid_argument("grid step must be between 1 and 100 cm, got " +
                                std::to_string(step_cm));
  }
  GridSpec g;
  g.step_cm = step_cm;
  g.nx = static_cast<int>(std::floor(field.total_x_cm() / step_cm + 1e-9));
  g.ny = static_cast<int>(std::floor(field.total_y_cm() / step_cm + 1e-9));
  // Centre the points on the carpet: the leftover is split equally on both sides.
  g.x0_cm = (field.total_x_cm() - (g.nx - 1) * step_cm) / 2.0;
  g.y0_cm = (field.total_y_cm() - (g.ny - 1) * step_cm) / 2.0;
  return g;
}

FeatureDb build_feature_db(const FieldGeometry& field, const CameraModel& camera,
                           const GridSpec& grid, const BuildProgress& progress, unsigned threads) {
  if (grid.nx <= 0 || grid.ny <= 0 || !(grid.step_cm > 0.0))
    throw std::invalid_argument("build_feature_db: empty grid");
  FeatureDb db;
  db.grid = grid;
  db.field_fingerprint = field.fingerprint();
  db.camera_fingerprint = camera.fingerprint();
  db.radius_step_px = camera.scan_step_px();
  db.features.resize(static_cast<std::size_t>(grid.cells()) * kFeatureBytes);
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  std::atomic<int> next_row{0};
  int rows_done = 0;
  std::mutex progress_mutex;
  auto work = [&] {
    std::vector<WhiteInterval> scratch;
    for (int j = next_row++; j < grid.ny; j = next_row++) {
      for (int i = 0; i < grid.nx; ++i) {
        expected_features(
            field, camera, grid.position(i, j),
            db.features.data() + static_cast<std::size_t>(j * grid.nx + i) * kFeatureBytes,
            scratch);
      }
      // Counted under the lock so that reports arrive in increasing order.
      const std::lock_guard lock(progress_mutex);
      const int done = ++rows_done;
      if (progress) progress(done * grid.nx, grid.cells());
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  return db;
}

void save_feature_db(const FeatureDb& db, const std::string& path) {
  Header h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kFeatureDbVersion;
  h.header_bytes = sizeof(Header);
  h.nx = db.grid.nx;
  h.ny = db.grid.ny;
  h.x0_cm = db.grid.x0_cm;
  h.y0_cm = db.grid.y0_cm;
  h.step_cm = db.grid.step_cm;
  h.rays = kScanRays;
  h.crossings = kCrossingsPerRay;
  h.field_fingerprint = db.field_fingerprint;
  h.camera_fingerprint = db.camera_fingerprint;
  h.payload_bytes = db.features.size();
  h.radius_step_px = db.radius_step_px;
  if (db.features.size() != static_cast<std::size_t>(db.grid.cells()) * kFeatureBytes) {
    throw std::invalid_argument("save_feature_db: feature array does not match the grid");
  }
  std::uint64_t sum = detail::fnv1a(&h, sizeof h);
  sum = detail::fnv1a(db.features.data(), db.features.size(), sum);
  // Beside the path and renamed into place: a full disk never leaves a partial database there.
  const auto bytes = [](const void* p, std::size_t n) {
    return std::string_view(static_cast<const char*>(p), n);
  };
  try {
    write_file_replacing(path, {bytes(&h, sizeof h), bytes(db.features.data(), db.features.size()),
                                bytes(&sum, sizeof sum)});
  } catch (const FileWriteError& e) {
    throw std::runtime_error(e.what());
  }
}

void refuse_to_overwrite_foreign_file(const std::string& path, const std::string& why) {
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec)) ||
      is_feature_db_file(path))
    return;
  throw std::runtime_error(
      path + ": exists and is not an omniloc feature database; not overwriting it" +
      (why.empty() ? "" : " (" + why + ")") + ": remove it or give another database path");
}

namespace {

/// The file as bytes, refusing what is not a regular file of the size its header announces before
/// reading more than the header (a directory, /dev/zero or a huge file never reaches the reader).
std::vector<char> read_database_file(const std::string& path, const std::string& where, Header& h) {
  // The largest grid the header check below lets through; the size is checked exactly against the
  // header once it is read.
  constexpr std::uintmax_t kMaxDatabaseBytes = std::uintmax_t{4} << 30;
  std::uintmax_t size = 0;
  try {
    size = regular_file_size(path, kMaxDatabaseBytes, "feature database");
  } catch (const FileReadError& e) {
    throw std::runtime_error(e.what());
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(where + "cannot open feature database");
  if (size < sizeof(Header)) {
    throw std::runtime_error(where + "truncated feature database (" + std::to_string(size) +
                             " bytes, shorter than its header)");
  }
  std::vector<char> bytes(sizeof(Header));
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  std::memcpy(&h, bytes.data(), sizeof h);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0)
    throw std::runtime_error(where + "not an omniloc feature database");
  if (h.version != kFeatureDbVersion) {
    throw std::runtime_error(where + "database format version " + std::to_string(h.version) +
                             ", this build reads version " + std::to_string(kFeatureDbVersion) +
                             ": rebuild it with `omniloc builddb`");
  }
  if (h.header_bytes != sizeof(Header) || h.rays != kScanRays || h.crossings != kCrossingsPerRay ||
      h.nx <= 0 || h.ny <= 0 || h.nx > 100000 || h.ny > 100000 ||
      h.payload_bytes !=
          static_cast<std::uint64_t>(h.nx) * static_cast<std::uint64_t>(h.ny) * kFeatureBytes) {
    throw std::runtime_error(where + "corrupt header (grid " + std::to_string(h.nx) + " x " +
                             std::to_string(h.ny) + ", " + std::to_string(h.rays) + " rays x " +
                             std::to_string(h.crossings) + ")");
  }
  const std::uint64_t expected = sizeof(Header) + h.payload_bytes + sizeof(std::uint64_t);
  if (size != expected) {
    throw std::runtime_error(where + (size < expected ? "truncated" : "oversized") +
                             " feature database: " + std::to_string(size) +
                             " bytes, the header announces " + std::to_string(expected));
  }
  bytes.resize(expected);
  in.read(bytes.data() + sizeof(Header), static_cast<std::streamsize>(expected - sizeof(Header)));
  if (!in)
    throw std::runtime_error(where + "read failed after " + std::to_string(in.gcount()) +
                             " bytes of the payload");
  return bytes;
}

/// The grid the file's points lie on must be the one the builder lays over this field at the
/// file's step (GridSpec::covering): a checksum only proves the bytes are as written, not that a
/// NaN origin, a shifted grid or a 1 x 1 grid make sense for the field in use.
void check_grid(const Header& h, const FieldGeometry& field, const std::string& where) {
  auto show = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return std::string(buf);
  };
  if (!std::isfinite(h.step_cm) || h.step_cm < 1.0 || h.step_cm > 100.0 ||
      !std::isfinite(h.x0_cm) || !std::isfinite(h.y0_cm)) {
    throw std::runtime_error(where + "corrupt grid (origin (" + show(h.x0_cm) + ", " +
                             show(h.y0_cm) + ") cm, step " + show(h.step_cm) +
                             " cm; the step must be 1 .. 100 cm)");
  }
  // A grid with a single point along a side cannot tell positions along it apart (and has no
  // neighbours to interpolate between): a step of more than half the carpet's side.
  if (h.nx < 2 || h.ny < 2) {
    throw std::runtime_error(where + "grid " + std::to_string(h.nx) + " x " + std::to_string(h.ny) +
                             " at " + show(h.step_cm) +
                             " cm has fewer than 2 points along a side: rebuild it with a smaller "
                             "`omniloc builddb --step`");
  }
  const GridSpec g = GridSpec::covering(field, h.step_cm);
  constexpr double kTolCm = 1e-6;
  if (g.nx != h.nx || g.ny != h.ny || std::abs(g.x0_cm - h.x0_cm) > kTolCm ||
      std::abs(g.y0_cm - h.y0_cm) > kTolCm) {
    throw std::runtime_error(
        where + "grid " + std::to_string(h.nx) + " x " + std::to_string(h.ny) + " from (" +
        show(h.x0_cm) + ", " + show(h.y0_cm) + ") cm is not the grid of field '" + field.name +
        "' at " + show(h.step_cm) + " cm (" + std::to_string(g.nx) + " x " + std::to_string(g.ny) +
        " from (" + show(g.x0_cm) + ", " + show(g.y0_cm) + ")): rebuild it with `omniloc builddb`");
  }
}

}  // namespace

bool is_feature_db_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  char magic[sizeof kMagic] = {};
  in.read(magic, sizeof magic);
  return in.gcount() == sizeof magic && std::memcmp(magic, kMagic, sizeof kMagic) == 0;
}

FeatureDb load_feature_db(const std::string& path, const FieldGeometry& field,
                          const CameraModel& camera) {
  const std::string where = path + ": ";
  Header h{};
  const std::vector<char> bytes = read_database_file(path, where, h);
  std::uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + sizeof(Header) + h.payload_bytes, sizeof stored);
  const std::uint64_t actual = detail::fnv1a(bytes.data(), sizeof(Header) + h.payload_bytes);
  if (stored != actual) {
    throw std::runtime_error(where + "checksum mismatch (stored " + hex(stored) + ", computed " +
                             hex(actual) + "): the file is corrupt");
  }
  if (h.field_fingerprint != field.fingerprint()) {
    throw std::runtime_error(where + "built for a different field geometry (fingerprint " +
                             hex(h.field_fingerprint) + ", field '" + field.name + "' has " +
                             hex(field.fingerprint()) + "): rebuild it with `omniloc builddb`");
  }
  if (h.camera_fingerprint != camera.fingerprint()) {
    throw std::runtime_error(where + "built for a different camera radius table (fingerprint " +
                             hex(h.camera_fingerprint) + ", camera in use has " +
                             hex(camera.fingerprint()) + "): rebuild it with `omniloc builddb`");
  }
  // The fingerprint covers the view the step derives from; the step is checked by itself to say so.
  if (h.radius_step_px != camera.scan_step_px()) {
    throw std::runtime_error(where + "radii sampled every " + std::to_string(h.radius_step_px) +
                             " px, the camera in use samples every " +
                             std::to_string(camera.scan_step_px()) +
                             " px: rebuild it with `omniloc builddb`");
  }
  check_grid(h, field, where);
  FeatureDb db;
  db.grid = {h.x0_cm, h.y0_cm, h.step_cm, h.nx, h.ny};
  db.field_fingerprint = h.field_fingerprint;
  db.camera_fingerprint = h.camera_fingerprint;
  db.radius_step_px = h.radius_step_px;
  db.features.assign(bytes.begin() + sizeof(Header),
                     bytes.begin() + static_cast<std::ptrdiff_t>(sizeof(Header) + h.payload_bytes));
  return db;
}

}  // namespace omniloc
