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
    if (!config.database.empty()) {
      save_feature_db(m.db, config.database);
      say("saved feature database " + config.database);
    }
  }
  return m;
}

}  // namespace omniloc::daemon
