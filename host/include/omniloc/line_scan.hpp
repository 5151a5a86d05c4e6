// Line scan: the white-line feature of equations (1)-(4). For each of 360 field-frame directions,
// the radii (from the image centre) of the first four white-line crossings, where a crossing is
// the entry edge of a white run. A radius is a sample index, uint8 (0..254): sample k lies
// k * CameraModel::scan_step_px() px out (1 px up to a 254 px view, so radius = px there; a larger
// view is divided into 254 samples). kNoCrossing marks "no further crossing within view". Each ray
// also records where its view ends (ray_end_px): the mast hides a ray entirely (end 0), an obstacle
// ends it where it begins, keeping the crossings before it, and a database crossing at or beyond
// the end is unknown rather than missing, so the matcher leaves it out.
//
// Sampling (shared by the image scan and the geometric scan so that they agree): along each ray,
// samples k = CameraModel::first_scan_sample() .. last_scan_sample(), each read at the pixel
// nearest k * scan_step_px(); a
// crossing is a white sample preceded by at least min_gap_px non-white samples (counted from the
// first sample, so a run already white there is not a crossing). The gap rule keeps a line that
// runs nearly along a ray from producing a zig-zag of crossings out of pixel rounding.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/field.hpp"

namespace omniloc {

inline constexpr int kScanRays = 360;
inline constexpr int kCrossingsPerRay = 4;
inline constexpr int kFeatureBytes = kScanRays * kCrossingsPerRay;
inline constexpr std::uint8_t kNoCrossing = 255;
/// ray_end_px of a ray that saw nothing (mast), and of one seen to the end of the view.
inline constexpr std::uint8_t kRayHidden = 0;
inline constexpr std::uint8_t kRayToViewEnd = 255;

/// A field-frame scan: ray k points along field direction k degrees; radii_px[4 k + n] is its
/// (n+1)-th crossing. Contiguous so that matching can use SIMD.
struct Scan {
  std::array<std::uint8_t, kFeatureBytes> radii_px{};
  /// Where ray k's view ends (px from the image centre, exclusive): its crossings are the ones
  /// below it. kRayHidden: nothing seen; kRayToViewEnd: seen to the end of the view.
  std::array<std::uint8_t, kScanRays> ray_end_px{};
  /// Rays that saw anything (ray_end_px > 0).
  [[nodiscard]] int rays_valid() const;
};

/// Colour classes on the HSV of OpenCV's 8-bit conversion (S and V in 0..255). White lines are
/// bright and unsaturated (survives a lighting gradient that scales brightness); an obstacle is a
/// run of dark pixels, which ends the ray where it starts; the green carpet and what lies beyond
/// the border are neither.
struct ScanParams {
  int white_v_min = 150;
  int white_s_max = 70;
  int dark_v_max = 45;
  int dark_run_px = 3;  // this many dark samples in a row end the ray (at the first of them)
  int min_gap_px = 2;   // must match the database (expected_features uses the default)
};

/// Scans a BGR 8-bit image taken at robot heading yaw_deg into field-frame rays. Classifies only
/// the pixels on the rays. Throws std::invalid_argument for an image that does not match the
/// camera.
[[nodiscard]] Scan scan_image(const cv::Mat& bgr, const CameraModel& camera, double yaw_deg,
                              const ScanParams& params = {});

/// Scan in the robot frame at a finer angular step, for estimating the yaw: ray j has bearing
/// j / rays_per_degree. rotate_to_field() picks, for each field direction, the nearest ray.
struct BearingScan {
  int rays_per_degree = 4;
  std::vector<std::uint8_t> radii_px;    // 360 * rays_per_degree * 4
  std::vector<std::uint8_t> ray_end_px;  // 360 * rays_per_degree, as Scan::ray_end_px
};
[[nodiscard]] BearingScan scan_image_bearings(const cv::Mat& bgr, const CameraModel& camera,
                                              int rays_per_degree, const ScanParams& params = {});
[[nodiscard]] Scan rotate_to_field(const BearingScan& scan, double yaw_deg);

/// The scan a robot at `position_cm` would see, by casting rays through the field model and the
/// camera's radius table (no obstacles, no mast: every ray seen to the end). This is a database
/// entry.
[[nodiscard]] Scan expected_scan(const FieldGeometry& field, const CameraModel& camera,
                                 const Eigen::Vector2d& position_cm);

/// One ray's crossings from its white runs, in order along the ray: radii_px(run) gives the run's
/// (enter, exit) radii in px; the integer samples k0..k1 inside each run are what the image scan
/// would visit, and an entry counts when at least min_gap_px non-white samples precede it (the gap
/// rule above). Writes 4 radii, kNoCrossing-padded. Shared by expected_features and the matcher's
/// linearised ray caster, so that both turn runs into crossings exactly as the image scan does.
template <class Runs, class RadiiPx>
void crossings_of_runs(int k0, int k1, int min_gap_px, const Runs& runs, RadiiPx radii_px,
                       std::uint8_t* out) {
  std::fill(out, out + kCrossingsPerRay, kNoCrossing);
  int found = 0;
  int last_white = k0 - 1;  // as if white just before the first sample: it cannot be an entry
  for (const auto& run : runs) {
    const auto [enter_px, exit_px] = radii_px(run);
    const int ka = std::max(static_cast<int>(std::ceil(enter_px - 1e-9)), k0);
    const int kb = std::min(static_cast<int>(std::floor(exit_px + 1e-9)), k1);
    if (ka > kb) continue;
    if (ka - last_white - 1 >= min_gap_px && found < kCrossingsPerRay)
      out[found++] = static_cast<std::uint8_t>(ka);
    last_white = kb;
  }
}

/// As expected_scan, writing the 1440 radii to `out`; `scratch` is reused between calls. Ray k is
/// cast at field bearing k + bearing_offset_deg (a scan rotated from the robot frame at a step of
/// 1 / rays_per_degree sees its rays that far from the whole degrees:
/// FieldScan::bearing_offset_deg).
void expected_features(const FieldGeometry& field, const CameraModel& camera,
                       const Eigen::Vector2d& position_cm, std::uint8_t* out,
                       std::vector<WhiteInterval>& scratch,
                       int min_gap_px = ScanParams{}.min_gap_px, double bearing_offset_deg = 0.0);

}  // namespace omniloc
