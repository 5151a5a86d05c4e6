// The calibration's self-check (docs/CALIBRATION.md, step 8): how much of the field's lines the
// camera puts on the frame's carpet the frame shows there as lines. The residual only measures the
// line pixels the fit kept; a wrong rim or a carpet edge taken for a line can fit a few of them
// well while the rest of the model lands on bare carpet. Reported, not yet a refusal (no threshold
// separates the cameras measured so far).
#include "self_check.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

namespace omniloc::detail {

LineRecall model_line_recall(const CameraModel& camera, const FrameAnalysis& analysis,
                             const Pose2& pose, const FieldGeometry& field) {
  // A line point is expected where carpet lies within 4 px of it (the painted strip itself is not
  // carpet), and seen where a line pixel lies within 3 px (the line's width and the fit's
  // residual).
  cv::Mat near_carpet, near_line;
  cv::dilate(analysis.carpet_mask, near_carpet, cv::getStructuringElement(cv::MORPH_RECT, {9, 9}));
  cv::dilate(analysis.line_mask, near_line, cv::getStructuringElement(cv::MORPH_RECT, {7, 7}));
  const double r_min = camera.body_radius_px + 2.0, r_max = camera.view_radius_px();
  LineRecall out;
  constexpr double kStepCm = 2.0;
  for_each_line_point(field, kStepCm, [&](const Eigen::Vector2d& q) {
    const Eigen::Vector2d robot = field_to_robot(q - pose.position_cm(), pose.yaw_deg);
    if (camera.bearing_hidden(rad_to_deg(std::atan2(robot.y(), robot.x())))) return;
    const auto px = camera.pixel_of_robot_point(robot);
    if (!px) return;
    const double r = (*px - camera.center_px).norm();
    if (r < r_min || r > r_max) return;
    const int u = static_cast<int>(std::lround(px->x())),
              v = static_cast<int>(std::lround(px->y()));
    if (u < 0 || v < 0 || u >= near_carpet.cols || v >= near_carpet.rows ||
        !near_carpet.at<std::uint8_t>(v, u))
      return;
    ++out.expected;
    out.seen += near_line.at<std::uint8_t>(v, u) != 0;
  });
  return out;
}

}  // namespace omniloc::detail
