// `omniloc builddb`: builds the feature database for a field geometry and a camera, showing
// progress, and writes the versioned, checksummed file (then reads it back to check it).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "commands.hpp"
#include "omniloc/camera.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"

namespace omniloc::cli {

namespace {
void builddb_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: omniloc builddb --out FILE [--field NAME|PATH] [--camera NAME|PATH] [--step CM] [--threads N]\n"
               "  --field    geometry file or name in common/fields/ (default fira-robosot)\n"
               "  --camera   camera file or name in common/cameras/ (default default)\n"
               "  --step     grid step in cm (default 10: 75 x 55 points on the FIRA field)\n"
               "  --threads  worker threads (default: one per core)\n");
}
}  // namespace

int cmd_builddb(std::span<const std::string_view> args) {
  std::string field_name = "fira-robosot", camera_name = "default", out;
  double step_cm = 10.0, threads = 0.0;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (a == "-h" || a == "--help") {
      builddb_usage(stdout);
      return 0;
    }
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "omniloc builddb: '%.*s' needs a value\n", static_cast<int>(a.size()), a.data());
      builddb_usage(stderr);
      return 2;
    }
    const std::string_view v = args[++i];
    bool ok = true;
    if (a == "--field") {
      field_name = v;
    } else if (a == "--camera") {
      camera_name = v;
    } else if (a == "--out") {
      out = v;
    } else if (a == "--step") {
      ok = parse_number(v, step_cm);
    } else if (a == "--threads") {
      ok = parse_number(v, threads) && threads >= 0 && threads <= 256 && threads == static_cast<int>(threads);
    } else {
      std::fprintf(stderr, "omniloc builddb: unknown option '%.*s'\n", static_cast<int>(a.size()), a.data());
      builddb_usage(stderr);
      return 2;
    }
    if (!ok) {
      std::fprintf(stderr, "omniloc builddb: bad value '%.*s' for %.*s\n", static_cast<int>(v.size()), v.data(),
                   static_cast<int>(a.size()), a.data());
      return 2;
    }
  }
  if (out.empty()) {
    std::fprintf(stderr, "omniloc builddb: --out FILE is required\n");
    builddb_usage(stderr);
    return 2;
  }
  const FieldGeometry field = load_field(field_name);
  const CameraModel camera = load_camera(camera_name);
  const GridSpec grid = GridSpec::covering(field, step_cm);
  std::printf("field %s (%s), camera %s, grid %d x %d at %.1f cm from (%.1f, %.1f)\n", field.name.c_str(),
              field.source.c_str(), camera_name.c_str(), grid.nx, grid.ny, grid.step_cm, grid.x0_cm, grid.y0_cm);
  const auto t0 = std::chrono::steady_clock::now();
  const FeatureDb db = build_feature_db(
      field, camera, grid,
      [](int done, int total) {
        std::fprintf(stderr, "\rbuilding: %5d / %d grid points (%3d %%)", done, total, 100 * done / total);
        if (done == total) std::fprintf(stderr, "\n");
      },
      static_cast<unsigned>(threads));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  save_feature_db(db, out);
  (void)load_feature_db(out, field, camera);  // read back: header, size and checksum
  std::printf("wrote %s: %d grid points x %d bytes = %zu bytes in memory, built in %.2f s, verified\n", out.c_str(),
              grid.cells(), kFeatureBytes, db.bytes_in_memory(), seconds);
  return 0;
}

}  // namespace omniloc::cli
