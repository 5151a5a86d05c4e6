// Camera calibration from frames taken at known positions (issue 13, item 1): the image centre,
// a radial model, yaw offset, mirroring, the view radius where the carpet ends, and the robot's
// own body and mast mask, all estimated from the images and the field model.
//
// Steps (calibrate_camera): mirror rim (strongest consistent bright-to-dark circle, RANSAC) ->
// carpet colour (dominant hue in the rim's disc) -> line pixels (locally brighter and less
// saturated than the carpet around them) -> body radius, masts and view radius (polar statistics
// of carpet / line / other) -> coarse brute-force search of yaw and mapping over a field-frame
// distance transform -> robust (Huber, truncated) Ceres fit of centre, radial model and yaw
// with nearest-line-point re-association (ICP-style).
//
// Radial model: ground distance d(r) a quartic in x = r / view radius, or where the quartic turns
// over, a rational form with the mirror's horizon (RadialModel), checked monotonic over [0, view
// radius]; written out as `radius_lut` rows.
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

/// The ground distance (cm) at image radius r (px), a ratio of polynomials in x = r / scale_px:
///   d(r) = (a1 x + a2 x^2 + a3 x^3 + a4 x^4) / (1 + e2 x^2 + e3 x^3 + e4 x^4).
/// Two forms are fitted (docs/CALIBRATION.md, step 6): the quartic (e = 0), and where the quartic
/// turns over, the rational form of a central omni camera (a2 = a3 = a4 = 0: Scaramuzza's model,
/// the ray through r leaves the mirror along (r, -z(r)) with z = z0 + z2 r^2 + z3 r^3 + z4 r^4 and
/// meets the floor at H r / z(r)), whose pole is the horizon that a hyperbolic or spherical mirror
/// approaches as its floor distance climbs steeply towards the rim.
struct RadialModel {
  double scale_px = 1.0;                        ///< r is normalised by it (the view radius)
  std::array<double, 4> a{0.0, 0.0, 0.0, 0.0};  ///< numerator a1..a4 (cm)
  std::array<double, 3> e{0.0, 0.0, 0.0};       ///< denominator e2..e4 (dimensionless)
  [[nodiscard]] bool rational() const { return e != std::array<double, 3>{0.0, 0.0, 0.0}; }
  [[nodiscard]] double ground_cm(double r_px) const;
  [[nodiscard]] double slope_cm_per_px(double r_px) const;
  /// True when d is finite and increases strictly on (0, r_max_px] (the horizon beyond it).
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
  cv::Mat carpet_mask;          // CV_8U, 255 = carpet colour
  cv::Mat line_mask;            // CV_8U, 255 = line pixel
  double body_radius_px = 0.0;  // inside: the robot itself
  double view_radius_px =
      0.0;  // carpet seen all round up to here (10th percentile of the carpet's end)
  std::vector<MastSector> masts_image;       // sectors in *image* angle (deg, about the rim centre)
  std::vector<Eigen::Vector2d> line_pixels;  // used for the fit (inside the ring, outside masts)
};

/// A colour class in OpenCV 8-bit HSV (H 0..179): hue within hue_half_width (circularly),
/// S >= sat_min, V >= val_min.
struct HsvClass {
  double hue = 0.0, hue_half_width = 0.0, sat_min = 0.0, val_min = 0.0;
};

/// The largest region of one goal colour in a frame.
struct GoalRegion {
  HsvClass colour;  // measured from the region's own pixels
  Eigen::Vector2d centroid_px{0.0, 0.0};
  int pixels = 0;
  cv::Mat mask;  // CV_8U, 255 = the region's pixels (for checks against hand-drawn goals)
};

/// The goal colours a frame shows (a goal not seen is empty).
struct GoalColours {
  std::optional<GoalRegion> blue, yellow;
};

/// What a goal colour is, before measuring it: the colour names' hue bands and how saturated and
/// bright paint is (carpet, lines, the dark floor and grey walls are not). Bands in OpenCV hue
/// units: blue 95..130 (190..260 deg), yellow 18..40 (36..80 deg), which leaves orange (the ball,
/// hue ~5..15) and green carpet (hue ~45..90) out. A region must cover min_area_fraction of the
/// mirror's disc (a goal 5 m away on a rendered 640 x 480 frame covers ~0.3 %; chromatic fringes
/// and a coloured robot top cover less after the 3 x 3 opening).
struct GoalColourOptions {
  double blue_hue_min = 95.0, blue_hue_max = 130.0;
  double yellow_hue_min = 18.0, yellow_hue_max = 40.0;
  double sat_min = 90.0, val_min = 50.0;
  double min_area_fraction = 0.0015;
};

struct FrameFit {
  double image_angle_of_field_x_deg = 0.0;  // alpha: image angle = field angle + alpha
  double yaw_deg = 0.0;  // robot heading used (given, or found with yaw_offset 0)
  bool yaw_given = false;
  double twin_yaw_deg = 0.0;             // best distinct heading (>= 30 deg away) and its score
  double score = 0.0, twin_score = 0.0;  // coarse truncated mean residual (px)
  int line_pixels = 0, inliers = 0;
  double rms_px = 0.0, rms_cm = 0.0, median_px = 0.0;
  // Self-check: of the field's line points the camera puts on the frame's carpet (`recall_points`),
  // the fraction seen there as line (docs/CALIBRATION.md, step 8).
  double line_recall = 0.0;
  int recall_points = 0;
};

