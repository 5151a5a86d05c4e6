// White-line extraction from omni-camera frames (issue 13 item 2): the camera JSON "vision" block
// (VisionModel, every key optional with its default here) and the LineExtractor that turns a BGR
// frame into a robot-frame BearingScan plus an ExtractionReport.
//
// Extraction (docs/VISION.md, "Extraction"): the carpet colour comes from vision.carpet_hsv
// (written by `omniloc calibrate`) or, when absent, from the frame (dominant colour next to the
// robot, the calibration's own estimate). Each ray is walked over every pixel it touches (a
// 4-connected traversal precomputed per camera, so a 1 px line cannot fall between samples), binned
// by integer radius. A bin is "line" when one of its pixels is brighter by line_contrast.val_step
// AND less saturated by line_contrast.sat_step than the carpet just before it on the ray (a running
// mean of the carpet bins), "carpet" when a pixel has the carpet colour (value window following the
// light per sector, frame to frame), else "other". A run of extraction.end_run_px "other" bins ends
// the ray at its first bin, keeping the crossings before it: an obstacle when the carpet resumes
// behind it, the carpet's end (walls, black floor) when it does not. Crossings use the database's
// gap rule (line_scan.hpp). A frame with too little carpet, too few rays or crossings is "no
// measurement".
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include "omniloc/config.hpp"

