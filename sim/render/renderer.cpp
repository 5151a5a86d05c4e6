#include "omniloc_sim/renderer.hpp"

#include <cmath>
#include <random>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>

namespace omniloc::sim {

namespace {
// Colours (BGR). Chosen so that the scan's thresholds separate them under +-20 % lighting:
// white V >= 188 after dimming, floor beyond the border V <= 110, carpet S ~ 180, robots V ~ 20.
const cv::Vec3f kCarpet(45.0f, 140.0f, 40.0f);
const cv::Vec3f kWhite(235.0f, 235.0f, 232.0f);
const cv::Vec3f kOutside(92.0f, 82.0f, 84.0f);
const cv::Vec3f kRobot(18.0f, 18.0f, 22.0f);
const cv::Vec3f kBody(60.0f, 55.0f, 55.0f);
const cv::Vec3f kMast(70.0f, 70.0f, 75.0f);
const cv::Vec3f kMirrorRim(0.0f, 0.0f, 0.0f);

// Does the floor point q lie behind (or under) obstacle o as seen from the camera at p?
bool hidden_by(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Obstacle& o) {
  const Eigen::Vector2d pq = q - p;
  const double len = pq.norm();
  if (len < 1e-9) return false;
  const Eigen::Vector2d u = pq / len;
  const Eigen::Vector2d f = o.position_cm - p;
  const double along = f.dot(u);
  if (along <= 0.0) return false;  // behind the camera
  const double perp2 = f.squaredNorm() - along * along;
  if (perp2 > o.radius_cm * o.radius_cm) return false;
  const double near = along - std::sqrt(o.radius_cm * o.radius_cm - perp2);
  return near <= len;
}
}  // namespace

RenderOptions noise_free() {
  RenderOptions o;
  o.noise_sigma = 0.0;
  o.blur = false;
  o.gradient_strength = 0.0;
  return o;
}

OmniRenderer::OmniRenderer(FieldGeometry field, CameraModel camera)
    : field_(std::move(field)), lines_(field_), camera_(std::move(camera)) {
  const CameraModel& cam = camera_;
  const double r_min = cam.min_radius_px(), r_view = cam.radius_lut.back().radius_px;
  rays_.resize(static_cast<std::size_t>(cam.width_px) * static_cast<std::size_t>(cam.height_px));
  for (int v = 0; v < cam.height_px; ++v) {
    for (int u = 0; u < cam.width_px; ++u) {
      PixelRay& pr = rays_[static_cast<std::size_t>(v) * static_cast<std::size_t>(cam.width_px) +
                           static_cast<std::size_t>(u)];
      pr = {0.0f, 0.0f, Kind::kFloor};
      const double du = (u - cam.center_px.x()) * (cam.mirrored ? -1.0 : 1.0);
      const double dv = cam.center_px.y() - v;
      const double r = std::hypot(du, dv);
      if (r > r_view) {
        pr.kind = Kind::kRim;
        continue;
      }
      if (r < r_min) {
        pr.kind = Kind::kBody;
        continue;
      }
      const double bearing = rad_to_deg(std::atan2(dv, du)) - cam.yaw_offset_deg;
      if (cam.bearing_hidden(bearing)) {
        pr.kind = Kind::kMast;
        continue;
      }
      const double d = cam.ground_cm_at_radius(r);
      pr.x_cm = static_cast<float>(d * std::cos(deg_to_rad(bearing)));
      pr.y_cm = static_cast<float>(d * std::sin(deg_to_rad(bearing)));
    }
  }
}

namespace {

// The floor at q seen from the robot at p: another robot standing in between, the floor beyond
// the carpet, a white line or the carpet.
cv::Vec3f floor_colour(const FieldGeometry& field, const WhiteLineIndex& lines,
                       const std::vector<Obstacle>& obstacles, const Eigen::Vector2d& p,
                       const Eigen::Vector2d& q) {
  bool behind_robot = false;
  for (const auto& o : obstacles) behind_robot = behind_robot || hidden_by(p, q, o);
  if (behind_robot) return kRobot;
  if (!on_carpet(field, q)) return kOutside;
  return lines.is_white(q) ? kWhite : kCarpet;
}

// The sensor after the optics: noise, then blur, then 8 bits (saturating to 0..255).
cv::Mat sensor_output(cv::Mat3f& img, const RenderOptions& opt) {
  if (opt.noise_sigma > 0.0) {
    cv::Mat3f noise(img.size());
    cv::RNG rng(opt.seed);
    rng.fill(noise, cv::RNG::NORMAL, cv::Scalar::all(0.0), cv::Scalar::all(opt.noise_sigma));
    img += noise;
  }
  if (opt.blur) cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  cv::Mat out;
  img.convertTo(out, CV_8UC3);  // saturates to 0..255
  return out;
}

}  // namespace

cv::Mat OmniRenderer::render(const Pose2& pose, const RenderOptions& opt) const {
  if (opt.realism.enabled) {
    throw std::invalid_argument(
        "OmniRenderer: realistic options need the true optics (use RealisticRenderer)");
  }
  const CameraModel& cam = camera_;
  cv::Mat3f img(cam.height_px, cam.width_px);
  const Eigen::Vector2d p(pose.x_cm, pose.y_cm);
  const double c = std::cos(deg_to_rad(pose.yaw_deg)), s = std::sin(deg_to_rad(pose.yaw_deg));
  const double gd = deg_to_rad(opt.gradient_direction_deg);
  const double half_diag = 0.5 * std::hypot(cam.width_px, cam.height_px);
  for (int v = 0; v < cam.height_px; ++v) {
    auto* row = img.ptr<cv::Vec3f>(v);
    const PixelRay* pr =
        rays_.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(cam.width_px);
    for (int u = 0; u < cam.width_px; ++u) {
      cv::Vec3f colour;
      switch (pr[u].kind) {
        case Kind::kRim:
          colour = kMirrorRim;
          break;
        case Kind::kBody:
          colour = kBody;
          break;
        case Kind::kMast:
          colour = kMast;
          break;
        case Kind::kFloor: {
          const double rx = pr[u].x_cm, ry = pr[u].y_cm;
          const Eigen::Vector2d q(p.x() + c * rx - s * ry, p.y() + s * rx + c * ry);
          colour = floor_colour(field_, lines_, opt.obstacles, p, q);
          break;
        }
      }
      if (opt.gradient_strength != 0.0) {
        const double along =
            ((u - cam.center_px.x()) * std::cos(gd) + (v - cam.center_px.y()) * std::sin(gd)) /
            half_diag;
        colour *= static_cast<float>(1.0 + opt.gradient_strength * along);
      }
      row[u] = colour;
    }
  }
  return sensor_output(img, opt);
}

cv::Mat render_omni(const FieldGeometry& field, const CameraModel& camera, const Pose2& pose,
                    const RenderOptions& opt) {
  return OmniRenderer(field, camera).render(pose, opt);
}

std::vector<Obstacle> random_obstacles(const FieldGeometry& field, const Pose2& pose, int count,
                                       std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> dist(60.0, 250.0), ang(0.0, 2.0 * kPi);
  std::vector<Obstacle> out;
  const Eigen::Vector2d p(pose.x_cm, pose.y_cm);
  for (int attempt = 0; attempt < 1000 && static_cast<int>(out.size()) < count; ++attempt) {
    const double d = dist(rng), a = ang(rng);
    Obstacle o{p + d * Eigen::Vector2d(std::cos(a), std::sin(a)), 20.0};
    if (!on_carpet(field, o.position_cm)) continue;
    bool clear = true;
    for (const auto& e : out)
      clear = clear && (e.position_cm - o.position_cm).norm() > 2.0 * o.radius_cm + 10.0;
    if (clear) out.push_back(o);
  }
  return out;
}

}  // namespace omniloc::sim
