// Feature database: for every point of a grid over the field and its border, the expected scan
// (360 rays x 4 crossings, uint8 sample indices, field frame) by ray casting the field model
// through the camera's radius table. Stored as a versioned binary file whose header carries the
// grid and the field and camera fingerprints, and a checksum; loading refuses a file that is
// truncated, corrupt, or was built for another field or camera. Databases are generated (`omniloc
// builddb`), never committed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "omniloc/camera.hpp"
#include "omniloc/field.hpp"
#include "omniloc/line_scan.hpp"

namespace omniloc {

/// Grid points (x0 + i step, y0 + j step), i < nx, j < ny; cell index j * nx + i.
struct GridSpec {
  double x0_cm = 5.0;
  double y0_cm = 5.0;
  double step_cm = 10.0;
  int nx = 75;
  int ny = 55;

  [[nodiscard]] int cells() const { return nx * ny; }
  [[nodiscard]] Eigen::Vector2d position(int i, int j) const {
    return {x0_cm + i * step_cm, y0_cm + j * step_cm};
  }
  [[nodiscard]] Eigen::Vector2d position(int cell) const { return position(cell % nx, cell / nx); }
  /// Cell centres over the whole carpet: step/2, 3 step/2, ... (75 x 55 for FIRA at 10 cm).
  [[nodiscard]] static GridSpec covering(const FieldGeometry& field, double step_cm);
};

struct FeatureDb {
  GridSpec grid;
  std::uint64_t field_fingerprint = 0;
  std::uint64_t camera_fingerprint = 0;
  double radius_step_px = 1.0;         // the features' radius unit (CameraModel::scan_step_px)
  std::vector<std::uint8_t> features;  // cells() * kFeatureBytes, cell-major

  [[nodiscard]] const std::uint8_t* cell_features(int cell) const {
    return features.data() + static_cast<std::size_t>(cell) * kFeatureBytes;
  }
  [[nodiscard]] std::size_t bytes_in_memory() const { return features.size() + sizeof(*this); }
};

/// Called with (cells done, cells total) as rows complete.
using BuildProgress = std::function<void(int done, int total)>;

/// Builds the database, using `threads` worker threads (0: one per core).
[[nodiscard]] FeatureDb build_feature_db(const FieldGeometry& field, const CameraModel& camera,
                                         const GridSpec& grid, const BuildProgress& progress = {},
                                         unsigned threads = 0);

/// 2: radii are sample indices, the header says the step (a view beyond 254 px; 1 had px only).
inline constexpr std::uint32_t kFeatureDbVersion = 2;

/// Writes the file: to a temporary file beside it, renamed into place once complete, so that a
/// failure part-way (a full disk) leaves the path as it was and no temporary behind. Throws
/// std::runtime_error naming the path and the system's error on I/O failure.
void save_feature_db(const FeatureDb& db, const std::string& path);

/// Throws std::runtime_error "<path>: exists and is not an omniloc feature database; not
/// overwriting it (<why>): remove it or give another database path" when something that is not a
/// feature database (is_feature_db_file) is at `path`: a database may be written there only over
/// nothing or over a database (any version, grid or checksum). `why` may be empty.
void refuse_to_overwrite_foreign_file(const std::string& path, const std::string& why = {});

/// True if `path` is a regular file that starts as a feature database does (its magic), whatever
/// its version, grid or checksum: a cache may overwrite such a file, never anything else.
[[nodiscard]] bool is_feature_db_file(const std::string& path);

/// Reads and checks a file against the field and camera in use; throws std::runtime_error naming
/// the path and the problem (not a database, version, truncated, checksum, fingerprint mismatch).
[[nodiscard]] FeatureDb load_feature_db(const std::string& path, const FieldGeometry& field,
                                        const CameraModel& camera);

}  // namespace omniloc