namespace omniloc {

struct CameraModel;
struct BearingScan;

/// The carpet's colour window (OpenCV 8-bit HSV: H 0..179, S/V 0..255). The value window's
/// midpoint is taken as the carpet's reference brightness, which the extraction follows per sector.
struct CarpetHsv {
  double hue = 0.0;
  double hue_half_width = 10.0;
  double sat_min = 40.0;
  double val_min = 40.0;
  double val_max = 255.0;
  bool operator==(const CarpetHsv&) const = default;
};

/// A line pixel is at least val_step brighter and sat_step less saturated than the carpet around
/// it.
struct LineContrast {
  double val_step = 12.0;
  double sat_step = 8.0;
  bool operator==(const LineContrast&) const = default;
};

/// A goal's colour class (the goal cue's, goals.hpp; the line extraction ignores it): hue within
/// +- hue_half_width (circular), saturation and value at least their minima.
struct GoalHsv {
  double hue = 0.0;
  double hue_half_width = 10.0;
  double sat_min = 80.0;
  double val_min = 60.0;
  [[nodiscard]] bool contains(int h, int s, int v) const;
  bool operator==(const GoalHsv&) const = default;
};

/// The extraction's own thresholds ("vision": {"extraction": {...}}).
struct ExtractionParams {
  int end_run_px = 4;  ///< this many "other" bins in a row end the ray (a line's fringe is 1-2 px)
  /// carpet bins in a row behind an end: an obstacle, not the carpet's end
  int carpet_resume_px = 4;
  int resume_within_px = 40;  ///< ... looked for this far behind the end (a ball, a low robot)
  double obstacle_window_deg = 30.0;  ///< an end this far inside the median end of the rays within
  int obstacle_step_px = 8;  ///< +- window is an obstacle (a tall one hides the carpet behind it)
  /// a line's edge: where it first reaches this fraction from carpet to peak
  double edge_fraction = 0.5;
  int carpet_mean_px = 8;  ///< length (px) of the running carpet mean along a ray
  int sectors = 16;        ///< light-following sectors around the image centre
  /// per frame, each sector's level moves this fraction towards what it saw
  double light_follow = 0.5;
  double light_range = 2.0;  ///< a sector's level stays within [ref / range, ref * range]
  /// estimated val_step = this many robust sigmas of the carpet's brightness
  double val_sigmas = 4.0;
  double sat_sigmas = 2.0;    ///< estimated sat_step = this many robust sigmas of its saturation
  double min_val_step = 6.0;  ///< floors of the estimated steps (8-bit quantisation and noise)
  double min_sat_step = 4.0;
  double min_carpet_fraction = 0.15;  ///< usable: this fraction of the visited bins is carpet ...
  double min_rays_seen = 0.25;  ///< ... this fraction of the rays sees carpet beyond the body ...
  int min_crossings = 20;       ///< ... and at least this many crossings (all rays)
  bool operator==(const ExtractionParams&) const = default;
};

/// How the goal evidence is judged (camera "vision.goal_cue", every key optional; these
/// initialisers are the defaults, documented in docs/LOCALIZER.md).
struct GoalCueConfig {
  /// Fewer goal-coloured pixels than this beyond the goal lines (at the pixel step): too weak to
  /// choose. 40 samples at step 2 are ~160 image pixels, a goal 3 m away shows ~10x that.
  int min_pixels = 40;
  /// (score of one candidate - score of the other) / (2 * pixels considered), in [-1, 1]: a
  /// choice needs at least this (0.5: three quarters of the pixels on one side).
  double min_margin = 0.5;
  /// The goal mouth's wedge is widened by this each side (posts, calibration and pose error).
  double post_margin_cm = 15.0;
  /// Every n-th pixel in each direction is examined (the goals are large; 2 -> a quarter).
  int pixel_step = 2;
  void validate(const config::Origin& at) const;
  bool operator==(const GoalCueConfig&) const = default;
};

/// A camera's "vision" block. Absent keys keep these defaults; absent carpet_hsv / line_contrast
/// are estimated from the frames.
struct VisionModel {
  std::optional<CarpetHsv> carpet_hsv;
  std::optional<LineContrast> line_contrast;
  std::optional<GoalHsv> goal_blue, goal_yellow;
  std::string goal_colour_at_x_max;  ///< "", "blue" or "yellow"
  GoalCueConfig goal_cue;            ///< how the goal colours choose between a pose and its twin
  ExtractionParams extraction;
  /// Throws ConfigError "<at>.<path>: <why> (got <value>)".
  void validate(const config::Origin& at) const;
  bool operator==(const VisionModel&) const = default;
};

/// The key table (config_reader.hpp) of a camera's "vision" block.
[[nodiscard]] const std::vector<config::Key<VisionModel>>& vision_keys();

/// Carpet colour statistics (OpenCV 8-bit HSV) and the thresholds derived from them; shared with
/// the calibration, which writes them as the "vision" block.
struct CarpetColour {
  double hue = 0.0, hue_half_width = 0.0;
  double sat_min = 0.0, val_min = 0.0, val_max = 255.0;
  double median_sat = 0.0, median_val = 0.0;
  double line_val_step =
      0.0;  // a line pixel is at least this much brighter than the carpet around it
  double line_sat_step = 0.0;  // ... and at least this much less saturated
};

/// Carpet = the most frequent colour (a 3-D H x S x V histogram) among `hsv` samples taken next to
/// the robot (it stands on the carpet). nullopt with `why` set when no colour dominates or it is
/// grey. Hue window: 3 robust sigmas (4..20 units); saturation down to 3 sigmas or a quarter below
/// the median; value 0.5 to 1.5 times the median.
/// With allow_grey a dominant grey (median saturation below 20) is a carpet of brightness alone:
/// every hue, no saturation floor (a carpet chosen by its structure, estimate_carpet_colour).
[[nodiscard]] std::optional<CarpetColour> carpet_colour_from_samples(
    const std::vector<cv::Vec3b>& hsv, std::string* why, bool allow_grey = false);

/// True for a carpet window of brightness alone (a grey carpet: every hue, no saturation floor).
[[nodiscard]] inline bool is_grey_carpet(double hue_half_width) {
  return hue_half_width >= 90.0;
}

/// Where estimate_carpet_colour looks: the ring [inner_px, outer_px] about centre_px (inner 0: the
/// robot's body is not known and the run from the centre is taken as the robot), pixels where
/// `mask` (CV_8U, optional) is 0 left out, and optionally a pixel the team knows is carpet.
struct CarpetSearch {
  cv::Point2d centre_px{0.0, 0.0};
  double inner_px = 0.0;
  double outer_px = 0.0;
  cv::Mat mask;
  std::optional<cv::Point2d> carpet_at;
};

/// The carpet from the frame's structure (carpet_estimate.cpp): k-means of the ring's colours in
/// CIELAB; along 180 bearings the cluster of the longest run beyond the robot gets the bearing's
/// vote (lines as wide as a fortieth of the ring bridged); the winner must be seen on 40 % of the
/// bearings; its window from its own pixels (carpet_colour_from_samples, grey allowed). nullopt
/// with `why` ("no carpet: ...") when no colour qualifies.
[[nodiscard]] std::optional<CarpetColour> estimate_carpet_colour(const cv::Mat& bgr,
                                                                 const CarpetSearch& search,
                                                                 std::string* why);

/// The q-quantile (0..1) and the robust sigma (1.4826 MAD) of samples.
[[nodiscard]] double percentile(std::vector<double> v, double q);
[[nodiscard]] double robust_sigma(std::vector<double> v);

/// One end of a ray that is not the carpet's end: a blob on the carpet (robot, person, ball).
struct ObstacleBlob {
  int first_ray = 0, last_ray = 0;  ///< bearing-scan ray indices (last may wrap below first)
  /// the smallest end radius among its rays (a sample index, line_scan.hpp)
  int near_radius_px = 0;
};

struct ExtractionReport {
  bool usable = false;
  std::string reason;  ///< why not usable ("" when usable)
  int rays = 0;        ///< rays walked (not hidden)
  int rays_seen = 0;   ///< rays that saw carpet beyond the body
  int crossings = 0;
  int rays_ended_at_carpet_edge = 0, rays_ended_at_obstacle = 0;
  double carpet_fraction = 0.0;  ///< carpet bins / bins visited
  /// Per ray: where the carpet ends (sample index as the scan's radii, line_scan.hpp; 0 hidden, 255
  /// not reached: carpet to the end of the view or the walk stopped after four crossings).
  std::vector<std::uint8_t> carpet_end_px;
  std::vector<ObstacleBlob> obstacles;
  CarpetHsv carpet;       ///< the carpet window used (estimated or from the camera)
  LineContrast contrast;  ///< the steps used
  bool carpet_estimated = false;
};

namespace detail {
struct LineExtractorAccess;
}  // namespace detail

/// Turns frames of one camera into bearing scans. Stateful only in its per-frame adaptation (the
/// carpet estimate, the light level per sector, the estimated line steps); deterministic.
class LineExtractor {
 public:
  explicit LineExtractor(const CameraModel& camera);
  /// Throws std::invalid_argument for an image that does not match the camera, or rays_per_degree
  /// outside 1..20.
  [[nodiscard]] BearingScan extract(const cv::Mat& bgr, int rays_per_degree,
                                    ExtractionReport* report = nullptr);
  ~LineExtractor();
  LineExtractor(const LineExtractor&);
  LineExtractor& operator=(const LineExtractor&);
  LineExtractor(LineExtractor&&) noexcept;
  LineExtractor& operator=(LineExtractor&&) noexcept;

