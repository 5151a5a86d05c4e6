#include "omniloc/camera.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "fnv.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/detail/config_reader.hpp"

namespace omniloc {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Linear interpolation in a strictly increasing table column `xs` -> `ys`.
template <class GetX, class GetY>
double interp(const std::vector<RadiusMark>& lut, double x, GetX gx, GetY gy) {
  if (lut.size() < 2 || !(x >= gx(lut.front())) || !(x <= gx(lut.back()))) return kNaN;
  const auto it = std::lower_bound(lut.begin(), lut.end(), x,
                                   [&](const RadiusMark& m, double v) { return gx(m) < v; });
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
  return std::min(image_r, radius_lut.empty() ? 0.0 : radius_lut.back().radius_px);
}

double CameraModel::scan_step_px() const {
  return std::max(1.0, view_radius_px() / kMaxScanSample);
}

int CameraModel::first_scan_sample() const {
  return static_cast<int>(std::ceil(min_radius_px() / scan_step_px()));
}

int CameraModel::last_scan_sample() const {
  // A step above 1 px is the view divided into kMaxScanSample samples: the last one is the view's
  // end.
  const double step = scan_step_px();
  return step > 1.0 ? kMaxScanSample : static_cast<int>(std::floor(view_radius_px()));
}

double CameraModel::min_radius_px() const {
  return std::max(body_radius_px, radius_lut.empty() ? 0.0 : radius_lut.front().radius_px);
}

double CameraModel::ground_cm_at_radius(double r) const {
  return interp(
      radius_lut, r, [](const RadiusMark& m) { return m.radius_px; },
      [](const RadiusMark& m) { return m.ground_cm; });
}

double CameraModel::radius_px_at_ground(double d) const {
  return interp(
      radius_lut, d, [](const RadiusMark& m) { return m.ground_cm; },
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

void CameraModel::validate(const config::Origin& at) const {
  using config::require;
  require(width_px >= 1 && width_px <= 16384, at / "width", "must be a pixel count in 1..16384",
          width_px);
  require(height_px >= 1 && height_px <= 16384, at / "height", "must be a pixel count in 1..16384",
          height_px);
  const bool centre_inside = center_px.x() >= 0 && center_px.y() >= 0 &&
                             center_px.x() <= width_px - 1.0 && center_px.y() <= height_px - 1.0;
  require(
      centre_inside, at / "center_px",
      "lies outside the " + std::to_string(width_px) + " x " + std::to_string(height_px) + " image",
      config::show({center_px.x(), center_px.y()}));
  if (radius_lut.size() < 2)
    (at / "radius_lut")
        .fail("must be a list of at least two [r_px, d_cm] pairs",
              std::to_string(radius_lut.size()) + " row(s)");
  for (std::size_t i = 0; i < radius_lut.size(); ++i) {
    const RadiusMark& m = radius_lut[i];
    const std::string row = config::show({m.radius_px, m.ground_cm});
    require(m.radius_px >= 0 && m.ground_cm >= 0, (at / "radius_lut")[i], "values must be >= 0",
            row);
    if (i > 0)
      require(
          m.radius_px > radius_lut[i - 1].radius_px && m.ground_cm > radius_lut[i - 1].ground_cm,
          (at / "radius_lut")[i], "table must be strictly increasing in both radius and distance",
          row);
  }
  require(std::isfinite(yaw_offset_deg) && std::abs(yaw_offset_deg) <= 360.0, at / "yaw_offset_deg",
          "must be an angle within [-360, 360] degrees", yaw_offset_deg);
  require(std::isfinite(body_radius_px) && body_radius_px >= 0.0, at / "mask" / "body_radius_px",
          "must be >= 0", body_radius_px);
  for (std::size_t i = 0; i < masts.size(); ++i) {
    const config::Origin m = (at / "mask" / "masts")[i];
    require(std::isfinite(masts[i].bearing_deg), m / "bearing_deg", "must be finite",
            masts[i].bearing_deg);
    require(masts[i].half_width_deg >= 0.0 && masts[i].half_width_deg < 90.0, m / "half_width_deg",
            "must be in [0, 90)", masts[i].half_width_deg);
  }
  vision.validate(at / "vision");
  require(last_scan_sample() > first_scan_sample() + 2, at,
          "no visible floor ring: the image or 'radius_lut' ends inside the body radius " +
              config::show(min_radius_px()) + " px",
          config::show(view_radius_px()) + " px");
}

namespace {

const config::KeyTable<MastSector>& mast_keys() {
  using config::Need;
  static const config::KeyTable<MastSector> table = {
      config::key("bearing_deg", &MastSector::bearing_deg, Need::kRequired),
      config::key("half_width_deg", &MastSector::half_width_deg, Need::kRequired),
  };
  return table;
}

}  // namespace
}  // namespace omniloc

namespace omniloc::config {

/// A calibration row [r_px, d_cm].
template <>
struct Codec<RadiusMark> {
  static constexpr Kind kKind = Kind::kOther;
  static RadiusMark read(const Node& n) {
    n.expect_array(2);
    return {n[0].number(), n[1].number()};
  }
  static Json write(const RadiusMark& m) { return Json::array({m.radius_px, m.ground_cm}); }
};

template <>
struct Codec<MastSector> : TableCodec<MastSector, &mast_keys> {};

}  // namespace omniloc::config

namespace omniloc {

const config::KeyTable<CameraModel>& camera_keys() {
  using config::key;
  using config::Need;
  using C = CameraModel;
  static const config::KeyTable<CameraModel> table = {
      config::note<C>("description"),
      config::record<C>("calibration"),  // written by `omniloc calibrate` (docs/CALIBRATION.md)
      key("width", &C::width_px, Need::kRequired),
      key("height", &C::height_px, Need::kRequired),
      key("center_px", &C::center_px, Need::kRequired),
      key("radius_lut", &C::radius_lut, Need::kRequired),
      key("yaw_offset_deg", &C::yaw_offset_deg, Need::kRequired),
      key("mirrored", &C::mirrored, Need::kRequired),
      config::group<C>("mask",
                       {
                           key("body_radius_px", &C::body_radius_px, Need::kRequired),
                           key("masts", &C::masts),
                       }),
      config::nested("vision", &C::vision, vision_keys()),  // optional; not in fingerprint()
  };
  return table;
}

CameraModel camera_from_json(const config::Node& node) {
  CameraModel cam;
  // Without a mask nothing of the floor is hidden (the initialisers would say the same, but the
  // file, not C++, is where a camera's values come from).
  cam.body_radius_px = 0.0;
  cam.masts.clear();
  config::read_keys(node, camera_keys(), cam);
  cam.validate(node.origin());
  return cam;
}

CameraModel load_camera(const std::string& name_or_path) {
  return camera_from_json(
      config::parse_json_file(resolve_data_file("cameras", name_or_path)).root());
}

}  // namespace omniloc
