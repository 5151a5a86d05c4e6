// Single-frame localisation shared by the Localizer and `omniloc locate` (see locate.hpp).
#include "omniloc/locate.hpp"

#include <cmath>
#include <utility>

#include <opencv2/imgproc.hpp>

namespace omniloc {

MatchOptions match_options_of(const LocalizerConfig& config) {
  MatchOptions o;
  o.refinement = config.refinement;
  o.cost = config.match_cost;
  o.crossing_cap_px = config.crossing_cap_px;
  o.ambiguity_ratio = config.ambiguity_ratio;
  return o;
}

double judged_error(const LocalizerConfig& config, const MatchResult& m) {
  return config.refinement == Refinement::kRayCast ? m.refined_error : m.error;
}

namespace {

struct Candidate {
  Pose2 pose;
  MatchResult match;
};

// The second candidate made as good as the first: the heading found again near its hint (when the
// heading is searched), the position by a local search there at that heading, then the refinement.
Candidate refine_second(const LocalizerConfig& config, const FieldGeometry& field,
                        const CameraModel& camera, const FeatureDb& db, const BearingScan& bearings,
                        const Eigen::Vector2d& position_cm, double yaw_deg, bool search_yaw) {
  const MatchOptions opt = match_options_of(config);
  if (search_yaw)
    yaw_deg = wrap_deg(
        estimate_yaw(field, camera, bearings, position_cm, yaw_deg, kAnyYawStepDeg, opt).yaw_deg);
  const FieldScan scan = make_field_scan(bearings, yaw_deg);
  Candidate c;
  c.match = local_search(db, scan, position_cm, db.grid.step_cm, opt);
  apply_refinement(db, field, camera, scan, c.match, opt);
  c.match.error = judged_error(config, c.match);
  c.pose = {c.match.position_cm.x(), c.match.position_cm.y(), yaw_deg};
  return c;
}

// The other candidate the goal colours are asked about, if the lines alone cannot rule it out:
// without a heading, the twin (centre * 2 - p, yaw + 180: the same lines on a point-symmetric
// field, even at the centre spot where it shares the position); else, or when the twin is clearly
// worse, the matcher's second distinct minimum when it flagged the result ambiguous and it stays
// within the ambiguity ratio once refined (or replaces the best when clearly better).
struct Contender {
  Candidate candidate;
  /// clearly better than the best: the best is dropped, nothing is ambiguous
  bool replaces_best = false;
};

std::optional<Contender> contender(const LocalizerConfig& config, const FieldGeometry& field,
                                   const CameraModel& camera, const FeatureDb& db,
                                   const BearingScan& bearings, const Candidate& best,
                                   double second_yaw_deg, bool yaw_searched) {
  const double ratio = match_options_of(config).ambiguity_ratio;
  if (yaw_searched) {
    const Eigen::Vector2d mirrored = 2.0 * field.centre_cm() - best.match.position_cm;
    Candidate twin = refine_second(config, field, camera, db, bearings, mirrored,
                                   wrap_deg(best.pose.yaw_deg + 180.0), true);
    if (twin.match.cell >= 0 && twin.match.error <= ratio * best.match.error)
      return Contender{twin, false};
  }
  if (best.match.ambiguous && std::isfinite(best.match.second_error)) {
    // Flagged on the grid errors; compared as the best is judged, after the refinement (a grid
    // point 5 cm from the robot often scores well above its refined error, so the grid errors
    // alone say little): a clearly worse second is no contender, a clearly better one replaces it.
    const Candidate second =
        refine_second(config, field, camera, db, bearings, best.match.second_position_cm,
                      second_yaw_deg, yaw_searched);
    if (second.match.cell < 0 || second.match.error > ratio * best.match.error) return std::nullopt;
    return Contender{second, second.match.error * ratio < best.match.error};
  }
  return std::nullopt;
}

}  // namespace

namespace {
// The global search's best: over every heading when none is known (second_yaw_deg the runner-up's
// heading), else at the heading given (the scan at_yaw, made when not given), refined.
Candidate best_candidate(const FieldGeometry& field, const CameraModel& camera, const FeatureDb& db,
                         const BearingScan& bearings, std::optional<double> yaw_deg,
                         const FieldScan* at_yaw, const MatchOptions& opt, double& second_yaw_deg) {
  Candidate best;
  if (!yaw_deg) {
    const PoseMatch pm = global_search_any_yaw(db, field, camera, bearings, kAnyYawStepDeg, opt);
    best = {{pm.match.position_cm.x(), pm.match.position_cm.y(), pm.yaw_deg}, pm.match};
    second_yaw_deg = pm.second_yaw_deg;
    return best;
  }
  FieldScan made;
  if (at_yaw == nullptr) {
    made = make_field_scan(bearings, *yaw_deg);
    at_yaw = &made;
  }
  best.match = global_search(db, *at_yaw, opt);
  apply_refinement(db, field, camera, *at_yaw, best.match, opt);
  best.pose = {best.match.position_cm.x(), best.match.position_cm.y(), at_yaw->yaw_deg};
  second_yaw_deg = at_yaw->yaw_deg;
  return best;
}
}  // namespace

SingleFrameResult locate_frame(const LocalizerConfig& config, const FieldGeometry& field,
                               const CameraModel& camera, const FeatureDb& db,
                               const BearingScan& bearings, std::optional<double> yaw_deg,
                               const GoalObservation* goals, const FieldScan* at_yaw) {
  const MatchOptions opt = match_options_of(config);
  SingleFrameResult r;
  double second_yaw_deg = 0.0;
  r.yaw_searched = !yaw_deg;
  Candidate best =
      best_candidate(field, camera, db, bearings, yaw_deg, at_yaw, opt, second_yaw_deg);
  best.match.error = judged_error(config, best.match);
  std::optional<Contender> found;
  if (best.match.cell >= 0)
    found = contender(config, field, camera, db, bearings, best, second_yaw_deg, r.yaw_searched);
  std::optional<Candidate> other;
  if (found && found->replaces_best) {
    best = found->candidate;
  } else if (found) {
    other = found->candidate;
  }
  r.lines_ambiguous = other.has_value();
  r.ambiguous = r.lines_ambiguous;
  if (other) {
    if (goals != nullptr) {
      r.goal_choice = choose_by_goals(field, best.pose, other->pose, *goals);
    } else {
      r.goal_choice.reason = "no goal observation";
    }
    if (r.goal_choice.decision == TwinDecision::kSecond) std::swap(best, *other);
    r.ambiguous = r.goal_choice.decision == TwinDecision::kUndecided;
    r.twin = other->pose;
    r.twin_error = other->match.error;
  } else {
    r.goal_choice.reason = "not needed (the lines alone are not ambiguous)";
  }
  if (r.ambiguous && r.twin &&
      (r.twin->position_cm() - best.pose.position_cm()).norm() <
          MatchOptions{}.ambiguity_separation_cm) {
    r.ambiguous = false;
    r.heading_ambiguous = true;
  }
  best.match.ambiguous = r.ambiguous;
  r.pose = best.pose;
  r.match = best.match;
  r.accepted = r.match.error < config.e_th && !(config.refuse_ambiguous && r.ambiguous);
  return r;
}

namespace {

cv::Point pixel_at(const CameraModel& camera, double radius_px, double bearing_deg) {
  const double phi = deg_to_rad(camera.image_angle_deg(bearing_deg));
  const double du = radius_px * std::cos(phi);
  return {static_cast<int>(std::lround(camera.center_px.x() + (camera.mirrored ? -du : du))),
          static_cast<int>(std::lround(camera.center_px.y() - radius_px * std::sin(phi)))};
}

void put(cv::Mat& img, const cv::Point& p, const cv::Vec3b& colour) {
  if (p.x >= 0 && p.y >= 0 && p.x < img.cols && p.y < img.rows) img.at<cv::Vec3b>(p) = colour;
}

// The lines (and the goal boxes) at `pose`, every field point through the camera's radius table.
void draw_field_model(cv::Mat& out, const CameraModel& camera, const FieldGeometry& field,
                      const Pose2& pose, const cv::Vec3b& colour) {
  auto draw = [&](const Eigen::Vector2d& q) {
    if (const auto px =
            camera.pixel_of_robot_point(field_to_robot(q - pose.position_cm(), pose.yaw_deg))) {
      if (std::hypot(px->x() - camera.center_px.x(), px->y() - camera.center_px.y()) >=
          camera.min_radius_px())
        put(out, {static_cast<int>(std::lround(px->x())), static_cast<int>(std::lround(px->y()))},
            colour);
    }
  };
  auto segment = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const double len = (b - a).norm();
    for (double t = 0; t <= len; t += 1.0) draw(a + (b - a) * (t / len));
  };
  for_each_line_point(field, 1.0, draw);
  for (const auto& d : field.discs) draw(d.centre_cm);
  const double cy = field.centre_cm().y(), w = field.goal.width_cm / 2.0;
  for (const double x : {field.border_cm, field.border_cm + field.field_length_cm}) {
    const double back =
        x < field.centre_cm().x() ? x - field.goal.depth_cm : x + field.goal.depth_cm;
    segment({x, cy - w}, {back, cy - w});
    segment({back, cy - w}, {back, cy + w});
    segment({back, cy + w}, {x, cy + w});
  }
}

}  // namespace

