// Pictures of the calibration's steps (`omniloc calibrate --debug-dir`, docs/CALIBRATION.md,
// "Step pictures"): what each step measured, drawn so a team can see where a venue's frame goes
// wrong. Pure drawing: the steps hand their results to a StepPictureSink (calibration.hpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "omniloc/calibration.hpp"

namespace omniloc::detail {

/// Step 4's polar classes: per (bearing bin, radius px) 0 other, 1 carpet, 2 line; bins of
/// 360 / angle_bins deg counter-clockwise from the image's +u axis about the rim centre.
struct PolarClasses {
  int angle_bins = 0, radii_px = 0;
  std::vector<std::uint8_t> cls;
  [[nodiscard]] std::uint8_t at(int bin, int r_px) const {
    return cls[static_cast<std::size_t>(bin) * static_cast<std::size_t>(radii_px) +
               static_cast<std::size_t>(r_px)];
  }
};

/// Step 5's grid: per handedness (0 not mirrored, 1 mirrored) the best coarse score (px) over the
/// shapes, rows = scale index, cols = heading term bin. The coarse search walks these scales.
struct CoarseGrid {
  static constexpr int kScales = 51;
  /// Row i's scale: the ground distance at the view radius, 60 cm x 1.08^i (60 cm .. 28 m).
  [[nodiscard]] static double view_cm(int row) { return 60.0 * std::pow(1.08, row); }
  cv::Mat1f score_px[2];
  double heading_step_deg = 0.0;
};

// The pictures' colours (BGR): saturated primaries that an 8-bit frame dimmed to 40 % cannot hold,
// so a test (or a script) can count them.
inline const cv::Vec3b kRimColour{255, 0, 255};
inline const cv::Vec3b kLineColour{255, 255, 255};
inline const cv::Vec3b kPolarCarpet{0, 160, 0}, kPolarLine{255, 255, 255}, kPolarOther{70, 70, 70};
inline const cv::Vec3b kBodyMark{0, 0, 255}, kViewMark{0, 255, 255};
inline const cv::Vec3b kResidualGood{0, 255, 0}, kResidualInlier{0, 255, 255},
    kResidualNear{0, 128, 255}, kResidualFar{0, 0, 255};

/// Step pictures' layout: each coarse cell is drawn kCoarseCellPx square; each handedness panel
/// has a caption strip above it.
constexpr int kCoarseCellPx = 4, kCoarseCaptionPx = 24, kCoarseFooterPx = 20;

/// 1: the frame with the rim circle (1 px, not antialiased) and a cross at its centre.
[[nodiscard]] cv::Mat disc_picture(const cv::Mat& bgr, const RimCircle& rim);
/// 3: the frame dimmed to 40 % with the line mask's pixels white.
[[nodiscard]] cv::Mat lines_picture(const cv::Mat& bgr, const cv::Mat& line_mask);
/// 4: the polar classes unwrapped, rows = bearing 0..359 deg (one per degree), cols = radius px;
/// body (radius < body) tinted red, mast bearings tinted blue, body and view radii marked as
/// columns. A radius of 0 (not measured: the step refused before) is not marked.
[[nodiscard]] cv::Mat polar_picture(const PolarClasses& polar, double body_radius_px,
                                    double view_radius_px, const std::vector<bool>& mast_bins);
/// 5: the coarse score as a heat map per handedness (hot = low score = good fit), heading term
/// along x, scale along y (small at the bottom), the best cell framed white.
[[nodiscard]] cv::Mat coarse_picture(const CoarseGrid& grid, double trunc_px);
/// 6: the frame dimmed to 40 % with each line pixel coloured by its residual: <= 1 px green,
/// <= the inlier threshold yellow, <= 8 px orange, beyond red.
[[nodiscard]] cv::Mat residuals_picture(const cv::Mat& bgr,
                                        const std::vector<Eigen::Vector2d>& pixels,
                                        const std::vector<double>& residuals_px,
                                        double inlier_threshold_px);

}  // namespace omniloc::detail
