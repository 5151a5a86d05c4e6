// Localizer config file (common/localizer/default.json): reading and validation.
#include <cmath>
#include <set>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>

#include "omniloc/data_files.hpp"
#include "omniloc/localizer.hpp"

namespace omniloc {

LocalizerConfig LocalizerConfig::paper() {
  LocalizerConfig c;
  c.mode = LocalizerMode::kPaper;
  c.refinement = Refinement::kNone;
  c.min_range_cm = 0.0;
  c.refuse_ambiguous = false;
  c.yaw_correction = false;  // the paper takes the heading from the gyro alone
  return c;
}

namespace {

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& why) {
  throw ConfigError(source + ": field '" + field + "': " + why);
}

void need_positive(double v, const std::string& source, const std::string& field) {
  if (!std::isfinite(v) || !(v > 0.0)) {
    std::ostringstream os;
    os << "must be a positive number (got " << v << ")";
    fail(source, field, os.str());
  }
}

void need_non_negative(double v, const std::string& source, const std::string& field) {
  if (!std::isfinite(v) || v < 0.0) {
    std::ostringstream os;
    os << "must be a number >= 0 (got " << v << ")";
    fail(source, field, os.str());
  }
}

}  // namespace

void validate_localizer_config(const LocalizerConfig& c, const std::string& source) {
  validate_fuzzy_config(c.fuzzy, source + ": fuzzy");
  need_positive(c.e_th, source, "e_th");
  need_positive(c.reset_period_ms, source, "reset_period_ms");
  need_positive(c.history_ms, source, "history_ms");
  if (c.history_ms < 100.0) fail(source, "history_ms", "must be at least 100 ms (frames arrive up to ~50 ms late)");
  if (c.scan_rays_per_degree < 1 || c.scan_rays_per_degree > 16) fail(source, "scan_rays_per_degree", "must be 1..16");
  need_non_negative(c.min_range_cm, source, "min_range_cm");
  need_positive(c.image_sigma_cm, source, "image_sigma_cm");
  need_positive(c.image_sigma_yaw_deg, source, "image_sigma_yaw_deg");
  if (c.lost_after_bad_frames < 1) fail(source, "lost_after_bad_frames", "must be >= 1");
  need_positive(c.check_period_ms, source, "check_period_ms");
  need_non_negative(c.disagree_min_cm, source, "disagree_min_cm");
  need_positive(c.disagree_sigmas, source, "disagree_sigmas");
  if (!(c.disagree_error_ratio > 0.0 && c.disagree_error_ratio <= 1.0))
    fail(source, "disagree_error_ratio", "must be in (0, 1]");
  if (c.disagree_frames < 1) fail(source, "disagree_frames", "must be >= 1");
  if (!(c.yaw_search_deg > 0.0 && c.yaw_search_deg <= 30.0)) fail(source, "yaw_search_deg", "must be in (0, 30] degrees");
  if (!(c.yaw_gain > 0.0 && c.yaw_gain <= 1.0)) fail(source, "yaw_gain", "must be in (0, 1]");
  if (!(c.yaw_rate_gain >= 0.0 && c.yaw_rate_gain < 1.0)) fail(source, "yaw_rate_gain", "must be in [0, 1)");
  need_non_negative(c.yaw_rate_max_deg_per_s, source, "yaw_rate_max_deg_per_s");
}

namespace {

double number(const cv::FileNode& n, const std::string& source, const std::string& field) {
  if (!n.isReal() && !n.isInt()) fail(source, field, "must be a number");
  return static_cast<double>(n);
}

int integer(const cv::FileNode& n, const std::string& source, const std::string& field) {
  if (!n.isInt()) fail(source, field, "must be an integer");
  return static_cast<int>(n);
}

bool boolean(const cv::FileNode& n, const std::string& source, const std::string& field) {
  // cv::FileStorage reads JSON true/false as the integers 1/0.
  if (!n.isInt() || (static_cast<int>(n) != 0 && static_cast<int>(n) != 1)) fail(source, field, "must be true or false");
  return static_cast<int>(n) == 1;
}

}  // namespace

