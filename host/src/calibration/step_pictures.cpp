// Drawing of the calibration's step pictures (step_pictures.hpp).
#include "step_pictures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

namespace omniloc::detail {

namespace {

// The frame at 40 % brightness: drawn marks in saturated colours stand out, and no frame pixel
// can equal them (every channel stays <= 102).
cv::Mat dimmed(const cv::Mat& bgr) {
  cv::Mat out;
  bgr.convertTo(out, CV_8UC3, 0.4);
  return out;
}

void caption(cv::Mat& img, const std::string& text, cv::Point at) {
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
}

cv::Point rounded(const Eigen::Vector2d& p) {
  return {static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))};
}

// One handedness's heat map: low scores hot. The colour scale runs from the panel's best score
// to the truncation (every pixel missing), so the basin shows whatever the venue's contrast.
cv::Mat coarse_panel(const cv::Mat1f& score_px, double trunc_px) {
  double lo = 0.0, hi = 0.0;
  cv::Point best;
  cv::minMaxLoc(score_px, &lo, &hi, &best, nullptr);
  const double span = std::max(1e-6, trunc_px - lo);
  cv::Mat1b level(score_px.size());
  for (int y = 0; y < score_px.rows; ++y)
    for (int x = 0; x < score_px.cols; ++x)
      level(y, x) = cv::saturate_cast<std::uint8_t>(255.0 * (1.0 - (score_px(y, x) - lo) / span));
  cv::flip(level, level, 0);  // small scales at the bottom
  cv::Mat heat;
  cv::applyColorMap(level, heat, cv::COLORMAP_INFERNO);
  cv::resize(heat, heat, cv::Size(), kCoarseCellPx, kCoarseCellPx, cv::INTER_NEAREST);
  const int y_best = score_px.rows - 1 - best.y;
  cv::rectangle(heat,
                cv::Rect(best.x * kCoarseCellPx - 1, y_best * kCoarseCellPx - 1, kCoarseCellPx + 2,
                         kCoarseCellPx + 2),
                cv::Scalar(255, 255, 255), 1);
  return heat;
}

}  // namespace

cv::Mat disc_picture(const cv::Mat& bgr, const RimCircle& rim) {
  cv::Mat out = bgr.clone();
  char text[96];
  std::snprintf(text, sizeof text, "rim (%.1f, %.1f) r %.1f px, %d/360 rays", rim.centre_px.x(),
                rim.centre_px.y(), rim.radius_px, rim.rays_on_circle);
  caption(out, text, {4, 14});  // first: the circle is drawn over it where they meet
  const cv::Scalar colour(kRimColour[0], kRimColour[1], kRimColour[2]);
  // Not antialiased: the circle's pixels keep the exact colour (a test finds them at the radius).
  cv::circle(out, rounded(rim.centre_px), static_cast<int>(std::lround(rim.radius_px)), colour, 1,
             cv::LINE_8);
  cv::drawMarker(out, rounded(rim.centre_px), colour, cv::MARKER_CROSS, 12, 1, cv::LINE_8);
  return out;
}

cv::Mat lines_picture(const cv::Mat& bgr, const cv::Mat& line_mask) {
  cv::Mat out = dimmed(bgr);
  out.setTo(cv::Scalar(kLineColour[0], kLineColour[1], kLineColour[2]), line_mask);
  return out;
}

