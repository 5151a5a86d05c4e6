// Goal colours as the twin cue (see goals.hpp).
#include "omniloc/goals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "omniloc/detail/config_reader.hpp"

namespace omniloc {

GoalColourModels goal_colour_models(const VisionModel& vision) {
  GoalColourModels m;
  m.blue = vision.goal_blue;
  m.yellow = vision.goal_yellow;
  if (vision.goal_colour_at_x_max == "blue") m.colour_at_x_max = GoalColour::kBlue;
  if (vision.goal_colour_at_x_max == "yellow") m.colour_at_x_max = GoalColour::kYellow;
  m.cue = vision.goal_cue;
  return m;
}

GoalColour goal_colour_at_x_max(const FieldGeometry& field, const GoalColourModels& models) {
  return field.goal.colour_at_x_max != GoalColour::kUnknown ? field.goal.colour_at_x_max
                                                            : models.colour_at_x_max;
}

GoalObservation observe_goals(const cv::Mat& bgr, const CameraModel& camera,
                              const FieldGeometry& field, const GoalColourModels& models) {
  if (bgr.empty() || bgr.type() != CV_8UC3 || bgr.cols != camera.width_px ||
      bgr.rows != camera.height_px) {
    std::ostringstream os;
    os << "observe_goals: image " << bgr.cols << " x " << bgr.rows
       << " does not match the camera's " << camera.width_px << " x " << camera.height_px
       << " (8-bit BGR)";
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
      if (models.blue && models.blue->contains(p[0], p[1], p[2]))
        c = GoalColour::kBlue;
      else if (models.yellow && models.yellow->contains(p[0], p[1], p[2]))
        c = GoalColour::kYellow;
      if (c == GoalColour::kUnknown) continue;
      const double du = u - camera.center_px.x(), dv = camera.center_px.y() - v;
      const double r = std::hypot(du, dv);
      if (r < r_min) continue;
      // Inverse of the camera's projection (camera.hpp): phi = bearing + yaw offset.
      const double phi = rad_to_deg(std::atan2(dv, camera.mirrored ? -du : du));
      const double bearing = wrap_deg(phi - camera.yaw_offset_deg);
      if (camera.bearing_hidden(bearing)) continue;
      const double d = camera.ground_cm_at_radius(r);
      obs.pixels.push_back(
          {static_cast<float>(bearing),
           std::isfinite(d) ? static_cast<float>(d) : std::numeric_limits<float>::infinity(),
           static_cast<float>(r), c});
    }
  }
  return obs;
}

namespace {

// Does the ray from `pose` along robot bearing b reach beyond the goal line at one end inside the
// goal mouth (widened by the margin), before the pixel's floor distance?
bool beyond_goal_line(const FieldGeometry& field, const Pose2& pose, const GoalPixel& px,
                      bool at_x_max, double margin_cm) {
  const Eigen::Vector2d dir = robot_to_field(
      {std::cos(deg_to_rad(px.bearing_deg)), std::sin(deg_to_rad(px.bearing_deg))}, pose.yaw_deg);
  const double x_line = at_x_max ? field.border_cm + field.field_length_cm : field.border_cm;
  if (std::abs(dir.x()) < 1e-9) return false;
  const double t = (x_line - pose.x_cm) / dir.x();
  if (!(t > 0.0) || !(px.ground_cm >= t - margin_cm)) return false;
  const double y = pose.y_cm + t * dir.y();
  return std::abs(y - field.centre_cm().y()) <= field.goal.width_cm / 2.0 + margin_cm;
}

GoalColour other(GoalColour c) {
  return c == GoalColour::kBlue ? GoalColour::kYellow : GoalColour::kBlue;
}

}  // namespace

GoalEvidence goal_evidence(const FieldGeometry& field, const Pose2& pose,
                           const GoalObservation& obs) {
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

TwinChoice choose_by_goals(const FieldGeometry& field, const Pose2& first, const Pose2& second,
                           const GoalObservation& obs) {
  TwinChoice c;
  if (!obs.colours_known) {
    c.reason = "goal colours unknown (no colour model, or which colour is at x = max not known)";
    return c;
  }
  c.first = goal_evidence(field, first, obs);
  c.second = goal_evidence(field, second, obs);
  const int considered = std::max(c.first.considered(), c.second.considered());
  std::ostringstream os;
  os << considered << " goal-coloured samples beyond the goal lines (first " << c.first.agreeing
     << " agree / " << c.first.contrary << " contrary, second " << c.second.agreeing << " / "
     << c.second.contrary << ")";
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
