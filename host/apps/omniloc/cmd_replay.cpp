// `omniloc replay REC_DIR --out poses.csv`: the localizer over a recording (docs/LOCALIZER.md).
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "commands.hpp"
#include "omniloc/cache_dir.hpp"
#include "omniloc/field.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/recording.hpp"

namespace omniloc::cli {

namespace {

void replay_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: omniloc replay REC_DIR [--out poses.csv] [--db FILE] [--config NAME|PATH] [--paper]\n"
               "  --out     output poses (default REC_DIR/poses.csv)\n"
               "  --db      feature database file: used if it matches the recording's field and camera,\n"
               "            else built and written there; a file that is not a feature database is never\n"
               "            overwritten (default: $XDG_CACHE_HOME/omniloc/, else ~/.cache/omniloc/)\n"
               "  --config  localizer config, name in common/localizer/ or path (default: default)\n"
               "  --paper   the paper's algorithm exactly (no refinement, no lost detection)\n");
}

void print_summary(const char* what, const char* unit, const ErrorSummary& s) {
  std::printf("%-16s mean %7.2f  median %7.2f  p95 %7.2f  max %7.2f %s  (%zu poses)\n", what, s.mean, s.median, s.p95,
              s.max, unit, s.count);
}

}  // namespace

int cmd_replay(std::span<const std::string_view> args) {
  std::string dir, out, db_path, config_name = "default";
  bool paper = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (a == "-h" || a == "--help") {
      replay_usage(stdout);
      return 0;
    }
    if (a == "--paper") {
      paper = true;
      continue;
    }
    if (a == "--out" || a == "--db" || a == "--config") {
      if (i + 1 >= args.size()) {
        std::fprintf(stderr, "omniloc replay: '%.*s' needs a value\n", static_cast<int>(a.size()), a.data());
        return 2;
      }
      const std::string v(args[++i]);
      (a == "--out" ? out : a == "--db" ? db_path : config_name) = v;
      continue;
    }
    if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "omniloc replay: unknown option '%.*s'\n", static_cast<int>(a.size()), a.data());
      replay_usage(stderr);
      return 2;
    }
    if (!dir.empty()) {
      std::fprintf(stderr, "omniloc replay: more than one REC_DIR given\n");
      return 2;
    }
    dir = a;
  }
  if (dir.empty()) {
    replay_usage(stderr);
    return 2;
  }
  if (out.empty()) out = (std::filesystem::path(dir) / "poses.csv").string();

  const Recording rec = load_recording(dir);
  const FieldGeometry field = recording_field(rec);
  LocalizerConfig config = load_localizer_config(config_name);
  if (paper) {
    const FuzzyConfig fuzzy = config.fuzzy;
    config = LocalizerConfig::paper();
    config.fuzzy = fuzzy;
  }
  const std::filesystem::path cache =
      db_path.empty() ? user_cache_dir() / feature_db_cache_name(field, rec.meta.camera) : std::filesystem::path(db_path);
  const FeatureDb db = load_or_build_feature_db(field, rec.meta.camera, cache,
                                                [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); });
  std::fprintf(stderr, "replaying %s: %zu windows, %zu frames%s, %s mode\n", dir.c_str(), rec.windows.size(),
               rec.frames.size(), rec.truth.empty() ? "" : ", with truth", paper ? "paper" : "full");
  const ReplayResult r = replay_recording(rec, config, field, db, [](std::size_t done, std::size_t total) {
    std::fprintf(stderr, "\r  %zu / %zu events (%3.0f%%)", done, total, 100.0 * static_cast<double>(done) / static_cast<double>(total));
    if (done == total) std::fprintf(stderr, "\n");
  });
  PosesCsvWriter writer(out);
  for (const LocalizedPose& p : r.poses) writer.write(p);
  writer.close();
  const LocalizerStats& s = r.stats;
  std::printf("wrote %zu poses to %s\n", r.poses.size(), out.c_str());
  std::printf("frames %d: accepted %d, rejected %d, ambiguous %d, dropped %d; global searches %d, "
              "relocalizations %d, lost events %d, origin resets %d; poses without a fix %zu\n",
              s.frames, s.accepted, s.rejected, s.ambiguous, s.dropped, s.global_searches, s.relocalizations,
              s.lost_events, s.origin_resets, r.poses_without_fix);
  if (r.position_error_cm) {
    print_summary("position error", "cm", *r.position_error_cm);
    print_summary("yaw error", "deg", *r.yaw_error_deg);
  } else if (!rec.truth.empty()) {
    std::printf("truth present but no pose with a fix inside its time span\n");
  }
  return 0;
}

}  // namespace omniloc::cli
