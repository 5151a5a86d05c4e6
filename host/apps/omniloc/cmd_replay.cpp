// `omniloc replay REC_DIR --out poses.csv`: the localizer over a recording (docs/LOCALIZER.md).
#include <unistd.h>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "omniloc/detail/cache_dir.hpp"
#include "omniloc/field.hpp"
#include "omniloc/gyro_heading.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/recording.hpp"

namespace omniloc::cli {

namespace {

struct ReplayArgs {
  std::string dir, out, db_path, config_name = "default";
  bool paper = false;
  std::string heading = "recorded", side = "unknown";
};

void print_summary(const char* what, const char* unit, const ErrorSummary& s) {
  std::printf("%-16s mean %7.2f  median %7.2f  p95 %7.2f  max %7.2f %s  (%zu poses)\n", what,
              s.mean, s.median, s.p95, s.max, unit, s.count);
}

// The localizer's configuration: the named one, or with --paper the paper's (keeping the named
// one's fuzzy rules).
LocalizerConfig replay_config(const ReplayArgs& a) {
  LocalizerConfig config = load_localizer_config(a.config_name);
  if (a.paper) {
    const FuzzyConfig fuzzy = config.fuzzy;
    config = LocalizerConfig::paper();
    config.fuzzy = fuzzy;
  }
  return config;
}

// What the replay found: the localizer's counts, the frames with no measurement, the first fix
// and, with truth, the errors.
void print_replay_result(const ReplayResult& r, const Recording& rec) {
  const LocalizerStats& s = r.stats;
  std::printf(
      "frames %d: accepted %d, rejected %d, ambiguous %d, dropped %d; global searches %d, "
      "relocalizations %d, lost events %d, origin resets %d; poses without a fix %zu\n",
      s.frames, s.accepted, s.rejected, s.ambiguous, s.dropped, s.global_searches,
      s.relocalizations, s.lost_events, s.origin_resets, r.poses_without_fix);
  // Frames that showed nothing usable (no carpet, too few rays or crossings): no measurement.
  std::size_t no_measurement = 0;
  const FrameReport* first_empty = nullptr;
  for (const FrameReport& f : r.frames) {
    if (f.no_measurement.empty()) continue;
    ++no_measurement;
    if (!first_empty) first_empty = &f;
  }
  if (first_empty) {
    std::printf("frames with no measurement %zu (the first at %.1f ms: %s)\n", no_measurement,
                first_empty->t_ms, first_empty->no_measurement.c_str());
  }
  if (s.gyro_yaw_dropped > 0)
    std::printf(
        "gyro yaw dropped as implausible in %d window(s): their heading came from the "
        "wheels\n",
        s.gyro_yaw_dropped);
  if (r.time_to_first_fix_ms) {
    std::printf("first fix %.2f s after the first window; decided by the side %d time(s)\n",
                *r.time_to_first_fix_ms / 1000.0, s.decided_by_side);
  } else {
    std::printf("no fix in the whole recording\n");
  }
  if (r.position_error_cm) {
    print_summary("position error", "cm", *r.position_error_cm);
    print_summary("yaw error", "deg", *r.yaw_error_deg);
  } else if (!rec.truth.empty()) {
    std::printf("truth present but no pose with a fix inside its time span\n");
  }
}

int run_replay(const ReplayArgs& a) {
  const std::string& dir = a.dir;
  const std::string out =
      a.out.empty() ? (std::filesystem::path(dir) / "poses.csv").string() : a.out;
  const Recording rec = load_recording(dir);
  const FieldGeometry field = recording_field(rec);
  const LocalizerConfig config = replay_config(a);
  const std::filesystem::path cache =
      a.db_path.empty() ? user_cache_dir() / feature_db_cache_name(field, rec.meta.camera)
                        : std::filesystem::path(a.db_path);
  const FeatureDb db = load_or_build_feature_db(
      field, rec.meta.camera, cache,
      [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); });
  std::fprintf(stderr, "replaying %s: %zu windows, %zu frames%s, %s mode\n", dir.c_str(),
               rec.windows.size(), rec.frames.size(), rec.truth.empty() ? "" : ", with truth",
               a.paper ? "paper" : "full");
  ReplaySettings settings;
  if (a.heading != "recorded") settings.heading = parse_heading_trust(a.heading);
  if (a.side != "unknown")
    settings.side = a.side == "blue" ? GoalColour::kBlue : GoalColour::kYellow;
  settings.warn = [](const std::string& w) {
    std::fprintf(stderr, "\nomniloc replay: warning: %s\n", w.c_str());
  };
  ReplayResult r;
  try {
    r = replay_recording(
        rec, config, field, db,
        [](std::size_t done, std::size_t total) {
          std::fprintf(stderr, "\r  %zu / %zu events (%3.0f%%)", done, total,
                       100.0 * static_cast<double>(done) / static_cast<double>(total));
          if (done == total) std::fprintf(stderr, "\n");
        },
        settings);
  } catch (const std::invalid_argument& e) {  // a side the field cannot place
    std::fprintf(stderr, "omniloc replay: %s\n", e.what());
    return 2;
  }
  PosesCsvWriter writer(out);
  for (const LocalizedPose& p : r.poses) writer.write(p);
  writer.close();
  std::printf("wrote %zu poses to %s\n", r.poses.size(), out.c_str());
  print_replay_result(r, rec);
  return 0;
}

}  // namespace

Subcommand add_replay(CLI::App& program) {
  CLI::App* app = program.add_subcommand(
      "replay", "run the localizer over a recording directory, write poses.csv, errors vs truth");
  auto a = std::make_shared<ReplayArgs>();
  app->add_option("REC_DIR", a->dir, "the recording directory")->required();
  app->add_option("--out", a->out, "output poses")->default_str("REC_DIR/poses.csv");
  app->add_option("--db", a->db_path,
                  "feature database file: used if it matches the recording's field and camera, "
                  "else built and\n"
                  "written there; a file that is not a feature database is never overwritten")
      ->default_str("$XDG_CACHE_HOME/omniloc/, else ~/.cache/omniloc/");
  app->add_option("--config", a->config_name, "localizer config, name in common/localizer/ or path")
      ->capture_default_str();
  app->add_flag("--paper", a->paper,
                "the paper's algorithm exactly (no refinement, no lost detection)");
  app->add_option("--heading", a->heading,
                  "how far the windows' heading is trusted: recorded (each window's own, "
                  "heading.csv; absolute\n"
                  "without one), absolute (aligned with the field), relative (a gyro, aligned at "
                  "the first fix),\n"
                  "none (the wheels: every heading tried)")
      ->check(CLI::IsMember({"recorded", "absolute", "relative", "none"}))
      ->capture_default_str();
  app->add_option(
         "--side", a->side,
         "the goal the team defends, as omnilocd's `side` key: decides the first fix's twin")
      ->check(CLI::IsMember({"unknown", "blue", "yellow"}))
      ->capture_default_str();
  return {app, [a] { return run_replay(*a); }};
}

}  // namespace omniloc::cli
