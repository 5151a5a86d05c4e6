#include "omniloc/camera.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/core/persistence.hpp>

#include "fnv.hpp"
#include "json_read.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/data_files.hpp"

namespace omniloc {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Linear interpolation in a strictly increasing table column `xs` -> `ys`.
template <class GetX, class GetY>
double interp(const std::vector<RadiusMark>& lut, double x, GetX gx, GetY gy) {
  if (lut.size() < 2 || !(x >= gx(lut.front())) || !(x <= gx(lut.back()))) return kNaN;
  const auto it = std::lower_bound(lut.begin(), lut.end(), x, [&](const RadiusMark& m, double v) { return gx(m) < v; });
  if (it == lut.begin()) return gy(*it);
  const RadiusMark& hi = *it;
  const RadiusMark& lo = *(it - 1);
  const double f = (x - gx(lo)) / (gx(hi) - gx(lo));
  return gy(lo) + f * (gy(hi) - gy(lo));
}
}  // namespace

double CameraModel::view_radius_px() const {
  const double image_r = std::min({center_px.x(), center_px.y(), width_px - 1.0 - center_px.x(),
                                   height_px - 1.0 - center_px.y()});
  // 254 px: crossing radii are stored as uint8 with 255 reserved for "no crossing".
  return std::min({image_r, radius_lut.empty() ? 0.0 : radius_lut.back().radius_px, 254.0});
}

double CameraModel::min_radius_px() const {
  return std::max(body_radius_px, radius_lut.empty() ? 0.0 : radius_lut.front().radius_px);
}

double CameraModel::ground_cm_at_radius(double r) const {
  return interp(radius_lut, r, [](const RadiusMark& m) { return m.radius_px; },
                [](const RadiusMark& m) { return m.ground_cm; });
}

double CameraModel::radius_px_at_ground(double d) const {
  return interp(radius_lut, d, [](const RadiusMark& m) { return m.ground_cm; },
                [](const RadiusMark& m) { return m.radius_px; });
}

std::optional<Eigen::Vector2d> CameraModel::pixel_of_robot_point(const Eigen::Vector2d& p) const {
  const double r = radius_px_at_ground(p.norm());
  if (std::isnan(r)) return std::nullopt;
  const double phi = deg_to_rad(image_angle_deg(rad_to_deg(std::atan2(p.y(), p.x()))));
  const double du = r * std::cos(phi);
  return Eigen::Vector2d(center_px.x() + (mirrored ? -du : du), center_px.y() - r * std::sin(phi));
}

std::optional<Eigen::Vector2d> CameraModel::robot_point_of_pixel(const Eigen::Vector2d& px) const {
  const double du = (px.x() - center_px.x()) * (mirrored ? -1.0 : 1.0);
  const double dv = center_px.y() - px.y();
  const double r = std::hypot(du, dv);
  const double d = ground_cm_at_radius(r);
  if (std::isnan(d)) return std::nullopt;
  const double bearing = std::atan2(dv, du) - deg_to_rad(yaw_offset_deg);
  return Eigen::Vector2d(d * std::cos(bearing), d * std::sin(bearing));
}

bool CameraModel::bearing_hidden(double bearing_deg) const {
  for (const auto& m : masts) {
    if (std::abs(angle_diff_deg(bearing_deg, m.bearing_deg)) <= m.half_width_deg) return true;
  }
  return false;
}

std::uint64_t CameraModel::fingerprint() const {
  using detail::fnv1a_double;
  std::uint64_t h = detail::kFnvOffset;
  // Masks and mirroring do not change where a floor point lands radially, but the database stores
  // field-frame radii only, so the fingerprint covers just what the database depends on: the
  // table and the visible ring. (Centre, yaw offset and mirroring matter to the scan, not to it.)
  for (const auto& m : radius_lut) {
    h = fnv1a_double(m.radius_px, h);
    h = fnv1a_double(m.ground_cm, h);
  }
  h = fnv1a_double(min_radius_px(), h);
  h = fnv1a_double(view_radius_px(), h);
  return h;
}

