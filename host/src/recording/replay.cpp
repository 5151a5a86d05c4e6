// Replay: the live localizer driven from a recording (the same class omnilocd uses).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include "omniloc/recording.hpp"

namespace omniloc {

std::string feature_db_cache_name(const FieldGeometry& field, const CameraModel& camera) {
  char buf[80];
  std::snprintf(buf, sizeof buf, "featuredb-%016llx-%016llx.bin",
                static_cast<unsigned long long>(field.fingerprint()),
                static_cast<unsigned long long>(camera.fingerprint()));
  return buf;
}

FeatureDb load_or_build_feature_db(const FieldGeometry& field, const CameraModel& camera,
                                   const std::filesystem::path& cache_path,
                                   const std::function<void(const std::string&)>& log) {
  std::string why = "no cached database";
  if (std::filesystem::exists(cache_path)) {
    try {
      FeatureDb db = load_feature_db(cache_path.string(), field, camera);
      if (log) log("database loaded from " + cache_path.string());
      return db;
    } catch (const std::exception& e) {
      // A stale or damaged database is a cache to rebuild; any other file is someone's data.
      refuse_to_overwrite_foreign_file(cache_path.string(), e.what());
      why = std::string("cached database unusable (") + e.what() + ")";
    }
  }
  FeatureDb db = build_feature_db(field, camera, GridSpec::covering(field, 10.0));
  std::error_code ec;
  if (cache_path.has_parent_path())
    std::filesystem::create_directories(cache_path.parent_path(), ec);
  try {
    save_feature_db(db, cache_path.string());
  } catch (const std::exception& e) {
    // The database is in memory: only the next run pays for building it again.
    if (log)
      log("warning: " + why + ": built, but not saved (" + e.what() +
          "); going on with the database in memory");
    return db;
  }
  if (log) log(why + ": built and saved to " + cache_path.string());
  return db;
}

ErrorSummary summarize_errors(std::vector<double> e) {
  if (e.empty()) throw std::invalid_argument("summarize_errors: no values");
  std::sort(e.begin(), e.end());
  ErrorSummary s;
  s.count = e.size();
  double sum = 0.0;
  for (double v : e) sum += v;
  s.mean = sum / static_cast<double>(e.size());
  const std::size_t n = e.size();
  s.median = n % 2 ? e[n / 2] : (e[n / 2 - 1] + e[n / 2]) / 2.0;
  const auto rank = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(n)));
  s.p95 = e[std::max<std::size_t>(rank, 1) - 1];
  s.max = e.back();
  return s;
}

namespace {

std::string gyro_warning(const Recording& rec, const EncoderWindow& w, const GyroYawCheck& check,
                         int dropped) {
  return (rec.dir / "encoders.csv").string() + ": window seq " + std::to_string(w.seq) + ": " +
         check.describe() + ": dropped, the window's heading taken from the wheels (" +
         std::to_string(dropped) + " window(s) dropped so far)";
}

}  // namespace

ReplayResult replay_recording(const Recording& rec, const LocalizerConfig& config,
                              const FieldGeometry& field, const FeatureDb& db,
                              const std::function<void(std::size_t, std::size_t)>& progress,
                              const ReplaySettings& settings) {
  Localizer loc(config, rec.meta.robot, field, rec.meta.camera, db, rec.meta.initial_pose);
  if (settings.side) loc.set_side(*settings.side);
  ReplayResult out;
  out.poses.reserve(rec.windows.size());
  const std::size_t total = rec.windows.size() + rec.frames.size();
  std::size_t wi = 0, fi = 0, done = 0;
  while (wi < rec.windows.size()) {
    // A frame goes in before the window whose end is at or after its time.
    if (fi < rec.frames.size() && rec.frames[fi].t_ms <= rec.windows[wi].t_end_ms) {
      (void)loc.on_image(rec.frames[fi].t_ms, load_frame(rec, fi));
      for (FrameReport& r : loc.take_frame_reports()) out.frames.push_back(std::move(r));
      ++fi;
    } else {
      EncoderWindow w = rec.windows[wi];
      if (settings.heading) w.heading_trust = *settings.heading;
      out.poses.push_back(loc.on_window(w));
      if (out.poses.back().gyro_yaw_dropped && settings.warn)
        settings.warn(
            gyro_warning(rec, w, *out.poses.back().gyro_yaw_dropped, loc.stats().gyro_yaw_dropped));
      for (FrameReport& r : loc.take_frame_reports()) out.frames.push_back(std::move(r));
      if (!out.time_to_first_fix_ms && out.poses.back().source != PoseSource::kNone)
        out.time_to_first_fix_ms = w.t_end_ms - rec.windows.front().t_end_ms;
      ++wi;
    }
    if (progress && (++done % 200 == 0 || done == total)) progress(done, total);
  }
  for (FrameReport& r : loc.take_frame_reports()) out.frames.push_back(std::move(r));
  out.stats = loc.stats();
  std::vector<double> pos, yaw;
  for (const LocalizedPose& p : out.poses) {
    if (p.source == PoseSource::kNone) {
      ++out.poses_without_fix;
      continue;
    }
    const auto t = truth_at(rec.truth, p.t_ms);
    if (!t) continue;
    pos.push_back(distance_cm(p.pose, *t));
    yaw.push_back(std::abs(yaw_difference_deg(p.pose, *t)));
  }
  if (!pos.empty()) {
    out.position_error_cm = summarize_errors(pos);
    out.yaw_error_deg = summarize_errors(yaw);
  }
  return out;
}

}  // namespace omniloc