LocalizerConfig parse_localizer_config(const cv::FileNode& node, const std::string& source) {
  if (node.empty() || !node.isMap()) throw ConfigError(source + ": the top level must be a JSON object");
  static const std::set<std::string> kKeys = {
      "mode", "fuzzy", "e_th", "reset_period_ms", "history_ms", "scan_rays_per_degree", "refinement", "min_range_cm",
      "refuse_ambiguous", "image_sigma_cm", "image_sigma_yaw_deg", "lost_after_bad_frames", "check_period_ms",
      "disagree_min_cm", "disagree_sigmas", "disagree_error_ratio", "disagree_frames", "gyro_yaw_known",
      "yaw_correction", "yaw_search_deg", "yaw_gain", "yaw_rate_gain", "yaw_rate_max_deg_per_s"};
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = (*it).name();
    if (!kKeys.count(key)) fail(source, key, "unknown key (see docs/LOCALIZER.md)");
  }
  // The mode chooses the defaults; every other key overrides one of them.
  LocalizerConfig c;
  if (const cv::FileNode m = node["mode"]; !m.empty()) {
    if (!m.isString()) fail(source, "mode", "must be \"full\" or \"paper\"");
    const std::string s = static_cast<std::string>(m);
    if (s == "paper") c = LocalizerConfig::paper();
    else if (s != "full") fail(source, "mode", "must be \"full\" or \"paper\" (got \"" + s + "\")");
  }
  const cv::FileNode fz = node["fuzzy"];
  if (fz.empty()) fail(source, "fuzzy", "missing (the fuzzy system's terms and rules)");
  c.fuzzy = parse_fuzzy_config(fz, source + ": fuzzy");
  auto opt_num = [&](const char* key, double& out) {
    if (const cv::FileNode n = node[key]; !n.empty()) out = number(n, source, key);
  };
  auto opt_int = [&](const char* key, int& out) {
    if (const cv::FileNode n = node[key]; !n.empty()) out = integer(n, source, key);
  };
  auto opt_bool = [&](const char* key, bool& out) {
    if (const cv::FileNode n = node[key]; !n.empty()) out = boolean(n, source, key);
  };
  opt_num("e_th", c.e_th);
  opt_num("reset_period_ms", c.reset_period_ms);
  opt_num("history_ms", c.history_ms);
  opt_int("scan_rays_per_degree", c.scan_rays_per_degree);
  if (const cv::FileNode n = node["refinement"]; !n.empty()) {
    const std::string s = n.isString() ? static_cast<std::string>(n) : std::string();
    if (s == "none") c.refinement = Refinement::kNone;
    else if (s == "interpolate") c.refinement = Refinement::kInterpolate;
    else if (s == "raycast") c.refinement = Refinement::kRayCast;
    else fail(source, "refinement", "must be \"none\", \"interpolate\" or \"raycast\"");
  }
  opt_num("min_range_cm", c.min_range_cm);
  opt_bool("refuse_ambiguous", c.refuse_ambiguous);
  opt_num("image_sigma_cm", c.image_sigma_cm);
  opt_num("image_sigma_yaw_deg", c.image_sigma_yaw_deg);
  opt_int("lost_after_bad_frames", c.lost_after_bad_frames);
  opt_num("check_period_ms", c.check_period_ms);
  opt_num("disagree_min_cm", c.disagree_min_cm);
  opt_num("disagree_sigmas", c.disagree_sigmas);
  opt_num("disagree_error_ratio", c.disagree_error_ratio);
  opt_int("disagree_frames", c.disagree_frames);
  opt_bool("gyro_yaw_known", c.gyro_yaw_known);
  opt_bool("yaw_correction", c.yaw_correction);
  opt_num("yaw_search_deg", c.yaw_search_deg);
  opt_num("yaw_gain", c.yaw_gain);
  opt_num("yaw_rate_gain", c.yaw_rate_gain);
  opt_num("yaw_rate_max_deg_per_s", c.yaw_rate_max_deg_per_s);
  validate_localizer_config(c, source);
  return c;
}

LocalizerConfig load_localizer_config(const std::string& name_or_path) {
  const std::filesystem::path path = resolve_data_file("localizer", name_or_path);
  cv::FileStorage fs;
  try {
    if (!fs.open(path.string(), cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON))
      throw ConfigError(path.string() + ": cannot open");
  } catch (const cv::Exception& e) {
    throw ConfigError(path.string() + ": not valid JSON (" + e.msg + ")");
  }
  return parse_localizer_config(fs.root(), path.string());
}

const char* pose_source_name(PoseSource s) {
  switch (s) {
    case PoseSource::kNone: return "none";
    case PoseSource::kImage: return "image";
    case PoseSource::kIntegrated: return "integrated";
    case PoseSource::kOdometry: return "odometry";
    case PoseSource::kLost: return "lost";
  }
  return "?";
}

std::optional<PoseSource> parse_pose_source(const std::string& name) {
  for (PoseSource s : {PoseSource::kNone, PoseSource::kImage, PoseSource::kIntegrated, PoseSource::kOdometry,
                       PoseSource::kLost})
    if (name == pose_source_name(s)) return s;
  return std::nullopt;
}

const char* frame_outcome_name(FrameOutcome o) {
  switch (o) {
    case FrameOutcome::kPending: return "pending";
    case FrameOutcome::kDropped: return "dropped";
    case FrameOutcome::kAccepted: return "accepted";
    case FrameOutcome::kRejected: return "rejected";
    case FrameOutcome::kAmbiguous: return "ambiguous";
    case FrameOutcome::kRelocalized: return "relocalized";
  }
  return "?";
}

}  // namespace omniloc
