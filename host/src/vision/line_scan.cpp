#include "omniloc/line_scan.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "hsv_tables.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/detail/vision_reference.hpp"

namespace omniloc {

namespace {

enum class Px : std::uint8_t { kOther = 0, kWhite = 1, kDark = 2 };

inline Px classify(const std::uint8_t* bgr, const ScanParams& p, const int* sdiv) {
  const int b = bgr[0], g = bgr[1], r = bgr[2];
  const int v = std::max({b, g, r});
  if (v <= p.dark_v_max) return Px::kDark;
  if (v < p.white_v_min) return Px::kOther;
  const int diff = v - std::min({b, g, r});
  const int s = (diff * sdiv[v] + (1 << 11)) >> 12;
  return s <= p.white_s_max ? Px::kWhite : Px::kOther;
}

void check_image(const cv::Mat& bgr, const CameraModel& cam) {
  if (bgr.empty()) throw std::invalid_argument("scan: empty image");
  if (bgr.type() != CV_8UC3)
    throw std::invalid_argument("scan: image must be 8-bit BGR (CV_8UC3), got type " +
                                std::to_string(bgr.type()));
  if (bgr.cols != cam.width_px || bgr.rows != cam.height_px) {
    throw std::invalid_argument("scan: image is " + std::to_string(bgr.cols) + " x " +
                                std::to_string(bgr.rows) + " but the camera model expects " +
                                std::to_string(cam.width_px) + " x " +
                                std::to_string(cam.height_px));
  }
}

// Walks one ray at image angle phi (rad). classify_at(u, v) gives the class of a pixel. Writes 4
// radii (kNoCrossing-padded) and returns the ray's end: the first sample of a dark run (an
// obstacle) before the fourth crossing, else kRayToViewEnd.
template <class ClassifyAt>
std::uint8_t walk_ray(const CameraModel& cam, double phi, int k0, int k1, const ScanParams& p,
                      std::uint8_t* out, ClassifyAt classify_at) {
  // Sample k lies k * step px out: the step folded into the direction.
  const double step = cam.scan_step_px();
  const double cu = std::cos(phi) * (cam.mirrored ? -step : step);
  const double sv = -std::sin(phi) * step;
  const double cx = cam.center_px.x(), cy = cam.center_px.y();
  int found = 0;
  int dark = 0;
  int gap = 0;  // non-white samples since the last white one (or since the first sample)
  std::fill(out, out + kCrossingsPerRay, kNoCrossing);
  for (int k = k0; k <= k1 && found < kCrossingsPerRay; ++k) {
    // Nearest pixel; coordinates are >= 0 inside the view circle, so +0.5 and truncation is
    // lround without its library call.
    const int u = static_cast<int>(cx + k * cu + 0.5);
    const int v = static_cast<int>(cy + k * sv + 0.5);
    const Px c = classify_at(u, v);
    if (c == Px::kDark) {
      if (++dark >= p.dark_run_px) return static_cast<std::uint8_t>(std::max(k - dark + 1, 1));
    } else {
      dark = 0;
    }
    if (c == Px::kWhite) {
      if (gap >= p.min_gap_px) out[found++] = static_cast<std::uint8_t>(k);
      gap = 0;
    } else {
      ++gap;
    }
  }
  return kRayToViewEnd;
}

// Unit vectors of the 360 field directions (immutable, built once).
const std::array<Eigen::Vector2d, kScanRays>& ray_directions() {
  static const std::array<Eigen::Vector2d, kScanRays> dirs = [] {
    std::array<Eigen::Vector2d, kScanRays> d;
    for (int k = 0; k < kScanRays; ++k)
      d[static_cast<std::size_t>(k)] = {std::cos(deg_to_rad(k)), std::sin(deg_to_rad(k))};
    return d;
  }();
  return dirs;
}

int first_sample(const CameraModel& cam) {
  return cam.first_scan_sample();
}
int last_sample(const CameraModel& cam) {
  return cam.last_scan_sample();
}

template <class ClassifyAt>
Scan scan_with(const CameraModel& cam, double yaw_deg, const ScanParams& p,
               ClassifyAt classify_at) {
  Scan s;
  const int k0 = first_sample(cam), k1 = last_sample(cam);
  for (int k = 0; k < kScanRays; ++k) {
    const double bearing = static_cast<double>(k) - yaw_deg;
    std::uint8_t* out = s.radii_px.data() + k * kCrossingsPerRay;
    if (cam.bearing_hidden(bearing)) {
      std::fill(out, out + kCrossingsPerRay, kNoCrossing);
      s.ray_end_px[static_cast<std::size_t>(k)] = kRayHidden;
      continue;
    }
    const double phi = deg_to_rad(cam.image_angle_deg(bearing));
    s.ray_end_px[static_cast<std::size_t>(k)] = walk_ray(cam, phi, k0, k1, p, out, classify_at);
  }
  return s;
}

}  // namespace

int Scan::rays_valid() const {
  int n = 0;
  for (auto e : ray_end_px) n += e != kRayHidden;
  return n;
}

Scan scan_image(const cv::Mat& bgr, const CameraModel& cam, double yaw_deg, const ScanParams& p) {
  check_image(bgr, cam);
  const int* sdiv = detail::hsv_tables().sat_div;
  return scan_with(cam, yaw_deg, p, [&](int u, int v) {
    return classify(bgr.ptr<std::uint8_t>(v) + 3 * u, p, sdiv);
  });
}

Scan scan_image_reference(const cv::Mat& bgr, const CameraModel& cam, double yaw_deg,
                          const ScanParams& p) {
  check_image(bgr, cam);
  cv::Mat hsv, white, dark;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(0, 0, p.white_v_min), cv::Scalar(255, p.white_s_max, 255), white);
  cv::inRange(hsv, cv::Scalar(0, 0, 0), cv::Scalar(255, 255, p.dark_v_max), dark);
  return scan_with(cam, yaw_deg, p, [&](int u, int v) {
    if (dark.at<std::uint8_t>(v, u) != 0) return Px::kDark;
    return white.at<std::uint8_t>(v, u) != 0 ? Px::kWhite : Px::kOther;
  });
}

