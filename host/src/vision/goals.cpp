// Goal colours as the twin cue (see goals.hpp).
#include "omniloc/goals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "omniloc/config_reader.hpp"

namespace omniloc {

bool HsvRange::contains(int h, int s, int v) const {
  const double d = std::fmod(std::abs(h - hue), 180.0);
  return std::min(d, 180.0 - d) <= hue_half_width && s >= sat_min && v >= val_min;
}

void HsvRange::validate(const config::Origin& at) const {
  config::require(hue >= 0 && hue <= 179, at / "hue", "must be an OpenCV hue 0..179", hue);
  config::require(hue_half_width >= 0 && hue_half_width < 90, at / "hue_half_width", "must be in 0..89", hue_half_width);
  config::require(sat_min >= 0 && sat_min <= 255, at / "sat_min", "must be in 0..255", sat_min);
  config::require(val_min >= 0 && val_min <= 255, at / "val_min", "must be in 0..255", val_min);
}

void GoalCueConfig::validate(const config::Origin& at) const {
  config::require(min_pixels >= 1, at / "min_pixels", "must be >= 1", min_pixels);
  config::require(min_margin > 0.0 && min_margin <= 1.0, at / "min_margin", "must be in (0, 1]", min_margin);
  config::require(post_margin_cm >= 0.0, at / "post_margin_cm", "must be >= 0", post_margin_cm);
  config::require(pixel_step >= 1 && pixel_step <= 16, at / "pixel_step", "must be in 1..16", pixel_step);
}

namespace {

const config::KeyTable<HsvRange>& hsv_keys() {
  using config::key;
  using config::Need;
  static const config::KeyTable<HsvRange> table = {
      key("hue", &HsvRange::hue, Need::kRequired),
      key("hue_half_width", &HsvRange::hue_half_width, Need::kRequired),
      key("sat_min", &HsvRange::sat_min, Need::kRequired),
      key("val_min", &HsvRange::val_min, Need::kRequired),
  };
  return table;
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

std::optional<HsvRange> read_hsv(const config::Node& goals, std::string_view name) {
  if (!goals.has(name)) return std::nullopt;
  const config::Node n = goals / name;
  HsvRange r;
  config::read_keys(n, hsv_keys(), r);
  r.validate(n.origin());
  return r;
}

}  // namespace

GoalColourModels goal_colour_models_from_vision(const config::Node& vision) {
  vision.expect_object();
  GoalColourModels m;
  if (vision.has("goals")) {
    const config::Node goals = vision / "goals";
    goals.expect_object();
    for (auto it = goals.json().begin(); it != goals.json().end(); ++it)
      if (it.key() != "blue" && it.key() != "yellow") (goals / it.key()).fail("unknown key (known keys: blue, yellow)");
    m.blue = read_hsv(goals, "blue");
    m.yellow = read_hsv(goals, "yellow");
  }
  if (vision.has("goal_colour_at_x_max"))
    m.colour_at_x_max = config::read_choice(vision / "goal_colour_at_x_max",
                                            config::Choices<GoalColour>{{"blue", GoalColour::kBlue}, {"yellow", GoalColour::kYellow}});
  if (vision.has("goal_cue")) {
    const config::Node cue = vision / "goal_cue";
    config::read_keys(cue, goal_cue_keys(), m.cue);
    m.cue.validate(cue.origin());
  }
  return m;
}

CameraWithGoals load_camera_with_goals(const std::string& name_or_path) {
  config::Document doc = config::parse_json_file(resolve_data_file("cameras", name_or_path));
  CameraWithGoals out;
  if (doc.json.is_object() && doc.json.contains("vision")) {
    out.goals = goal_colour_models_from_vision(doc.root() / "vision");
    doc.json.erase("vision");
  }
  out.camera = camera_from_json(doc.root());
  return out;
}

GoalColour goal_colour_at_x_max(const FieldGeometry& field, const GoalColourModels& models) {
  return field.goal.colour_at_x_max != GoalColour::kUnknown ? field.goal.colour_at_x_max : models.colour_at_x_max;
}

GoalObservation observe_goals(const cv::Mat& bgr, const CameraModel& camera, const FieldGeometry& field,
                              const GoalColourModels& models) {
  if (bgr.empty() || bgr.type() != CV_8UC3 || bgr.cols != camera.width_px || bgr.rows != camera.height_px) {
    std::ostringstream os;
    os << "observe_goals: image " << bgr.cols << " x " << bgr.rows << " does not match the camera's " << camera.width_px
       << " x " << camera.height_px << " (8-bit BGR)";
    throw std::invalid_argument(os.str());
  }
  GoalObservation obs;
  obs.cue = models.cue;
  obs.colour_at_x_max = goal_colour_at_x_max(field, models);
  obs.colours_known = (models.blue || models.yellow) && obs.colour_at_x_max != GoalColour::kUnknown;
  if (!obs.colours_known) return obs;
  cv::Mat hsv;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  const double r_min = camera.min_radius_px();
  const int step = models.cue.pixel_step;
  for (int v = 0; v < hsv.rows; v += step) {
    const cv::Vec3b* row = hsv.ptr<cv::Vec3b>(v);
    for (int u = 0; u < hsv.cols; u += step) {
      const cv::Vec3b p = row[u];
      GoalColour c = GoalColour::kUnknown;
      if (models.blue && models.blue->contains(p[0], p[1], p[2])) c = GoalColour::kBlue;
      else if (models.yellow && models.yellow->contains(p[0], p[1], p[2])) c = GoalColour::kYellow;
      if (c == GoalColour::kUnknown) continue;
      const double du = u - camera.center_px.x(), dv = camera.center_px.y() - v;
      const double r = std::hypot(du, dv);
      if (r < r_min) continue;
      // Inverse of the camera's projection (camera.hpp): phi = bearing + yaw offset.
      const double phi = rad_to_deg(std::atan2(dv, camera.mirrored ? -du : du));
      const double bearing = wrap_deg(phi - camera.yaw_offset_deg);
      if (camera.bearing_hidden(bearing)) continue;
      const double d = camera.ground_cm_at_radius(r);
      obs.pixels.push_back({static_cast<float>(bearing),
                            std::isfinite(d) ? static_cast<float>(d) : std::numeric_limits<float>::infinity(),
                            static_cast<float>(r), c});
    }
  }
  return obs;
}

namespace {

// Does the ray from `pose` along robot bearing b reach beyond the goal line at one end inside the
// goal mouth (widened by the margin), before the pixel's floor distance?
bool beyond_goal_line(const FieldGeometry& field, const Pose2& pose, const GoalPixel& px, bool at_x_max, double margin_cm) {
  const Eigen::Vector2d dir = robot_to_field({std::cos(deg_to_rad(px.bearing_deg)), std::sin(deg_to_rad(px.bearing_deg))},
                                             pose.yaw_deg);
  const double x_line = at_x_max ? field.border_cm + field.field_length_cm : field.border_cm;
  if (std::abs(dir.x()) < 1e-9) return false;
  const double t = (x_line - pose.x_cm) / dir.x();
  if (!(t > 0.0) || !(px.ground_cm >= t - margin_cm)) return false;
  const double y = pose.y_cm + t * dir.y();
  return std::abs(y - field.centre_cm().y()) <= field.goal.width_cm / 2.0 + margin_cm;
}

GoalColour other(GoalColour c) { return c == GoalColour::kBlue ? GoalColour::kYellow : GoalColour::kBlue; }

}  // namespace

GoalEvidence goal_evidence(const FieldGeometry& field, const Pose2& pose, const GoalObservation& obs) {
  GoalEvidence e;
  if (!obs.colours_known) return e;
  for (const auto& px : obs.pixels) {
    for (const bool at_x_max : {true, false}) {
      if (!beyond_goal_line(field, pose, px, at_x_max, obs.cue.post_margin_cm)) continue;
      const GoalColour expected = at_x_max ? obs.colour_at_x_max : other(obs.colour_at_x_max);
      (px.colour == expected ? e.agreeing : e.contrary) += 1;
      break;  // a ray crosses at most one goal line in front of the robot
    }
  }
  return e;
}

TwinChoice choose_by_goals(const FieldGeometry& field, const Pose2& first, const Pose2& second, const GoalObservation& obs) {
  TwinChoice c;
  if (!obs.colours_known) {
    c.reason = "goal colours unknown (no colour model, or which colour is at x = max not known)";
    return c;
  }
  c.first = goal_evidence(field, first, obs);
  c.second = goal_evidence(field, second, obs);
  const int considered = std::max(c.first.considered(), c.second.considered());
  std::ostringstream os;
  os << considered << " goal-coloured samples beyond the goal lines (first " << c.first.agreeing << " agree / "
     << c.first.contrary << " contrary, second " << c.second.agreeing << " / " << c.second.contrary << ")";
  if (considered < obs.cue.min_pixels) {
    c.reason = "weak evidence: " + os.str() + ", fewer than " + std::to_string(obs.cue.min_pixels);
    return c;
  }
  c.margin = (c.first.score() - c.second.score()) / (2.0 * considered);
  os << ", margin " << c.margin;
  if (std::abs(c.margin) < obs.cue.min_margin) {
    c.reason = "weak evidence: " + os.str() + " below " + config::show(obs.cue.min_margin);
    return c;
  }
  c.decision = c.margin > 0.0 ? TwinDecision::kFirst : TwinDecision::kSecond;
  c.reason = os.str();
  return c;
}

}  // namespace omniloc