CameraModel camera_from_json(const cv::FileNode& node, const std::string& ctx) {
  using detail::read_number;
  using detail::read_positive;
  if (!node.isMap()) throw std::runtime_error(ctx + ": expected a JSON object");
  CameraModel cam;
  const double w = read_positive(node, "width", ctx);
  const double h = read_positive(node, "height", ctx);
  if (w != std::floor(w) || h != std::floor(h) || w > 16384 || h > 16384) {
    throw std::runtime_error(ctx + ": fields 'width'/'height' must be whole pixel counts up to 16384");
  }
  cam.width_px = static_cast<int>(w);
  cam.height_px = static_cast<int>(h);
  const cv::FileNode c = node["center_px"];
  if (c.empty()) throw std::runtime_error(ctx + ": missing field 'center_px'");
  detail::read_pair(c, ctx + ": field 'center_px'", cam.center_px.x(), cam.center_px.y());
  if (cam.center_px.x() < 0 || cam.center_px.y() < 0 || cam.center_px.x() > w - 1 || cam.center_px.y() > h - 1) {
    throw std::runtime_error(ctx + ": field 'center_px' lies outside the " + std::to_string(cam.width_px) + " x " +
                             std::to_string(cam.height_px) + " image");
  }
  const cv::FileNode lut = node["radius_lut"];
  if (!lut.isSeq() || lut.size() < 2) {
    throw std::runtime_error(ctx + ": field 'radius_lut' must be a list of at least two [r_px, d_cm] pairs");
  }
  for (int i = 0; i < static_cast<int>(lut.size()); ++i) {
    const std::string row = ctx + ": field 'radius_lut' row " + std::to_string(i);
    RadiusMark m{};
    detail::read_pair(lut[i], row, m.radius_px, m.ground_cm);
    if (m.radius_px < 0 || m.ground_cm < 0) throw std::runtime_error(row + ": values must be >= 0");
    if (!cam.radius_lut.empty() &&
        (m.radius_px <= cam.radius_lut.back().radius_px || m.ground_cm <= cam.radius_lut.back().ground_cm)) {
      throw std::runtime_error(row + ": table must be strictly increasing in both radius and distance");
    }
    cam.radius_lut.push_back(m);
  }
  cam.yaw_offset_deg = read_number(node, "yaw_offset_deg", ctx);
  const cv::FileNode mir = node["mirrored"];
  if (mir.empty() || mir.isNone()) throw std::runtime_error(ctx + ": missing field 'mirrored'");
  if (!mir.isInt()) throw std::runtime_error(ctx + ": field 'mirrored' must be true or false");
  cam.mirrored = static_cast<int>(mir) != 0;
  const cv::FileNode mask = node["mask"];
  if (!mask.empty() && !mask.isNone()) {
    const std::string mctx = ctx + ": field 'mask'";
    if (!mask.isMap()) throw std::runtime_error(mctx + " must be an object");
    cam.body_radius_px = read_positive(mask, "body_radius_px", mctx, true);
    const cv::FileNode masts = mask["masts"];
    if (!masts.empty() && !masts.isNone()) {
      if (!masts.isSeq()) throw std::runtime_error(mctx + ": field 'masts' must be a list");
      for (int i = 0; i < static_cast<int>(masts.size()); ++i) {
        const std::string e = mctx + " masts[" + std::to_string(i) + "]";
        MastSector s;
        s.bearing_deg = read_number(masts[i], "bearing_deg", e);
        s.half_width_deg = read_positive(masts[i], "half_width_deg", e, true);
        if (s.half_width_deg >= 90.0) throw std::runtime_error(e + ": field 'half_width_deg' must be < 90");
        cam.masts.push_back(s);
      }
    }
  }
  if (cam.view_radius_px() <= cam.min_radius_px() + 2.0) {
    throw std::runtime_error(ctx + ": no visible floor ring: the image or 'radius_lut' ends at radius " +
                             std::to_string(cam.view_radius_px()) + " px, inside the body radius " +
                             std::to_string(cam.min_radius_px()) + " px");
  }
  return cam;
}

CameraModel load_camera(const std::string& name_or_path) {
  const std::string file = resolve_data_file("cameras", name_or_path).string();
  cv::FileStorage fs = detail::open_json(file);
  return camera_from_json(fs.root(), file);
}

}  // namespace omniloc