  /// The per-resolution ray layout (internal: omniloc/detail/line_extractor.hpp).
  struct RayTable;

 private:
  friend struct detail::LineExtractorAccess;  // the reference walks, for tests and benchmarks
  /// The straightforward walk (every pixel's H, S, V computed on every ray that touches it): the
  /// reference extract() must equal byte for byte (tests) and is measured against (bench_vision).
  BearingScan extract_reference(const cv::Mat& bgr, int rays_per_degree,
                                ExtractionReport* report = nullptr);

  /// The ways of walking the rays; all give the same bytes (scan and report, frame after frame).
  enum class Walk {
    kFast,  ///< extract(): the code plane converted 8 pixels at a time (AVX2) and 8 rays walked in
            ///< lockstep
    kBinWalk,    ///< the scalar code plane and the scalar bin-by-bin walk (extract() before the
                 ///< lockstep walk)
    kReference,  ///< extract_reference()
  };
  BearingScan extract_with(Walk how, const cv::Mat& bgr, int rays_per_degree,
                           ExtractionReport* report = nullptr);

  struct Frame;
  const RayTable& table(int rays_per_degree, std::size_t step_bytes);
  bool ensure_carpet(const cv::Mat& bgr, std::string* why);
  BearingScan extract_impl(const cv::Mat& bgr, int rays_per_degree, ExtractionReport* report,
                           Walk how);
  BearingScan extract_once(const cv::Mat& bgr, int rays_per_degree, ExtractionReport* report,
                           Walk how);
  template <class Pixel>
  void walk_rays(const RayTable& t, BearingScan& scan, ExtractionReport& rep, Frame& fr,
                 Pixel px) const;
  void walk(const cv::Mat& bgr, const RayTable& t, BearingScan& scan, ExtractionReport& rep,
            Frame& fr) const;
  void bin_layout(RayTable& t, int n) const;
  void code_pixels(const cv::Mat& bgr, const RayTable& t, int sat_min);
  bool code_pixels_avx2(const cv::Mat& bgr, const RayTable& t, int sat_min);
  void walk_fast(const RayTable& t, BearingScan& scan, ExtractionReport& rep, Frame& fr) const;
  bool walk_lockstep(const RayTable& t, BearingScan& scan, ExtractionReport& rep, Frame& fr) const;
  void adapt(const Frame& fr);
  void mark_tall_obstacles(const BearingScan& scan, ExtractionReport& rep) const;
  void mark_tall_obstacles_fast(const BearingScan& scan, ExtractionReport& rep) const;

  // The camera's geometry, copied (the extractor may outlive the camera).
  int width_px_, height_px_;
  double cx_, cy_, yaw_offset_deg_;
  bool mirrored_;
  double step_px_;  // px between a ray's samples (CameraModel::scan_step_px): a bin is one sample
  int k0_, k1_;
  std::vector<std::pair<double, double>> masts_;  // bearing, half width (deg)
  VisionModel vision_;
  std::vector<RayTable> tables_;  // by rays_per_degree (index), built on first use
  // Adaptation state.
  std::optional<CarpetHsv> carpet_;
  std::optional<LineContrast> contrast_;
  double ref_val_ = 0.0;
  std::vector<double> sector_val_, sector_sat_;
  std::array<bool, 180> hue_ok_{};
  // Per frame, per pixel any ray touches: V | S << 8 | (S >= sat_min and carpet hue) << 16, so
  // that a pixel several rays share is converted once (the fast walk).
  std::vector<std::uint32_t> code_;
};

}  // namespace omniloc
