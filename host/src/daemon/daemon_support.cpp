// The daemon's small helpers: the wall clock, model loading.
#include <chrono>
#include <filesystem>
#include <thread>

#include "omniloc/daemon.hpp"

namespace omniloc::daemon {
namespace {
std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

SteadyClock::SteadyClock() : start_ns_(steady_ns()) {}

double SteadyClock::now_ms() {
  return static_cast<double>(steady_ns() - start_ns_) * 1e-6;
}

void SteadyClock::wait_ms(double ms) {
  if (ms > 0)
    std::this_thread::sleep_for(std::chrono::microseconds(static_cast<std::int64_t>(ms * 1000.0)));
}

namespace {

// The database is in memory: a failed save (a full disk, a missing directory) costs only the next
// start its build, so the daemon says so and goes on, as `omniloc replay --db` does.
void save_database(const FeatureDb& db, const std::string& path,
                   const std::function<void(const std::string&)>& say) {
  try {
    save_feature_db(db, path);
    say("saved feature database " + path);
  } catch (const std::exception& e) {
    say(std::string("warning: feature database built, but not saved (") + e.what() +
        "); going on with the database in memory");
  }
}

}  // namespace

DaemonModels load_models(const DaemonConfig& config,
                         const std::function<void(const std::string&)>& progress) {
  auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  DaemonModels m;
  m.field = load_field(config.field);
  m.camera = load_camera(config.camera_model);
  m.robot = load_named_robot_config(config.robot);
  m.localizer = load_localizer_config(config.localizer);
  const GridSpec grid = GridSpec::covering(m.field, config.grid_step_cm);
  if (!config.database.empty() && std::filesystem::exists(config.database)) {
    say("loading feature database " + config.database);
    m.db = load_feature_db(config.database, m.field, m.camera);
  } else {
    say("building feature database (" + std::to_string(grid.nx) + " x " + std::to_string(grid.ny) +
        " points)");
    m.db = build_feature_db(m.field, m.camera, grid);
    if (!config.database.empty()) save_database(m.db, config.database, say);
  }
  return m;
}

}  // namespace omniloc::daemon
