// Camera calibration from frames taken at known positions (issue 13, item 1): the image centre,
// a radial model, yaw offset, mirroring, the view radius where the carpet ends, and the robot's
// own body and mast mask, all estimated from the images and the field model.
//
// Steps (calibrate_camera): mirror rim (strongest consistent bright-to-dark circle, RANSAC) ->
// carpet colour (dominant hue in the rim's disc) -> line pixels (locally brighter and less
// saturated than the carpet around them) -> body radius, masts and view radius (polar statistics
// of carpet / line / other) -> coarse brute-force search of yaw and mapping over a field-frame
// distance transform -> robust (Huber, truncated) Ceres fit of centre, radial polynomial and yaw
// with nearest-line-point re-association (ICP-style).
//
// Radial model: ground distance d(r) = a1 r + a2 r^2 + a3 r^3 + a4 r^4 (cm, r in px from the image
// centre), checked monotonic over [0, view radius]; written out as `radius_lut` rows.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/field.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

/// One calibration image and where the robot stood (field frame); yaw empty = unknown (searched).
struct CalibrationFrame {
  cv::Mat image;  // BGR, 8 bit
  std::string name;
  Eigen::Vector2d position_cm{0.0, 0.0};
  std::optional<double> yaw_deg;
};

/// d(r) = sum_k a[k] r^(k+1): ground distance (cm) at image radius r (px).
struct RadialPolynomial {
  std::array<double, 4> a{0.0, 0.0, 0.0, 0.0};
  [[nodiscard]] double ground_cm(double r_px) const;
  [[nodiscard]] double slope_cm_per_px(double r_px) const;
  /// True when d increases strictly on (0, r_max_px].
  [[nodiscard]] bool monotonic_up_to(double r_max_px) const;
};

/// The mirror's rim: the outermost circle along which the image steps from bright to dark.
struct RimCircle {
  Eigen::Vector2d centre_px{0.0, 0.0};
  double radius_px = 0.0;
  int rays_on_circle = 0;  // of 360
};

// CarpetColour (the carpet colour statistics and line steps) lives in vision.hpp: the robot
// library estimates it too.

/// Per-frame image analysis: what calibrate_camera measured before fitting.
struct FrameAnalysis {
  RimCircle rim;
  CarpetColour carpet;
  cv::Mat carpet_mask;             // CV_8U, 255 = carpet colour
  cv::Mat line_mask;               // CV_8U, 255 = line pixel
  double body_radius_px = 0.0;     // inside: the robot itself
  double view_radius_px = 0.0;     // carpet seen all round up to here (10th percentile of the carpet's end)
  std::vector<MastSector> masts_image;  // sectors in *image* angle (deg, about the rim centre)
  std::vector<Eigen::Vector2d> line_pixels;  // used for the fit (inside the ring, outside masts)
};

struct FrameFit {
  double image_angle_of_field_x_deg = 0.0;  // alpha: image angle = field angle + alpha
  double yaw_deg = 0.0;                     // robot heading used (given, or found with yaw_offset 0)
  bool yaw_given = false;
  double twin_yaw_deg = 0.0;                // best distinct heading (>= 30 deg away) and its score
  double score = 0.0, twin_score = 0.0;     // coarse truncated mean residual (px)
  int line_pixels = 0, inliers = 0;
  double rms_px = 0.0, rms_cm = 0.0, median_px = 0.0;
};

struct CalibrationResult {
  CameraModel camera;  // what the project reads (radius_lut ends at the view radius)
  RadialPolynomial radial;
  RimCircle rim;
  CarpetColour carpet;
  double view_radius_px = 0.0;
  // Radii between which lines crossing the rays measured the mapping (5th-95th percentile); the
  // polynomial is extrapolated outside (towards the body when no line crosses there).
  double measured_min_px = 0.0, measured_max_px = 0.0;
  bool mirrored_ambiguous = false;  // the other handedness fits as well (symmetric view)
  double mirrored_score = 0.0, unmirrored_score = 0.0;
  std::vector<FrameAnalysis> analyses;
  std::vector<FrameFit> fits;
  double rms_px = 0.0, rms_cm = 0.0, median_px = 0.0, inlier_fraction = 0.0;
  double inlier_threshold_px = 0.0;
};

struct CalibrationOptions {
  std::function<void(const std::string&)> progress;  // stage messages for a long run
};

/// Finds the mirror rim. Throws std::runtime_error when no circle is consistent over the image.
[[nodiscard]] RimCircle find_mirror_rim(const cv::Mat& bgr, const std::string& context);

/// Rim, carpet colour, line pixels, body, masts, view radius of one frame. Throws when the frame
/// shows no carpet or no lines.
[[nodiscard]] FrameAnalysis analyse_frame(const cv::Mat& bgr, const std::string& context);

/// The whole calibration (all frames share one camera). Throws std::runtime_error with the frame's
/// name and the reason when nothing fits.
[[nodiscard]] CalibrationResult calibrate_camera(const std::vector<CalibrationFrame>& frames, const FieldGeometry& field,
                                                 const CalibrationOptions& options = {});

/// The camera file (today's keys plus a "calibration" block the reader ignores), as JSON text.
[[nodiscard]] std::string calibrated_camera_json(const CalibrationResult& result,
                                                 const std::vector<CalibrationFrame>& frames);

/// The frame with the detected line pixels, the field model projected at the fitted pose, the
/// rim, body and view circles and the masts.
[[nodiscard]] cv::Mat calibration_overlay(const CalibrationFrame& frame, const FrameAnalysis& analysis,
                                          const FrameFit& fit, const CalibrationResult& result,
                                          const FieldGeometry& field);

}  // namespace omniloc
