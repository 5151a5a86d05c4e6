// The camera JSON "vision" block (keys, defaults in vision.hpp, validation) and the carpet colour
// statistics shared with the calibration.
#include <algorithm>
#include <cmath>

#include "omniloc/detail/config_reader.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

namespace {

using config::Key;
using config::KeyTable;
using config::Need;

const KeyTable<CarpetHsv>& carpet_keys() {
  using config::key;
  // All required: a carpet window is only meaningful whole (calibrate writes every key).
  static const KeyTable<CarpetHsv> t = {
      key("hue", &CarpetHsv::hue, Need::kRequired),
      key("hue_half_width", &CarpetHsv::hue_half_width, Need::kRequired),
      key("sat_min", &CarpetHsv::sat_min, Need::kRequired),
      key("val_min", &CarpetHsv::val_min, Need::kRequired),
      key("val_max", &CarpetHsv::val_max, Need::kRequired),
  };
  return t;
}

const KeyTable<LineContrast>& contrast_keys() {
  using config::key;
  static const KeyTable<LineContrast> t = {
      key("val_step", &LineContrast::val_step),
      key("sat_step", &LineContrast::sat_step),
  };
  return t;
}

const KeyTable<GoalHsv>& goal_keys() {
  using config::key;
  static const KeyTable<GoalHsv> t = {
      key("hue", &GoalHsv::hue, Need::kRequired),
      key("hue_half_width", &GoalHsv::hue_half_width),
      key("sat_min", &GoalHsv::sat_min),
      key("val_min", &GoalHsv::val_min),
  };
  return t;
}

const KeyTable<ExtractionParams>& extraction_keys() {
  using config::key;
  using E = ExtractionParams;
  static const KeyTable<E> t = {
      key("end_run_px", &E::end_run_px),
      key("carpet_resume_px", &E::carpet_resume_px),
      key("resume_within_px", &E::resume_within_px),
      key("obstacle_window_deg", &E::obstacle_window_deg),
      key("obstacle_step_px", &E::obstacle_step_px),
      key("edge_fraction", &E::edge_fraction),
      key("carpet_mean_px", &E::carpet_mean_px),
      key("sectors", &E::sectors),
      key("light_follow", &E::light_follow),
      key("light_range", &E::light_range),
      key("val_sigmas", &E::val_sigmas),
      key("sat_sigmas", &E::sat_sigmas),
      key("min_val_step", &E::min_val_step),
      key("min_sat_step", &E::min_sat_step),
      key("min_carpet_fraction", &E::min_carpet_fraction),
      key("min_rays_seen", &E::min_rays_seen),
      key("min_crossings", &E::min_crossings),
  };
  return t;
}

// An optional nested struct: present in the file -> engaged (its own table's defaults for the keys
// it omits); absent -> nullopt and nothing written.
template <class S>
Key<VisionModel> optional_nested(std::string name, std::optional<S> VisionModel::*member,
                                 const KeyTable<S>& sub) {
  return Key<VisionModel>{std::move(name),
                          Need::kOptional,
                          config::Kind::kOther,
                          [member, &sub](const config::Node& n, VisionModel& out) {
                            S s{};
                            config::read_keys(n, sub, s);
                            out.*member = s;
                          },
                          [member, &sub](const VisionModel& in) -> std::optional<config::Json> {
                            if (!(in.*member)) return std::nullopt;
                            return config::write_keys(*(in.*member), sub);
                          },
                          {}};
}

void check_hue(const config::Origin& at, double hue, double half) {
  config::require(hue >= 0.0 && hue < 180.0, at / "hue", "must be an OpenCV hue in [0, 180)", hue);
  config::require(half > 0.0 && half <= 90.0, at / "hue_half_width", "must be in (0, 90]", half);
}

void check_level(const config::Origin& at, const char* name, double v) {
  config::require(v >= 0.0 && v <= 255.0, at / name, "must be an 8-bit level in [0, 255]", v);
}

const config::KeyTable<GoalCueConfig>& goal_cue_keys() {
  using config::key;
  static const config::KeyTable<GoalCueConfig> table = {
      key("min_pixels", &GoalCueConfig::min_pixels),
      key("min_margin", &GoalCueConfig::min_margin),
      key("post_margin_cm", &GoalCueConfig::post_margin_cm),
      key("pixel_step", &GoalCueConfig::pixel_step),
  };
  return table;
}

}  // namespace

const std::vector<config::Key<VisionModel>>& vision_keys() {
  using V = VisionModel;
  static const KeyTable<V> t = {
      optional_nested("carpet_hsv", &V::carpet_hsv, carpet_keys()),
      optional_nested("line_contrast", &V::line_contrast, contrast_keys()),
      config::group<V>("goals", {optional_nested("blue", &V::goal_blue, goal_keys()),
                                 optional_nested("yellow", &V::goal_yellow, goal_keys())}),
      config::choice(
          "goal_colour_at_x_max", &V::goal_colour_at_x_max,
          config::Choices<std::string>{{"", ""}, {"blue", "blue"}, {"yellow", "yellow"}}),
      config::nested("goal_cue", &V::goal_cue, goal_cue_keys()),
      config::nested("extraction", &V::extraction, extraction_keys()),
  };
  return t;
}