struct CalibrationResult {
  CameraModel camera;  // what the project reads (radius_lut ends at the view radius)
  RadialModel radial;
  RimCircle rim;
  CarpetColour carpet;
  double view_radius_px = 0.0;
  // Radii between which lines crossing the rays measured the mapping (5th-95th percentile); the
  // polynomial is extrapolated outside (towards the body when no line crosses there).
  double measured_min_px = 0.0, measured_max_px = 0.0;
  bool mirrored_ambiguous = false;  // the other handedness fits as well (symmetric view)
  std::string handedness_from;  // what decided it: "given (--mirrored)" or "the lines: <frame> ..."
  // Every frame was taken within the ambiguity separation (50 cm) of the centre of the
  // point-symmetric field: the yaw offset 180 deg away fits as well, so the offset is known only up
  // to 180 deg, and so is which goal is where (no goal_colour_at_x_max is written).
  bool yaw_offset_ambiguous = false;
  double mirrored_score = 0.0, unmirrored_score = 0.0;
  std::vector<FrameAnalysis> analyses;
  std::vector<FrameFit> fits;
  double rms_px = 0.0, rms_cm = 0.0, median_px = 0.0, inlier_fraction = 0.0;
  double inlier_threshold_px = 0.0;
  // Venue colours: the goals (the frame where each is largest) and, when a frame's heading was
  // given, which colour is at the x = max end (kUnknown otherwise).
  GoalColours goals;
  GoalColour goal_colour_at_x_max = GoalColour::kUnknown;
};

/// What a team can tell the analysis when a step fails on its frames (`omniloc calibrate
/// --carpet-at`).
struct AnalysisHints {
  std::optional<Eigen::Vector2d>
      carpet_at_px;  ///< a pixel that is carpet: its colour cluster is the carpet
  /// The mirror's disc (`--center` with `--rim-radius`): replaces the rim search.
  std::optional<Eigen::Vector2d> centre_px;
  std::optional<double> rim_radius_px;
  std::optional<bool>
      mirrored;  ///< the handedness (`--mirrored yes|no`) when the lines do not tell it
};

/// Receives one step's picture (`omniloc calibrate --debug-dir`; docs/CALIBRATION.md, "Step
/// pictures"): the frame's name, the step ("1-disc", "2-carpet", "3-lines", "4-polar", "5-coarse",
/// "6-residuals") and the picture (8-bit BGR, the carpet mask 8-bit grey). Called as each step
/// ends and, for a step that refuses after measuring (polar statistics), just before the refusal
/// is thrown: a failed run has the pictures of the steps it reached, which is when a team needs
/// them. The library writes no file: the caller decides where pictures go.
using StepPictureSink = std::function<void(const std::string& frame_name, const std::string& step,
                                           const cv::Mat& picture)>;

struct CalibrationOptions {
  std::function<void(const std::string&)> progress;  // stage messages for a long run
  StepPictureSink step_pictures;                     // empty: no picture is drawn
  GoalColourOptions goal_colours;
  AnalysisHints hints;  // the same for every frame
};

/// The goal colours of one analysed frame: pixels inside the rim and outside the body that are
/// not carpet (nor of the carpet's hue within twice its half width) and lie in a colour name's
/// band, opened 3 x 3, largest connected region; its colour class from the region's pixels (median
/// hue, 3 robust sigmas at least 4 units; S and V from the 5th percentile less a fifth). A pure
/// function of the image and its analysis.
[[nodiscard]] GoalColours measure_goal_colours(const cv::Mat& bgr, const FrameAnalysis& analysis,
                                               const GoalColourOptions& options = {});

/// Which colour is at the field's x = max end, from where the regions lie seen from a known pose
/// (position and heading) through the camera: the region whose direction is nearer the x = max
/// goal's. kUnknown when no goal is seen or the two regions disagree.
[[nodiscard]] GoalColour goal_colour_at_x_max(const GoalColours& goals, const CameraModel& camera,
                                              const Eigen::Vector2d& position_cm, double yaw_deg,
                                              const FieldGeometry& field);

/// Finds the mirror rim. Throws std::runtime_error when no circle is consistent over the image.
[[nodiscard]] RimCircle find_mirror_rim(const cv::Mat& bgr, const std::string& context);

/// Rim, carpet colour, line pixels, body, masts, view radius of one frame. Throws when the frame
/// shows no carpet or no lines.
/// Pictures 1-4 (disc, carpet, lines, polar) go to `pictures` when given.
[[nodiscard]] FrameAnalysis analyse_frame(const cv::Mat& bgr, const std::string& context,
                                          const AnalysisHints& hints = {},
                                          const StepPictureSink& pictures = {});

/// The whole calibration (all frames share one camera). Throws std::runtime_error with the frame's
/// name and the reason when nothing fits.
[[nodiscard]] CalibrationResult calibrate_camera(const std::vector<CalibrationFrame>& frames,
                                                 const FieldGeometry& field,
                                                 const CalibrationOptions& options = {});

/// The camera file (today's keys, a "calibration" block the reader ignores, and the "vision" colour
/// model: carpet_hsv, line_contrast, goals.blue / goals.yellow when seen, goal_colour_at_x_max when
/// known; docs/CALIBRATION.md), as JSON text.
[[nodiscard]] std::string calibrated_camera_json(const CalibrationResult& result,
                                                 const std::vector<CalibrationFrame>& frames);

/// The frame with the detected line pixels, the field model projected at the fitted pose, the
/// rim, body and view circles and the masts.
[[nodiscard]] cv::Mat calibration_overlay(const CalibrationFrame& frame,
                                          const FrameAnalysis& analysis, const FrameFit& fit,
                                          const CalibrationResult& result,
                                          const FieldGeometry& field);

}  // namespace omniloc
