// Localizer config file (common/localizer/default.json): its keys, reading and validation.
#include <cmath>

#include "omniloc/detail/config_reader.hpp"
#include "omniloc/localizer.hpp"

namespace omniloc {

LocalizerConfig LocalizerConfig::paper() {
  LocalizerConfig c;
  c.mode = LocalizerMode::kPaper;
  c.match_cost = MatchCost::kPaperSad;  // equation (5) as printed, and the paper's threshold on it
  c.e_th = 20.0;
  c.refinement = Refinement::kNone;
  c.min_range_cm = 0.0;
  c.refuse_ambiguous = false;
  c.yaw_correction = false;  // the paper takes the heading from the gyro alone
  return c;
}

void LocalizerConfig::validate(const config::Origin& at) const {
  using config::require;
  const auto positive = [&](double v, const char* field) {
    require(std::isfinite(v) && v > 0.0, at / field, "must be a positive number", v);
  };
  const auto non_negative = [&](double v, const char* field) {
    require(std::isfinite(v) && v >= 0.0, at / field, "must be a number >= 0", v);
  };
  fuzzy.validate(at / "fuzzy");
  positive(e_th, "e_th");
  require(crossing_cap_px >= 1 && crossing_cap_px <= 127, at / "crossing_cap_px",
          "must be 1..127 px (the two sides' costs of a slot add up in one byte)", crossing_cap_px);
  if (match_cost == MatchCost::kBounded) {
    require(
        e_th <= crossing_cap_px, at / "e_th",
        "must not exceed crossing_cap_px: the bounded error never does, every match would be good",
        e_th);
  }
  require(std::isfinite(ambiguity_ratio) && ambiguity_ratio >= 1.0, at / "ambiguity_ratio",
          "must be a number >= 1", ambiguity_ratio);
  // Upper bounds: the history is kept in memory, and periods beyond a day are typos.
  const auto at_most = [&](double v, const char* field, double hi, const char* why) {
    require(v <= hi, at / field, why, v);
  };
  positive(reset_period_ms, "reset_period_ms");
  require(reset_period_ms >= 1.0, at / "reset_period_ms", "must be at least 1 ms", reset_period_ms);
  at_most(reset_period_ms, "reset_period_ms", 8.64e7, "must be at most a day (8.64e7 ms)");
  require(std::isfinite(history_ms) && history_ms >= 100.0, at / "history_ms",
          "must be at least 100 ms (frames arrive up to ~50 ms late)", history_ms);
  at_most(history_ms, "history_ms", 60000.0,
          "must be at most 60000 ms (the history is kept in memory)");
  require(scan_rays_per_degree >= 1 && scan_rays_per_degree <= 16, at / "scan_rays_per_degree",
          "must be 1..16", scan_rays_per_degree);
  non_negative(min_range_cm, "min_range_cm");
  positive(image_sigma_cm, "image_sigma_cm");
  positive(image_sigma_yaw_deg, "image_sigma_yaw_deg");
  require(lost_after_bad_frames >= 1, at / "lost_after_bad_frames", "must be >= 1",
          lost_after_bad_frames);
  positive(check_period_ms, "check_period_ms");
  at_most(min_range_cm, "min_range_cm", 10000.0, "must be at most 10000 cm");
  at_most(image_sigma_cm, "image_sigma_cm", 10000.0, "must be at most 10000 cm");
  at_most(image_sigma_yaw_deg, "image_sigma_yaw_deg", 180.0, "must be at most 180 degrees");
  at_most(disagree_min_cm, "disagree_min_cm", 10000.0, "must be at most 10000 cm");
  non_negative(disagree_min_cm, "disagree_min_cm");
  positive(disagree_sigmas, "disagree_sigmas");
  require(disagree_error_ratio > 0.0 && disagree_error_ratio <= 1.0, at / "disagree_error_ratio",
          "must be in (0, 1]", disagree_error_ratio);
  require(disagree_frames >= 1, at / "disagree_frames", "must be >= 1", disagree_frames);
  require(yaw_search_deg > 0.0 && yaw_search_deg <= 30.0, at / "yaw_search_deg",
          "must be in (0, 30] degrees", yaw_search_deg);
  require(yaw_gain > 0.0 && yaw_gain <= 1.0, at / "yaw_gain", "must be in (0, 1]", yaw_gain);
  require(yaw_rate_gain >= 0.0 && yaw_rate_gain < 1.0, at / "yaw_rate_gain", "must be in [0, 1)",
          yaw_rate_gain);
  non_negative(yaw_rate_max_deg_per_s, "yaw_rate_max_deg_per_s");
}

void validate_localizer_config(const LocalizerConfig& c, const std::string& source) {
  c.validate(source);
}

const config::KeyTable<LocalizerConfig>& localizer_config_keys() {
  using config::key;
  using config::Need;
  using L = LocalizerConfig;
  static const config::KeyTable<LocalizerConfig> table = {
      // First: the mode chooses the values every other key overrides.
      config::custom<L>(
          "mode", Need::kOptional,
          [](const config::Node& n, L& c) {
            const auto mode = config::read_choice<LocalizerMode>(
                n, {{"full", LocalizerMode::kFull}, {"paper", LocalizerMode::kPaper}});
            if (mode == LocalizerMode::kPaper) c = LocalizerConfig::paper();
            c.mode = mode;
          },
          [](const L& c) {
            return config::Json(c.mode == LocalizerMode::kPaper ? "paper" : "full");
          }),
      config::choice<L, MatchCost>(
          "match_cost", &L::match_cost,
          {{"bounded", MatchCost::kBounded}, {"paper_sad", MatchCost::kPaperSad}}),
      key("crossing_cap_px", &L::crossing_cap_px),
      key("e_th", &L::e_th),
      key("ambiguity_ratio", &L::ambiguity_ratio),
      key("reset_period_ms", &L::reset_period_ms),
      key("history_ms", &L::history_ms),
      key("scan_rays_per_degree", &L::scan_rays_per_degree),
      config::choice<L, Refinement>("refinement", &L::refinement,
                                    {{"none", Refinement::kNone},
                                     {"interpolate", Refinement::kInterpolate},
                                     {"raycast", Refinement::kRayCast}}),
      key("min_range_cm", &L::min_range_cm),
      key("refuse_ambiguous", &L::refuse_ambiguous),
      key("image_sigma_cm", &L::image_sigma_cm),
      key("image_sigma_yaw_deg", &L::image_sigma_yaw_deg),
      key("lost_after_bad_frames", &L::lost_after_bad_frames),
      key("check_period_ms", &L::check_period_ms),
      key("disagree_min_cm", &L::disagree_min_cm),
      key("disagree_sigmas", &L::disagree_sigmas),
      key("disagree_error_ratio", &L::disagree_error_ratio),
      key("disagree_frames", &L::disagree_frames),
      key("cross_check_worker", &L::cross_check_worker),
      key("gyro_yaw_known", &L::gyro_yaw_known),
      key("yaw_correction", &L::yaw_correction),
      key("yaw_search_deg", &L::yaw_search_deg),
      key("yaw_gain", &L::yaw_gain),
      key("yaw_rate_gain", &L::yaw_rate_gain),
      key("yaw_rate_max_deg_per_s", &L::yaw_rate_max_deg_per_s),
      config::nested("fuzzy", &L::fuzzy, fuzzy_config_keys(), Need::kRequired),
  };
  return table;
}

LocalizerConfig parse_localizer_config(const config::Node& node) {
  LocalizerConfig c;
  config::read_keys(node, localizer_config_keys(), c);
  c.validate(node.origin());
  return c;
}

LocalizerConfig load_localizer_config(const std::string& name_or_path) {
  return parse_localizer_config(
      config::parse_json_file(resolve_data_file("localizer", name_or_path)).root());
}

const char* pose_source_name(PoseSource s) {
  switch (s) {
    case PoseSource::kNone:
      return "none";
    case PoseSource::kImage:
      return "image";
    case PoseSource::kIntegrated:
      return "integrated";
    case PoseSource::kOdometry:
      return "odometry";
    case PoseSource::kLost:
      return "lost";
  }
  return "?";
}

std::optional<PoseSource> parse_pose_source(const std::string& name) {
  for (PoseSource s : {PoseSource::kNone, PoseSource::kImage, PoseSource::kIntegrated,
                       PoseSource::kOdometry, PoseSource::kLost})
    if (name == pose_source_name(s)) return s;
  return std::nullopt;
}

const char* frame_outcome_name(FrameOutcome o) {
  switch (o) {
    case FrameOutcome::kPending:
      return "pending";
    case FrameOutcome::kDropped:
      return "dropped";
    case FrameOutcome::kAccepted:
      return "accepted";
    case FrameOutcome::kRejected:
      return "rejected";
    case FrameOutcome::kAmbiguous:
      return "ambiguous";
    case FrameOutcome::kRelocalized:
      return "relocalized";
  }
  return "?";
}

}  // namespace omniloc