void GoalCueConfig::validate(const config::Origin& at) const {
  config::require(min_pixels >= 1, at / "min_pixels", "must be >= 1", min_pixels);
  config::require(min_margin > 0.0 && min_margin <= 1.0, at / "min_margin", "must be in (0, 1]",
                  min_margin);
  config::require(post_margin_cm >= 0.0, at / "post_margin_cm", "must be >= 0", post_margin_cm);
  config::require(pixel_step >= 1 && pixel_step <= 16, at / "pixel_step", "must be in 1..16",
                  pixel_step);
}

bool GoalHsv::contains(int h, int s, int v) const {
  const double d = std::fmod(std::abs(h - hue), 180.0);
  return std::min(d, 180.0 - d) <= hue_half_width && s >= sat_min && v >= val_min;
}

void VisionModel::validate(const config::Origin& at) const {
  using config::require;
  goal_cue.validate(at / "goal_cue");
  if (carpet_hsv) {
    const config::Origin c = at / "carpet_hsv";
    check_hue(c, carpet_hsv->hue, carpet_hsv->hue_half_width);
    check_level(c, "sat_min", carpet_hsv->sat_min);
    check_level(c, "val_min", carpet_hsv->val_min);
    check_level(c, "val_max", carpet_hsv->val_max);
    require(carpet_hsv->val_max > carpet_hsv->val_min, c / "val_max",
            "must be above val_min " + config::show(carpet_hsv->val_min), carpet_hsv->val_max);
  }
  if (line_contrast) {
    const config::Origin c = at / "line_contrast";
    require(line_contrast->val_step > 0.0 && line_contrast->val_step <= 255.0, c / "val_step",
            "must be in (0, 255]", line_contrast->val_step);
    require(line_contrast->sat_step >= 0.0 && line_contrast->sat_step <= 255.0, c / "sat_step",
            "must be in [0, 255]", line_contrast->sat_step);
  }
  for (const auto& [name, g] : {std::pair{"blue", &goal_blue}, std::pair{"yellow", &goal_yellow}}) {
    if (!*g) continue;
    const config::Origin c = at / "goals" / name;
    check_hue(c, (*g)->hue, (*g)->hue_half_width);
    check_level(c, "sat_min", (*g)->sat_min);
    check_level(c, "val_min", (*g)->val_min);
  }
  const ExtractionParams& e = extraction;
  const config::Origin x = at / "extraction";
  require(e.end_run_px >= 1 && e.end_run_px <= 64, x / "end_run_px", "must be 1..64", e.end_run_px);
  require(e.carpet_resume_px >= 1 && e.carpet_resume_px <= 64, x / "carpet_resume_px",
          "must be 1..64", e.carpet_resume_px);
  require(e.obstacle_window_deg >= 0.0 && e.obstacle_window_deg <= 90.0, x / "obstacle_window_deg",
          "must be in [0, 90]", e.obstacle_window_deg);
  require(e.obstacle_step_px >= 1 && e.obstacle_step_px <= 254, x / "obstacle_step_px",
          "must be 1..254", e.obstacle_step_px);
  require(e.resume_within_px >= 1 && e.resume_within_px <= 254, x / "resume_within_px",
          "must be 1..254", e.resume_within_px);
  require(e.edge_fraction > 0.0 && e.edge_fraction < 1.0, x / "edge_fraction", "must be in (0, 1)",
          e.edge_fraction);
  require(e.carpet_mean_px >= 1 && e.carpet_mean_px <= 128, x / "carpet_mean_px", "must be 1..128",
          e.carpet_mean_px);
  require(e.sectors >= 1 && e.sectors <= 360, x / "sectors", "must be 1..360", e.sectors);
  require(e.light_follow >= 0.0 && e.light_follow <= 1.0, x / "light_follow", "must be in [0, 1]",
          e.light_follow);
  require(e.light_range >= 1.0 && e.light_range <= 16.0, x / "light_range", "must be in [1, 16]",
          e.light_range);
  require(e.val_sigmas > 0.0 && e.val_sigmas <= 20.0, x / "val_sigmas", "must be in (0, 20]",
          e.val_sigmas);
  require(e.sat_sigmas >= 0.0 && e.sat_sigmas <= 20.0, x / "sat_sigmas", "must be in [0, 20]",
          e.sat_sigmas);
  require(e.min_val_step > 0.0 && e.min_val_step <= 255.0, x / "min_val_step",
          "must be in (0, 255]", e.min_val_step);
  require(e.min_sat_step >= 0.0 && e.min_sat_step <= 255.0, x / "min_sat_step",
          "must be in [0, 255]", e.min_sat_step);
  require(e.min_carpet_fraction >= 0.0 && e.min_carpet_fraction <= 1.0, x / "min_carpet_fraction",
          "must be in [0, 1]", e.min_carpet_fraction);
  require(e.min_rays_seen >= 0.0 && e.min_rays_seen <= 1.0, x / "min_rays_seen",
          "must be in [0, 1]", e.min_rays_seen);
  require(e.min_crossings >= 0, x / "min_crossings", "must be >= 0", e.min_crossings);
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k =
      static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double robust_sigma(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const double med = percentile(v, 0.5);
  for (double& x : v) x = std::abs(x - med);
  return 1.4826 * percentile(std::move(v), 0.5);
}

namespace {

// The samples in the histogram's peak cell or next to it (8 deg hue, 16 levels of S and V), their
// hue unwrapped around the peak.
struct PeakCluster {
  std::vector<double> hs, ss, vs;
};

PeakCluster peak_cluster(const std::vector<cv::Vec3b>& samples) {
  constexpr int kHb = 45, kSb = 16, kVb = 16;  // 8 deg hue, 16 levels of S and V
  std::vector<int> hist(kHb * kSb * kVb, 0);
  for (const auto& p : samples)
    ++hist[static_cast<std::size_t>((p[0] / 4) * kSb * kVb + (p[1] / 16) * kVb + p[2] / 16)];
  const auto peak = static_cast<int>(std::max_element(hist.begin(), hist.end()) - hist.begin());
  const int ph = peak / (kSb * kVb), ps = (peak / kVb) % kSb, pv = peak % kVb;
  PeakCluster c;
  for (const auto& p : samples) {
    const int dh = std::abs(p[0] / 4 - ph);
    if (std::min(dh, kHb - dh) <= 1 && std::abs(p[1] / 16 - ps) <= 1 &&
        std::abs(p[2] / 16 - pv) <= 1) {
      double h = p[0];
      if (h - ph * 4 > 90) h -= 180;  // unwrap around the peak
      if (ph * 4 - h > 90) h += 180;
      c.hs.push_back(h);
      c.ss.push_back(p[1]);
      c.vs.push_back(p[2]);
    }
  }
  return c;
}

// Grey: the hue of a barely saturated pixel is noise (it scatters the histogram's peak), so the
// samples (one colour cluster already) are judged whole and the window is of brightness alone.
// nullopt when they are saturated enough to be a colour.
std::optional<CarpetColour> grey_carpet(const std::vector<cv::Vec3b>& samples) {
  std::vector<double> all_s, all_v;
  for (const auto& p : samples) {
    all_s.push_back(p[1]);
    all_v.push_back(p[2]);
  }
  if (!(percentile(all_s, 0.5) < 20.0)) return std::nullopt;
  CarpetColour g;
  g.hue_half_width = 90.0;
  g.median_sat = percentile(all_s, 0.5);
  g.median_val = percentile(all_v, 0.5);
  g.val_min = 0.5 * g.median_val;
  g.val_max = std::min(255.0, 1.5 * g.median_val);
  return g;
}

}  // namespace

std::optional<CarpetColour> carpet_colour_from_samples(const std::vector<cv::Vec3b>& samples,
                                                       std::string* why, bool allow_grey) {
  if (samples.empty()) {
    if (why) *why = "no carpet: no pixels next to the robot";
    return std::nullopt;
  }
  const PeakCluster pc = peak_cluster(samples);
  const std::vector<double>&hs = pc.hs, &ss = pc.ss, &vs = pc.vs;
  CarpetColour c;
  c.hue = std::fmod(percentile(hs, 0.5) + 180.0, 180.0);
  c.median_sat = percentile(ss, 0.5);
  c.median_val = percentile(vs, 0.5);
  // Hue: three robust sigmas, 4..20 units (8..40 deg). Saturation: down to three sigmas or a
  // quarter below the median. Value: half to 1.5 times the median (the renderer's +-20 % light
  // and the real frame's vignetting stay inside; the black floor beyond the carpet and bright
  // walls of the same hue do not).
  c.hue_half_width = std::clamp(3.0 * robust_sigma(hs), 4.0, 20.0);
  c.sat_min = c.median_sat - std::max(3.0 * robust_sigma(ss), 0.25 * c.median_sat);
  c.val_min = 0.5 * c.median_val;
  c.val_max = std::min(255.0, 1.5 * c.median_val);
  if (allow_grey) {
    if (auto g = grey_carpet(samples)) return g;
  }
  if (static_cast<double>(hs.size()) < 0.05 * static_cast<double>(samples.size()) ||
      c.median_sat < 20.0) {
    if (why) {
      *why = "no carpet: no dominant colour around the robot (hue " +
             std::to_string(static_cast<int>(2 * c.hue)) + " deg on " + std::to_string(hs.size()) +
             " of " + std::to_string(samples.size()) + " pixels, median saturation " +
             std::to_string(static_cast<int>(c.median_sat)) + ")";
    }
    return std::nullopt;
  }
  return c;
}

}  // namespace omniloc