cv::Mat locate_overlay(const cv::Mat& bgr, const CameraModel& camera, const FieldGeometry& field,
                       const LocateOverlayInput& in) {
  cv::Mat out = bgr.clone();
  const double view = camera.view_radius_px(), r0 = camera.min_radius_px();
  if (in.bearings != nullptr) {
    const BearingScan& s = *in.bearings;
    const int rays = kScanRays * s.rays_per_degree;
    for (int j = 0; j < rays; ++j) {
      const double b = static_cast<double>(j) / s.rays_per_degree;
      const std::uint8_t end = s.ray_end_px[static_cast<std::size_t>(j)];
      if (end == kRayHidden) continue;
      const double step =
          camera.scan_step_px();  // the scan's radii are sample indices (line_scan.hpp)
      const double r_end = end == kRayToViewEnd ? view : end * step;
      if (j % s.rays_per_degree == 0)
        cv::line(out, pixel_at(camera, r0, b), pixel_at(camera, r_end, b), {110, 110, 110}, 1);
      for (int n = 0; n < kCrossingsPerRay; ++n) {
        const std::uint8_t r = s.radii_px[static_cast<std::size_t>(j * kCrossingsPerRay + n)];
        if (r != kNoCrossing && r * step < r_end)
          put(out, pixel_at(camera, r * step, b), {255, 0, 255});
      }
      if (end != kRayToViewEnd)
        put(out, pixel_at(camera, r_end, b), {0, 0, 255});  // carpet boundary / obstacle
    }
  }
  if (in.goals != nullptr) {
    for (const auto& p : in.goals->pixels) {
      put(out, pixel_at(camera, p.radius_px, p.bearing_deg),
          p.colour == GoalColour::kBlue ? cv::Vec3b{255, 80, 0} : cv::Vec3b{0, 220, 255});
    }
  }
  if (in.result != nullptr) {
    if (in.result->twin) draw_field_model(out, camera, field, *in.result->twin, {255, 255, 0});
    if (in.result->match.cell >= 0)
      draw_field_model(out, camera, field, in.result->pose, {0, 255, 255});
  }
  const cv::Point c(static_cast<int>(std::lround(camera.center_px.x())),
                    static_cast<int>(std::lround(camera.center_px.y())));
  cv::circle(out, c, static_cast<int>(std::lround(view)), {0, 255, 0}, 1, cv::LINE_AA);
  return out;
}

}  // namespace omniloc
