// `omniloc builddb`: builds the feature database for a field geometry and a camera, showing
// progress, and writes the versioned, checksummed file (then reads it back to check it).
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "omniloc/camera.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"

namespace omniloc::cli {

namespace {

struct BuilddbArgs {
  std::string field_name = "fira-robosot", camera_name = "default", out;
  double step_cm = 10.0;
  unsigned threads = 0;
};

int run_builddb(const BuilddbArgs& a) {
  // Over nothing or an older database only, as replay and locate write their --db.
  refuse_to_overwrite_foreign_file(a.out);
  const FieldGeometry field = load_field(a.field_name);
  const CameraModel camera = load_camera(a.camera_name);
  const GridSpec grid = GridSpec::covering(field, a.step_cm);
  std::printf("field %s (%s), camera %s, grid %d x %d at %.1f cm from (%.1f, %.1f)\n",
              field.name.c_str(), field.source.c_str(), a.camera_name.c_str(), grid.nx, grid.ny,
              grid.step_cm, grid.x0_cm, grid.y0_cm);
  const auto t0 = std::chrono::steady_clock::now();
  const FeatureDb db = build_feature_db(
      field, camera, grid,
      [](int done, int total) {
        std::fprintf(stderr, "\rbuilding: %5d / %d grid points (%3d %%)", done, total,
                     100 * done / total);
        if (done == total) std::fprintf(stderr, "\n");
      },
      a.threads);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  save_feature_db(db, a.out);
  (void)load_feature_db(a.out, field, camera);  // read back: header, size and checksum
  std::printf(
      "wrote %s: %d grid points x %d bytes = %zu bytes in memory, built in %.2f s, verified\n",
      a.out.c_str(), grid.cells(), kFeatureBytes, db.bytes_in_memory(), seconds);
  return 0;
}

}  // namespace

Subcommand add_builddb(CLI::App& program) {
  CLI::App* app = program.add_subcommand(
      "builddb", "build the vision feature database (field x camera x grid) with progress");
  auto a = std::make_shared<BuilddbArgs>();
  app->add_option("--out", a->out, "the database file to write")->required();
  app->add_option("--field", a->field_name, "geometry file or name in common/fields/")
      ->capture_default_str();
  app->add_option("--camera", a->camera_name, "camera file or name in common/cameras/")
      ->capture_default_str();
  add_number_option(*app, "--step", a->step_cm,
                    "grid step in cm (10: 75 x 55 points on the FIRA field)", 1.0, 100.0);
  add_number_option(*app, "--threads", a->threads, "worker threads; 0: one per core", 0u, 256u);
  return {app, [a] { return run_builddb(*a); }};
}

}  // namespace omniloc::cli