BearingScan scan_image_bearings(const cv::Mat& bgr, const CameraModel& cam, int rays_per_degree,
                                const ScanParams& p) {
  check_image(bgr, cam);
  if (rays_per_degree < 1 || rays_per_degree > 20) {
    throw std::invalid_argument("scan_image_bearings: rays_per_degree must be 1..20, got " +
                                std::to_string(rays_per_degree));
  }
  const int* sdiv = detail::hsv_tables().sat_div;
  BearingScan s;
  s.rays_per_degree = rays_per_degree;
  const int n = kScanRays * rays_per_degree;
  s.radii_px.assign(static_cast<std::size_t>(n) * kCrossingsPerRay, kNoCrossing);
  s.ray_end_px.assign(static_cast<std::size_t>(n), kRayHidden);
  const int k0 = first_sample(cam), k1 = last_sample(cam);
  for (int j = 0; j < n; ++j) {
    const double bearing = static_cast<double>(j) / rays_per_degree;
    if (cam.bearing_hidden(bearing)) continue;
    std::uint8_t* out = s.radii_px.data() + static_cast<std::size_t>(j) * kCrossingsPerRay;
    s.ray_end_px[static_cast<std::size_t>(j)] =
        walk_ray(cam, deg_to_rad(cam.image_angle_deg(bearing)), k0, k1, p, out,
                 [&](int u, int v) { return classify(bgr.ptr<std::uint8_t>(v) + 3 * u, p, sdiv); });
  }
  return s;
}

Scan rotate_to_field(const BearingScan& b, double yaw_deg) {
  Scan s;
  const int n = kScanRays * b.rays_per_degree;
  if (static_cast<int>(b.ray_end_px.size()) != n)
    throw std::invalid_argument("rotate_to_field: malformed bearing scan");
  for (int k = 0; k < kScanRays; ++k) {
    long j = std::lround((static_cast<double>(k) - yaw_deg) * b.rays_per_degree) % n;
    if (j < 0) j += n;
    s.ray_end_px[static_cast<std::size_t>(k)] = b.ray_end_px[static_cast<std::size_t>(j)];
    std::copy_n(b.radii_px.begin() + j * kCrossingsPerRay, kCrossingsPerRay,
                s.radii_px.begin() + k * kCrossingsPerRay);
  }
  return s;
}

void expected_features(const FieldGeometry& field, const CameraModel& cam,
                       const Eigen::Vector2d& pos, std::uint8_t* out,
                       std::vector<WhiteInterval>& iv, int min_gap_px, double bearing_offset_deg) {
  const int k0 = first_sample(cam), k1 = last_sample(cam);
  const double step = cam.scan_step_px();
  const double t_lo = cam.ground_cm_at_radius(k0 * step);
  const double t_hi = cam.ground_cm_at_radius(k1 * step);
  const RayCaster caster(field);
  const auto& dirs = ray_directions();
  for (int k = 0; k < kScanRays; ++k) {
    const Eigen::Vector2d dir = bearing_offset_deg == 0.0
                                    ? dirs[static_cast<std::size_t>(k)]
                                    : Eigen::Vector2d(std::cos(deg_to_rad(k + bearing_offset_deg)),
                                                      std::sin(deg_to_rad(k + bearing_offset_deg)));
    caster.intervals(pos, dir, t_lo, t_hi, iv);
    crossings_of_runs(
        k0, k1, min_gap_px, iv,
        [&cam, step](const WhiteInterval& w) {
          return std::pair{cam.radius_px_at_ground(w.enter_cm) / step,
                           cam.radius_px_at_ground(w.exit_cm) / step};
        },
        out + k * kCrossingsPerRay);
  }
}

Scan expected_scan(const FieldGeometry& field, const CameraModel& cam, const Eigen::Vector2d& pos) {
  Scan s;
  std::vector<WhiteInterval> scratch;
  expected_features(field, cam, pos, s.radii_px.data(), scratch, ScanParams{}.min_gap_px);
  s.ray_end_px.fill(kRayToViewEnd);
  return s;
}

}  // namespace omniloc