cv::Mat polar_picture(const PolarClasses& polar, double body_radius_px, double view_radius_px,
                      const std::vector<bool>& mast_bins) {
  const int rows = 360, cols = std::max(1, polar.radii_px);
  cv::Mat3b out(rows, cols, cv::Vec3b(0, 0, 0));
  const int bins_per_row = std::max(1, polar.angle_bins / rows);
  for (int row = 0; row < rows && polar.radii_px > 0; ++row) {
    const int bin = row * bins_per_row;
    const bool mast = static_cast<std::size_t>(bin) < mast_bins.size() &&
                      mast_bins[static_cast<std::size_t>(bin)];
    for (int r = 0; r < polar.radii_px; ++r) {
      const std::uint8_t c = polar.at(bin, r);
      cv::Vec3b px = c == 2 ? kPolarLine : (c == 1 ? kPolarCarpet : kPolarOther);
      // Tints, not replacements: the classes stay readable under the body and the masts.
      if (r < body_radius_px)
        px = cv::Vec3b(px[0] / 2, px[1] / 2, static_cast<std::uint8_t>(px[2] / 2 + 110));
      else if (mast)
        px = cv::Vec3b(static_cast<std::uint8_t>(px[0] / 2 + 110), px[1] / 2, px[2] / 2);
      out(row, r) = px;
    }
  }
  auto mark = [&](double r_px, const cv::Vec3b& colour) {
    const int col = static_cast<int>(std::lround(r_px));
    if (r_px > 0.0 && col < cols) out.col(col).setTo(cv::Scalar(colour[0], colour[1], colour[2]));
  };
  mark(body_radius_px, kBodyMark);
  mark(view_radius_px, kViewMark);
  return out;
}

cv::Mat coarse_picture(const CoarseGrid& grid, double trunc_px) {
  const cv::Size cells = grid.score_px[0].size();
  const int panel_w = cells.width * kCoarseCellPx, panel_h = cells.height * kCoarseCellPx;
  cv::Mat out(2 * (kCoarseCaptionPx + panel_h) + kCoarseFooterPx, panel_w, CV_8UC3,
              cv::Scalar(0, 0, 0));
  for (int mir = 0; mir < 2; ++mir) {
    const cv::Mat1f& s = grid.score_px[mir];
    if (s.empty()) continue;
    double lo = 0.0;
    cv::Point best;
    cv::minMaxLoc(s, &lo, nullptr, &best, nullptr);
    const int top = mir * (kCoarseCaptionPx + panel_h);
    char text[128];
    std::snprintf(text, sizeof text, "%s: best %.2f px at heading term %.0f deg, d(view) %.0f cm",
                  mir ? "mirrored" : "not mirrored", lo, best.x * grid.heading_step_deg,
                  CoarseGrid::view_cm(best.y));
    caption(out, text, {4, top + 16});
    coarse_panel(s, trunc_px).copyTo(out(cv::Rect(0, top + kCoarseCaptionPx, panel_w, panel_h)));
  }
  char legend[128];
  std::snprintf(legend, sizeof legend,
                "x: heading term 0..360 deg; y: d(view) %.0f cm..%.0f m; hot = good",
                CoarseGrid::view_cm(0), CoarseGrid::view_cm(CoarseGrid::kScales - 1) / 100.0);
  caption(out, legend, {4, out.rows - 6});
  return out;
}

cv::Mat residuals_picture(const cv::Mat& bgr, const std::vector<Eigen::Vector2d>& pixels,
                          const std::vector<double>& residuals_px, double inlier_threshold_px) {
  cv::Mat out = dimmed(bgr);
  char text[96];
  std::snprintf(text, sizeof text,
                "residual: green <= 1 px, yellow <= %.0f px, orange <= 8 px, red beyond",
                inlier_threshold_px);
  caption(out, text, {4, 14});  // first: the pixels are drawn over it
  for (std::size_t i = 0; i < pixels.size() && i < residuals_px.size(); ++i) {
    const double e = residuals_px[i];
    const cv::Vec3b c = e <= 1.0                   ? kResidualGood
                        : e <= inlier_threshold_px ? kResidualInlier
                        : e <= 8.0                 ? kResidualNear
                                                   : kResidualFar;
    const cv::Point p = rounded(pixels[i]);
    if (p.x >= 0 && p.y >= 0 && p.x < out.cols && p.y < out.rows) out.at<cv::Vec3b>(p) = c;
  }
  return out;
}

}  // namespace omniloc::detail
