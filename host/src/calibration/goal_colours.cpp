// Goal colours of a venue (issue 13 items 1 and 4): the blue and the yellow goal regions of a
// frame, their HSV classes, and which one is at the field's x = max end.
#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "omniloc/calibration.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

namespace {

// Largest opened connected region of `band` pixels, and its colour class.
std::optional<GoalRegion> largest_region(const cv::Mat& hsv, const cv::Mat& band,
                                         double min_pixels) {
  cv::Mat opened, labels, stats, centroids;
  cv::morphologyEx(band, opened, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  const int n = cv::connectedComponentsWithStats(opened, labels, stats, centroids, 8, CV_32S);
  int best = 0;
  for (int k = 1; k < n; ++k)
    if (best == 0 || stats.at<int>(k, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA))
      best = k;
  if (best == 0 || stats.at<int>(best, cv::CC_STAT_AREA) < min_pixels) return std::nullopt;
  std::vector<double> hs, ss, vs;
  for (int v = 0; v < labels.rows; ++v)
    for (int u = 0; u < labels.cols; ++u)
      if (labels.at<int>(v, u) == best) {
        const auto& p = hsv.at<cv::Vec3b>(v, u);
        hs.push_back(p[0]);
        ss.push_back(p[1]);
        vs.push_back(p[2]);
      }
  GoalRegion g;
  g.pixels = stats.at<int>(best, cv::CC_STAT_AREA);
  g.centroid_px = {centroids.at<double>(best, 0), centroids.at<double>(best, 1)};
  g.mask = labels == best;
  g.colour.hue = percentile(hs, 0.5);
  // Three robust sigmas, at least 4 hue units (JPEG and noise spread paint that much).
  g.colour.hue_half_width = std::max(4.0, 3.0 * robust_sigma(hs));
  g.colour.sat_min = 0.8 * percentile(ss, 0.05);
  g.colour.val_min = 0.8 * percentile(vs, 0.05);
  return g;
}

}  // namespace

GoalColours measure_goal_colours(const cv::Mat& bgr, const FrameAnalysis& a,
                                 const GoalColourOptions& o) {
  cv::Mat hsv;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::Mat blue = cv::Mat::zeros(bgr.size(), CV_8U), yellow = cv::Mat::zeros(bgr.size(), CV_8U);
  const Eigen::Vector2d c = a.rim.centre_px;
  for (int v = 0; v < hsv.rows; ++v) {
    for (int u = 0; u < hsv.cols; ++u) {
      const double r = std::hypot(u - c.x(), v - c.y());
      if (r > a.rim.radius_px || r < a.body_radius_px) continue;
      if (!a.carpet_mask.empty() && a.carpet_mask.at<std::uint8_t>(v, u)) continue;
      const auto& p = hsv.at<cv::Vec3b>(v, u);
      if (p[1] < o.sat_min || p[2] < o.val_min) continue;
      // The carpet's hue, darker or paler than its class (vignetting, shadows), is still carpet:
      // a teal carpet otherwise bleeds into the blue band.
      const double dh = std::abs(p[0] - a.carpet.hue);
      if (std::min(dh, 180.0 - dh) <= 2.0 * a.carpet.hue_half_width) continue;
      if (p[0] >= o.blue_hue_min && p[0] <= o.blue_hue_max) blue.at<std::uint8_t>(v, u) = 255;
      if (p[0] >= o.yellow_hue_min && p[0] <= o.yellow_hue_max) yellow.at<std::uint8_t>(v, u) = 255;
    }
  }
  const double min_pixels = o.min_area_fraction * kPi * a.rim.radius_px * a.rim.radius_px;
  return {largest_region(hsv, blue, min_pixels), largest_region(hsv, yellow, min_pixels)};
}

GoalColour goal_colour_at_x_max(const GoalColours& goals, const CameraModel& cam,
                                const Eigen::Vector2d& pos, double yaw_deg,
                                const FieldGeometry& field) {
  const Eigen::Vector2d g_max(field.border_cm + field.field_length_cm, field.centre_cm().y());
  const Eigen::Vector2d g_min(field.border_cm, field.centre_cm().y());
  const double to_max = rad_to_deg(std::atan2(g_max.y() - pos.y(), g_max.x() - pos.x()));
  const double to_min = rad_to_deg(std::atan2(g_min.y() - pos.y(), g_min.x() - pos.x()));
  // +1: the region lies towards the x = max goal, -1: towards the other, 0: not seen.
  auto side = [&](const std::optional<GoalRegion>& g) {
    if (!g) return 0;
    const double du = (g->centroid_px.x() - cam.center_px.x()) * (cam.mirrored ? -1.0 : 1.0);
    const double phi = rad_to_deg(std::atan2(cam.center_px.y() - g->centroid_px.y(), du));
    const double field_angle = phi - cam.yaw_offset_deg + yaw_deg;
    return std::abs(angle_diff_deg(field_angle, to_max)) <
                   std::abs(angle_diff_deg(field_angle, to_min))
               ? 1
               : -1;
  };
  const int b = side(goals.blue), y = side(goals.yellow);
  if (b != 0 && y != 0 && b == y) return GoalColour::kUnknown;  // both on one side: do not guess
  if (b != 0) return b > 0 ? GoalColour::kBlue : GoalColour::kYellow;
  if (y != 0) return y > 0 ? GoalColour::kYellow : GoalColour::kBlue;
  return GoalColour::kUnknown;
}

}  // namespace omniloc
