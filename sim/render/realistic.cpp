// Realistic omni frames (issue 13 item 6): a 3-D scene seen through a true hyperbolic-mirror camera
// (TrueOptics) that is not the database's CameraModel. See renderer.hpp for the optics' formula.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc_sim/renderer.hpp"

namespace omniloc::sim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The colours are SceneLook's (renderer.hpp): today's defaults, or a sampled venue's.

// Deterministic hash of integer cell coordinates to [0, 1): procedural textures.
double cell_hash(std::int64_t a, std::int64_t b, std::uint64_t seed) {
  std::uint64_t h = seed ^ 0x9E3779B97F4A7C15ull;
  for (const std::int64_t v : {a, b}) {
    h ^= static_cast<std::uint64_t>(v) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
  }
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

// Textured surface: blocks (posters, doors, shelves) brighter or darker than the base.
float block_factor(double s_cm, double z_cm, double cell_s, double cell_z, std::uint64_t seed) {
  const double h = cell_hash(static_cast<std::int64_t>(std::floor(s_cm / cell_s)),
                             static_cast<std::int64_t>(std::floor(z_cm / cell_z)), seed);
  return static_cast<float>(0.45 + 1.0 * h);
}

Eigen::Matrix3d tilt_rotation(const TrueOptics& o) {
  const double t = deg_to_rad(o.tilt_towards_deg);
  return Eigen::AngleAxisd(deg_to_rad(o.tilt_deg), Eigen::Vector3d(-std::sin(t), std::cos(t), 0.0))
      .toRotationMatrix();
}

// The profiles other than the hyperbola (whose unit-sphere form is kept as it was): the pixel's
// radius gives theta, its image angle the azimuth; then the tilt and the yaw offset as for it.
Eigen::Vector3d profile_ray_of_pixel(const TrueOptics& o, const Eigen::Vector2d& px) {
  const double ua = (px.x() - o.centre_px.x()) * (o.mirrored ? -1.0 : 1.0);
  const double vb = o.centre_px.y() - px.y();
  const double r = std::hypot(ua, vb);
  const double theta = o.theta_rad_at_radius(r);
  const Eigen::Vector3d local =
      r > 1e-12
          ? Eigen::Vector3d(std::sin(theta) * ua / r, std::sin(theta) * vb / r, std::cos(theta))
          : Eigen::Vector3d(0.0, 0.0, 1.0);
  const Eigen::Vector3d img = tilt_rotation(o) * local;
  const double c = std::cos(deg_to_rad(-o.yaw_offset_deg)),
               s = std::sin(deg_to_rad(-o.yaw_offset_deg));
  return Eigen::Vector3d(c * img.x() - s * img.y(), s * img.x() + c * img.y(), img.z())
      .normalized();
}

std::optional<Eigen::Vector2d> profile_pixel_of_robot_point(const TrueOptics& o,
                                                            const Eigen::Vector3d& p) {
  const Eigen::Vector3d d =
      Eigen::Vector3d(p.x(), p.y(), o.viewpoint_height_cm - p.z()).normalized();
  const double c = std::cos(deg_to_rad(o.yaw_offset_deg)),
               s = std::sin(deg_to_rad(o.yaw_offset_deg));
  const Eigen::Vector3d x = tilt_rotation(o).transpose() *
                            Eigen::Vector3d(c * d.x() - s * d.y(), s * d.x() + c * d.y(), d.z());
  const double theta = std::acos(std::clamp(x.z(), -1.0, 1.0));
  if (theta >= o.max_theta_rad() - 1e-9) return std::nullopt;
  const double r = o.radius_px_at_theta(theta), n = std::hypot(x.x(), x.y());
  const double ma = n > 1e-15 ? r * x.x() / n : 0.0, mb = n > 1e-15 ? r * x.y() / n : 0.0;
  return Eigen::Vector2d(o.centre_px.x() + ma * (o.mirrored ? -1.0 : 1.0), o.centre_px.y() - mb);
}

// The profile's own parameters must describe a mapping that increases from the centre outwards.
void check_optics(const TrueOptics& o) {
  if (o.width_px < 1 || o.height_px < 1 || !(o.viewpoint_height_cm > 0.0) ||
      !(o.mirror_radius_px > 0.0))
    throw std::invalid_argument(
        "TrueOptics: size, viewpoint_height_cm > 0 and mirror_radius_px > 0 are required");
  bool ok = true;
  switch (o.profile) {
    case MirrorProfile::kHyperbolic:
      ok = o.focal_px > 0.0 && o.xi > 0.0 && o.xi < 1.0;
      break;
    case MirrorProfile::kTangent:
      ok = o.tan_a_cm > 0.0 && o.tan_b_per_px > 0.0 && o.tan_b_per_px * o.mirror_radius_px < kPi;
      break;
    case MirrorProfile::kSpherical:
      ok = o.sphere_radius_px > o.mirror_radius_px;
      break;
    case MirrorProfile::kConical:
      ok = o.cone_tip_deg >= 0.0 && o.cone_tip_px > 0.0 && o.cone_deg_per_px > 0.0;
      break;
  }
  if (!ok)
    throw std::invalid_argument(
        std::string("TrueOptics: bad parameters for the ") + mirror_profile_name(o.profile) +
        " profile (hyperbolic: focal_px > 0, 0 < xi < 1; tangent: a, b > 0, b x rim < pi; "
        "spherical: sphere radius > rim; conical: tip >= 0, tip_px > 0, deg_per_px > 0)");
}

struct Hit {
  enum Type { kNone, kFloor, kPanel, kColumnSide, kColumnTop } type = kNone;
  double t = kInf;
  int index = -1;
  double s = 0.0, z = 0.0;  // position on a panel (along, height) for its texture
};

// Signed distance (cm, < 0 inside) from q to the nearest white line, each with its own width.
double line_distance_cm(const FieldGeometry& f, const std::vector<double>& width,
                        const Eigen::Vector2d& q) {
  double best = kInf;
  std::size_t i = 0;
  for (const auto& s : f.segments) {
    const double half = 0.5 * width[i++];
    const Eigen::Vector2d ab = s.b_cm - s.a_cm;
    const double len = ab.norm();
    const Eigen::Vector2d ex = ab / len;
    const Eigen::Vector2d ap = q - s.a_cm;
    const double along = ap.dot(ex), across = std::abs(ex.x() * ap.y() - ex.y() * ap.x());
    best = std::min(best, std::max({across - half, -along - half, along - len - half}));
  }
  for (const auto& a : f.arcs) {
    const double half = 0.5 * width[i++];
    const Eigen::Vector2d d = q - a.centre_cm;
    const double radial = std::abs(d.norm() - a.radius_cm) - half;
    if (radial > best) continue;
    bool inside = a.end_deg - a.start_deg >= 360.0;
    if (!inside) {
      double rel = std::fmod(rad_to_deg(std::atan2(d.y(), d.x())) - a.start_deg, 360.0);
      if (rel < 0.0) rel += 360.0;
      inside = rel <= a.end_deg - a.start_deg;
    }
    if (inside) best = radial;
  }
  // A mark's radius varies with its "line" width like a painted disc would.
  for (const auto& d : f.discs)
    best = std::min(best, (q - d.centre_cm).norm() - d.radius_cm * width[i++] / f.line_width_cm);
  return best;
}

bool in_goal_box(const FieldGeometry& f, const Eigen::Vector2d& q, bool& at_x_max) {
  const double cy = f.centre_cm().y(), w = f.goal.width_cm, d = f.goal.depth_cm;
  if (std::abs(q.y() - cy) > w / 2.0) return false;
  const double x0 = f.border_cm, x1 = f.border_cm + f.field_length_cm;
  if (q.x() < x0 && q.x() >= x0 - d) {
    at_x_max = false;
    return true;
  }
  if (q.x() > x1 && q.x() <= x1 + d) {
    at_x_max = true;
    return true;
  }
  return false;
}

cv::Vec3f goal_paint(const SceneLook& look, GoalColour c) {
  return c == GoalColour::kYellow ? look.goal_yellow : look.goal_blue;
}

GoalColour colour_at_x_max(const FieldGeometry& f, const RealismOptions& r) {
  return f.goal.colour_at_x_max != GoalColour::kUnknown ? f.goal.colour_at_x_max
                                                        : r.goal_colour_at_x_max;
}

GoalColour other(GoalColour c) {
  return c == GoalColour::kYellow ? GoalColour::kBlue : GoalColour::kYellow;
}

// The carpet at q with its lines: grain (3 cm), patches (40 cm) on a textured carpet, and lines
// worn in 25 cm stretches (dimmer, or gone where the wear is worst) as on an old venue's carpet.
cv::Vec3f carpet_colour(const FieldGeometry& f, const Scene& sc, const SceneLook& lk,
                        const Eigen::Vector2d& q, double footprint_cm, std::uint64_t tex_seed) {
  const double sd = line_distance_cm(f, sc.line_width_cm, q);
  float cover = static_cast<float>(std::clamp(0.5 - sd / footprint_cm, 0.0, 1.0));
  if (lk.line_wear > 0.0 && cover > 0.0f) {
    const double w = cell_hash(std::lround(q.x() / 25.0), std::lround(q.y() / 25.0), tex_seed + 9);
    if (w < lk.line_wear)
      cover *= w < lk.line_wear / 3.0 ? 0.0f : static_cast<float>(0.35 + 0.4 * w / lk.line_wear);
  }
  const float g = static_cast<float>(lk.carpet_grain);
  const float grain = static_cast<float>(1.0 - lk.carpet_grain / 2.0) +
                      g * static_cast<float>(cell_hash(std::lround(q.x() / 3.0),
                                                       std::lround(q.y() / 3.0), tex_seed));
  cv::Vec3f carpet = lk.carpet * grain;
  if (lk.carpet_patch_contrast > 0.0) {
    const double p = cell_hash(static_cast<std::int64_t>(std::floor(q.x() / 40.0)),
                               static_cast<std::int64_t>(std::floor(q.y() / 40.0)), tex_seed + 13);
    carpet *= static_cast<float>(1.0 + lk.carpet_patch_contrast * (2.0 * p - 1.0));
  }
  return carpet * (1.0f - cover) + lk.line * cover;
}

}  // namespace

bool on_look_carpet(const FieldGeometry& f, const SceneLook& look, const Eigen::Vector2d& q) {
  if (!on_carpet(f, q)) return false;
  const double* in = look.carpet_inset_cm;
  return q.x() >= in[0] && q.x() <= f.total_x_cm() - in[1] && q.y() >= in[2] &&
         q.y() <= f.total_y_cm() - in[3];
}

// --- optics
// ---------------------------------------------------------------------------------------

const char* mirror_profile_name(MirrorProfile p) {
  switch (p) {
    case MirrorProfile::kHyperbolic:
      return "hyperbolic";
    case MirrorProfile::kTangent:
      return "tangent";
    case MirrorProfile::kSpherical:
      return "spherical";
    case MirrorProfile::kConical:
      return "conical";
  }
  return "unknown";
}

double TrueOptics::max_theta_rad() const {
  // The hyperbola maps rays up to its asymptote, cos theta = -xi; the others up to straight up.
  return profile == MirrorProfile::kHyperbolic ? std::acos(-xi) : kPi;
}

double TrueOptics::theta_rad_at_radius(double r) const {
  switch (profile) {
    case MirrorProfile::kHyperbolic: {
      const double m = r / focal_px;
      const double lambda = (xi + std::sqrt(1.0 + (1.0 - xi * xi) * m * m)) / (1.0 + m * m);
      return std::atan2(lambda * m, lambda - xi);
    }
    case MirrorProfile::kTangent: {
      const double br = std::clamp(tan_b_per_px * r, 0.0, kPi);
      return std::atan2(tan_a_cm / viewpoint_height_cm * std::sin(br), std::cos(br));
    }
    case MirrorProfile::kSpherical:
      return 2.0 * std::asin(std::clamp(r / sphere_radius_px, 0.0, 1.0));
    case MirrorProfile::kConical:
      return std::min(kPi,
                      deg_to_rad(cone_tip_deg * std::tanh(r / cone_tip_px) + cone_deg_per_px * r));
  }
  return 0.0;
}

double TrueOptics::radius_px_at_theta(double theta) const {
  switch (profile) {
    case MirrorProfile::kHyperbolic:
      return focal_px * std::sin(theta) / (std::cos(theta) + xi);
    case MirrorProfile::kTangent:
      return std::atan2(viewpoint_height_cm / tan_a_cm * std::sin(theta), std::cos(theta)) /
             tan_b_per_px;
    case MirrorProfile::kSpherical:
      return sphere_radius_px * std::sin(theta / 2.0);
    case MirrorProfile::kConical: {
      // No closed form: theta(r) increases strictly, so bisect to the last bit.
      double lo = 0.0, hi = 180.0 / cone_deg_per_px;
      for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (theta_rad_at_radius(mid) < theta ? lo : hi) = mid;
      }
      return 0.5 * (lo + hi);
    }
  }
  return 0.0;
}

Eigen::Vector3d TrueOptics::ray_of_pixel(const Eigen::Vector2d& px) const {
  if (profile != MirrorProfile::kHyperbolic) return profile_ray_of_pixel(*this, px);
  const double ma = (px.x() - centre_px.x()) / focal_px * (mirrored ? -1.0 : 1.0);
  const double mb = (centre_px.y() - px.y()) / focal_px;
  const double m2 = ma * ma + mb * mb;
  const double lambda = (xi + std::sqrt(1.0 + (1.0 - xi * xi) * m2)) / (1.0 + m2);
  const Eigen::Vector3d img =
      tilt_rotation(*this) * Eigen::Vector3d(lambda * ma, lambda * mb, lambda - xi);
  // Image angle = bearing + yaw offset: turn back by the offset into the robot frame.
  const double c = std::cos(deg_to_rad(-yaw_offset_deg)), s = std::sin(deg_to_rad(-yaw_offset_deg));
  return Eigen::Vector3d(c * img.x() - s * img.y(), s * img.x() + c * img.y(), img.z())
      .normalized();
}

std::optional<Eigen::Vector2d> TrueOptics::pixel_of_robot_point(const Eigen::Vector3d& p) const {
  if (profile != MirrorProfile::kHyperbolic) return profile_pixel_of_robot_point(*this, p);
  const Eigen::Vector3d d = Eigen::Vector3d(p.x(), p.y(), viewpoint_height_cm - p.z()).normalized();
  const double c = std::cos(deg_to_rad(yaw_offset_deg)), s = std::sin(deg_to_rad(yaw_offset_deg));
  const Eigen::Vector3d img(c * d.x() - s * d.y(), s * d.x() + c * d.y(), d.z());
  const Eigen::Vector3d x = tilt_rotation(*this).transpose() * img;
  if (x.z() + xi <= 1e-9) return std::nullopt;
  const double ma = x.x() / (x.z() + xi), mb = x.y() / (x.z() + xi);
  return Eigen::Vector2d(centre_px.x() + focal_px * ma * (mirrored ? -1.0 : 1.0),
                         centre_px.y() - focal_px * mb);
}

double TrueOptics::radius_px_at_ground(double d) const {
  if (profile != MirrorProfile::kHyperbolic)
    return radius_px_at_theta(std::atan2(d, viewpoint_height_cm));
  const double h = viewpoint_height_cm;
  return focal_px * d / (h + xi * std::sqrt(d * d + h * h));
}

double TrueOptics::ground_cm_at_radius(double r) const {
  if (profile == MirrorProfile::kTangent) {
    const double br = tan_b_per_px * r;  // the model's own form, exact where it is defined
    return br < kPi / 2.0 ? tan_a_cm * std::tan(br) : std::numeric_limits<double>::quiet_NaN();
  }
  if (profile != MirrorProfile::kHyperbolic) {
    const double theta = theta_rad_at_radius(r);
    return theta < kPi / 2.0 ? viewpoint_height_cm * std::tan(theta)
                             : std::numeric_limits<double>::quiet_NaN();
  }
  const double m = r / focal_px;
  const double lambda = (xi + std::sqrt(1.0 + (1.0 - xi * xi) * m * m)) / (1.0 + m * m);
  if (lambda - xi <= 1e-12)
    return std::numeric_limits<double>::quiet_NaN();  // at or above the horizon
  return viewpoint_height_cm * lambda * m / (lambda - xi);
}

CameraModel nominal_camera(const TrueOptics& o, double max_ground_cm) {
  CameraModel cam;
  cam.width_px = o.width_px;
  cam.height_px = o.height_px;
  cam.center_px = o.centre_px;
  cam.yaw_offset_deg = o.yaw_offset_deg;
  cam.mirrored = o.mirrored;
  cam.body_radius_px = o.radius_px_at_ground(o.body_radius_cm);
  cam.radius_lut.clear();
  const double r_end = std::min(o.mirror_radius_px, o.radius_px_at_ground(max_ground_cm));
  for (double r = 0.0; r < r_end; r += 4.0)
    cam.radius_lut.push_back({r, r == 0.0 ? 0.0 : o.ground_cm_at_radius(r)});
  cam.radius_lut.push_back({r_end, o.ground_cm_at_radius(r_end)});
  return cam;
}

// --- scene
// ----------------------------------------------------------------------------------------

RenderOptions realistic(std::uint64_t seed) {
  RenderOptions o;
  o.seed = seed;
  o.noise_sigma = 4.0;
  o.blur = true;
  o.gradient_strength = 0.1;
  o.realism.enabled = true;
  return o;
}

namespace {

// The scene's random draws, in one sequence: every step below draws from it in turn, so their
// order is the scene's seed. Two draws are never arguments of one call (or one parenthesised
// constructor): C++ leaves the order of those open, gcc and clang take opposite ones, and a seed
// named two scenes. Where draws were once arguments, they are now made one per statement in the
// order gcc took (the right-most first), so each seed still names the scene it was tested on.
struct SceneDraws {
  std::mt19937_64 rng;
  std::uniform_real_distribution<double> u01{0.0, 1.0};
  double uni(double a, double b) { return a + (b - a) * u01(rng); }
};

// The room's floor beyond the carpet: [-m0, X + m1] x [-m2, Y + m3].
struct Room {
  double m0, m1, m2, m3, X, Y;
};

// Room: each wall 60..250 cm beyond the carpet, bright, middling or dark, textured.
Room add_room_walls(Scene& sc, const FieldGeometry& f, const RealismOptions& r, SceneDraws& d) {
  const double X = f.total_x_cm(), Y = f.total_y_cm();
  const double m0 = d.uni(60, 250), m1 = d.uni(60, 250), m2 = d.uni(60, 250), m3 = d.uni(60, 250);
  const Eigen::Vector2d c00(-m0, -m2), c10(X + m1, -m2), c11(X + m1, Y + m3), c01(-m0, Y + m3);
  const std::vector<cv::Vec3f>& palette = r.look.walls;
  if (palette.empty()) throw std::invalid_argument("SceneLook: no wall colours");
  // (n - 0.001: today's uni(0, 3.999) for the four default paints.)
  const double n_walls = static_cast<double>(palette.size()) - 0.001;
  for (const auto& [a, b] :
       {std::pair{c00, c10}, std::pair{c10, c11}, std::pair{c11, c01}, std::pair{c01, c00}})
    sc.panels.push_back(
        {a, b, r.wall_height_cm, palette[static_cast<std::size_t>(d.uni(0, n_walls))], true});
  return {m0, m1, m2, m3, X, Y};
}

// Goal boxes: back wall and two sides behind each goal line, painted.
void add_goal_boxes(Scene& sc, const FieldGeometry& f, const RealismOptions& r) {
  const double cy = f.centre_cm().y(), gw = f.goal.width_cm / 2.0, gd = f.goal.depth_cm;
  const GoalColour at_max = colour_at_x_max(f, r);
  for (const bool x_max : {false, true}) {
    if (!r.look.goals) break;
    const double xg = x_max ? f.border_cm + f.field_length_cm : f.border_cm;
    const double xb = x_max ? xg + gd : xg - gd;
    const cv::Vec3f paint = goal_paint(r.look, x_max ? at_max : other(at_max));
    sc.panels.push_back({{xb, cy - gw}, {xb, cy + gw}, r.goal_height_cm, paint, false});
    sc.panels.push_back({{xg, cy - gw}, {xb, cy - gw}, r.goal_height_cm, paint, false});
    sc.panels.push_back({{xg, cy + gw}, {xb, cy + gw}, r.goal_height_cm, paint, false});
  }
}

// A column of radius rad at q keeps clear of the robot (at p) and of the columns placed so far.
bool clear_of(const Scene& sc, const Eigen::Vector2d& p, const Eigen::Vector2d& q, double rad) {
  if ((q - p).norm() < rad + 35.0) return false;
  for (const auto& c : sc.columns)
    if ((c.position_cm - q).norm() < c.radius_cm + rad + 10.0) return false;
  return true;
}

// count columns made by make(q) on the room's floor off the carpet (people, furniture).
template <typename Make>
void add_off_carpet(Scene& sc, const Room& room, const Eigen::Vector2d& p, int count, SceneDraws& d,
                    Make make) {
  const double m0 = room.m0, m1 = room.m1, m2 = room.m2, m3 = room.m3, X = room.X, Y = room.Y;
  for (int k = 0, attempt = 0; k < count && attempt < 2000; ++attempt) {
    const double qy = d.uni(-m2, Y + m3);  // y first (SceneDraws)
    const double qx = d.uni(-m0, X + m1);
    const Eigen::Vector2d q(qx, qy);
    Column c = make(q);
    const bool in_room = q.x() - c.radius_cm > -m0 && q.x() + c.radius_cm < X + m1 &&
                         q.y() - c.radius_cm > -m2 && q.y() + c.radius_cm < Y + m3;
    const bool off_carpet = q.x() < -c.radius_cm || q.x() > X + c.radius_cm ||
                            q.y() < -c.radius_cm || q.y() > Y + c.radius_cm;
    if (!in_room || !off_carpet || !clear_of(sc, p, q, c.radius_cm)) continue;
    sc.columns.push_back(c);
    ++k;
  }
}

// Robots: dark bodies, some with a coloured top (team markers), 60..250 cm away on the carpet.
void add_robots(Scene& sc, const FieldGeometry& f, const RealismOptions& r,
                const Eigen::Vector2d& p, SceneDraws& d) {
  const cv::Vec3f dark = r.look.robot_dark;
  const cv::Vec3f tops[] = {dark, {180, 40, 200}, {200, 190, 40}, {60, 60, 200}};
  for (int k = 0, attempt = 0; k < r.robots && attempt < 2000; ++attempt) {
    const double dist = d.uni(60, 250), a = d.uni(0, 2 * kPi);
    const Eigen::Vector2d q = p + dist * Eigen::Vector2d(std::cos(a), std::sin(a));
    if (!on_look_carpet(f, r.look, q) || !clear_of(sc, p, q, 22.0)) continue;
    sc.columns.push_back(
        {q, 22.0, d.uni(55, 75), dark, tops[static_cast<int>(d.uni(0, 3.999))], false});
    ++k;
  }
}

// The ball 45..160 cm away on the carpet, clear of the robots.
void add_ball(Scene& sc, const FieldGeometry& f, const RealismOptions& r, const Eigen::Vector2d& p,
              SceneDraws& d) {
  for (int attempt = 0; attempt < 2000; ++attempt) {
    const double dist = d.uni(45, 160), a = d.uni(0, 2 * kPi);
    const Eigen::Vector2d q = p + dist * Eigen::Vector2d(std::cos(a), std::sin(a));
    if (!on_look_carpet(f, r.look, q) || !clear_of(sc, p, q, 11.0)) continue;
    sc.columns.push_back({q, 11.0, 21.0, r.look.ball, r.look.ball, false});
    sc.ball_cm = q;
    break;
  }
}

}  // namespace

Scene realistic_scene(const FieldGeometry& f, const Pose2& pose, const RenderOptions& opt) {
  const RealismOptions& r = opt.realism;
  Scene sc;
  SceneDraws d{std::mt19937_64(opt.seed * 0x2545F4914F6CDD1Dull + 17)};
  auto uni = [&](double a, double b) { return d.uni(a, b); };
  const Room room = add_room_walls(sc, f, r, d);
  add_goal_boxes(sc, f, r);
  const Eigen::Vector2d p(pose.x_cm, pose.y_cm);
  const cv::Vec3f dark = r.look.robot_dark;
  for (const auto& o : opt.obstacles)
    sc.columns.push_back({o.position_cm, o.radius_cm, 60.0, dark, dark, false});
  add_robots(sc, f, r, p, d);
  if (r.ball) add_ball(sc, f, r, p, d);
  add_off_carpet(sc, room, p, r.people, d, [&](const Eigen::Vector2d& q) {
    cv::Vec3f shirt;
    for (int ch = 2; ch >= 0; --ch) shirt[ch] = static_cast<float>(uni(20, 230));  // red first
    return Column{q, 22.0, uni(160, 185), cv::Vec3f(60, 40, 30), shirt, false};
  });
  add_off_carpet(sc, room, p, r.furniture, d, [&](const Eigen::Vector2d& q) {
    const bool bright = d.u01(d.rng) < 0.5;
    const cv::Vec3f c = bright ? cv::Vec3f(210, 212, 215) : cv::Vec3f(40, 52, 70);
    return Column{q, uni(30, 55), uni(70, 120), c, c, true};
  });
  const std::size_t nlines = f.segments.size() + f.arcs.size() + f.discs.size();
  for (std::size_t i = 0; i < nlines; ++i)
    sc.line_width_cm.push_back(f.line_width_cm * (1.0 + r.line_width_spread * uni(-1.0, 1.0)));
  return sc;
}

// --- renderer
// -------------------------------------------------------------------------------------

RealisticRenderer::RealisticRenderer(FieldGeometry field, TrueOptics optics)
    : field_(std::move(field)), optics_(std::move(optics)) {
  const TrueOptics& o = optics_;
  check_optics(o);
  const double body_px = o.radius_px_at_ground(o.body_radius_cm);
  rays_.resize(static_cast<std::size_t>(o.width_px) * static_cast<std::size_t>(o.height_px));
  for (int v = 0; v < o.height_px; ++v) {
    for (int u = 0; u < o.width_px; ++u) {
      PixelRay& pr = rays_[static_cast<std::size_t>(v) * static_cast<std::size_t>(o.width_px) +
                           static_cast<std::size_t>(u)];
      pr = {1.0f, 0.0f, 0.0f, 1.0f, 0.0f, Kind::kScene};
      const Eigen::Vector2d px(u, v), rel = px - o.centre_px;
      const double r = rel.norm();
      pr.radius_frac = static_cast<float>(r / o.mirror_radius_px);
      if (r > o.mirror_radius_px + o.ring_px) {
        pr.kind = Kind::kHousing;
        continue;
      }
      if (r > o.mirror_radius_px) {
        pr.kind = Kind::kRing;
        continue;
      }
      bool rod = false;
      for (const auto& rd : o.rods) {
        const Eigen::Vector2d dir(std::cos(deg_to_rad(rd.image_angle_deg)),
                                  -std::sin(deg_to_rad(rd.image_angle_deg)));
        const double along = rel.dot(dir), across = std::abs(dir.x() * rel.y() - dir.y() * rel.x());
        rod = rod || (along > 0.6 * body_px && across <= rd.width_px / 2.0);
      }
      if (rod) {
        pr.kind = Kind::kRod;
        continue;
      }
      const Eigen::Vector3d d = o.ray_of_pixel(px);
      const double n = std::hypot(d.x(), d.y());
      if (n < 1e-9) {
        pr.kind = Kind::kBody;
        continue;
      }
      pr.dx = static_cast<float>(d.x() / n);
      pr.dy = static_cast<float>(d.y() / n);
      pr.cot = static_cast<float>(d.z() / n);
      if (pr.cot > 0.0f && o.viewpoint_height_cm / pr.cot < o.body_radius_cm) {
        pr.kind = Kind::kBody;
        continue;
      }
      // Floor footprint of one pixel, radially (where lines thin out).
      const Eigen::Vector2d e = r > 1e-9 ? Eigen::Vector2d(rel / r) : Eigen::Vector2d(1.0, 0.0);
      auto floor_at = [&](const Eigen::Vector2d& q) {
        const Eigen::Vector3d dd = o.ray_of_pixel(q);
        return dd.z() > 1e-9 ? o.viewpoint_height_cm * std::hypot(dd.x(), dd.y()) / dd.z() : 1e6;
      };
      pr.footprint_cm = static_cast<float>(
          std::clamp(std::abs(floor_at(px + 0.5 * e) - floor_at(px - 0.5 * e)), 0.2, 1e3));
    }
  }
}

namespace {

// Ceiling lights: the floor is brighter under them (+-light_unevenness).
struct CeilingLights {
  std::vector<Eigen::Vector2d> at;
  double unevenness = 0.0;
  [[nodiscard]] float operator()(const Eigen::Vector2d& q) const {
    double g = 0.0;
    for (const auto& l : at)
      g = std::max(g, std::exp(-(q - l).squaredNorm() / (2.0 * 280.0 * 280.0)));
    return static_cast<float>(1.0 - unevenness + 2.0 * unevenness * g);
  }
};

CeilingLights ceiling_lights(const FieldGeometry& f, const RenderOptions& opt) {
  std::mt19937_64 rng(opt.seed * 0x9E3779B97F4A7C15ull + 5);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  CeilingLights lights;
  lights.unevenness = opt.realism.light_unevenness;
  for (int k = 0; k < 3; ++k) {
    const double y = u01(rng) * f.total_y_cm();  // y first: gcc's order (SceneDraws' comment)
    lights.at.emplace_back(u01(rng) * f.total_x_cm(), y);
  }
  return lights;
}

// The nearest thing a scene ray from the viewpoint (height h, at p, horizontal direction dir,
// falling cot cm per cm) meets: the floor, a wall or goal panel, a column's side or its top.
Hit nearest_hit(const Scene& sc, const Eigen::Vector2d& p, const Eigen::Vector2d& dir, double cot,
                double h) {
  Hit hit;
  if (cot > 1e-9) hit = {Hit::kFloor, h / cot, -1, 0.0, 0.0};
  for (std::size_t i = 0; i < sc.panels.size(); ++i) {
    const Panel& pn = sc.panels[i];
    const Eigen::Vector2d e = pn.b_cm - pn.a_cm, w = pn.a_cm - p;
    const double den = dir.x() * e.y() - dir.y() * e.x();
    if (std::abs(den) < 1e-12) continue;
    const double t = (w.x() * e.y() - w.y() * e.x()) / den;
    const double s = (w.x() * dir.y() - w.y() * dir.x()) / den;
    if (t <= 0.0 || t >= hit.t || s < 0.0 || s > 1.0) continue;
    const double z = h - t * cot;
    if (z < 0.0 || z > pn.height_cm) continue;
    hit = {Hit::kPanel, t, static_cast<int>(i), s * e.norm(), z};
  }
  for (std::size_t i = 0; i < sc.columns.size(); ++i) {
    const Column& c = sc.columns[i];
    const Eigen::Vector2d fvec = c.position_cm - p;
    const double along = fvec.dot(dir);
    const double perp2 = fvec.squaredNorm() - along * along;
    const double r2 = c.radius_cm * c.radius_cm;
    if (perp2 > r2 || along + c.radius_cm <= 0.0) continue;
    const double half = std::sqrt(r2 - perp2);
    const double t_near = std::max(0.0, along - half), t_far = along + half;
    if (t_near >= hit.t) continue;
    const double z_near = h - t_near * cot;
    if (z_near >= 0.0 && z_near <= c.height_cm) {
      hit = {Hit::kColumnSide, t_near, static_cast<int>(i), std::atan2(fvec.y(), fvec.x()), z_near};
    } else if (z_near > c.height_cm && cot > 1e-9) {
      const double t_top = (h - c.height_cm) / cot;
      if (t_top >= t_near && t_top <= t_far && t_top < hit.t)
        hit = {Hit::kColumnTop, t_top, static_cast<int>(i), 0.0, c.height_cm};
    }
  }
  return hit;
}

// What one frame's scene rays are shaded with: the same for every pixel.
struct SceneShading {
  const FieldGeometry& field;
  const Scene& sc;
  const SceneLook& lk;
  Eigen::Vector2d p;
  GoalColour at_max;
  std::uint64_t tex_seed;
  CeilingLights light;
};

// The floor at q: a goal box's paint, the carpet (lines, texture) or the floor beyond, lit.
cv::Vec3f floor_colour(const SceneShading& s, const Eigen::Vector2d& q, float footprint_cm) {
  cv::Vec3f colour;
  bool x_max = false;
  if (s.lk.goals && in_goal_box(s.field, q, x_max)) {
    colour = goal_paint(s.lk, x_max ? s.at_max : other(s.at_max)) * 0.85f;
  } else if (on_look_carpet(s.field, s.lk, q)) {
    colour = carpet_colour(s.field, s.sc, s.lk, q, footprint_cm, s.tex_seed);
  } else {
    colour =
        s.lk.floor_beyond *
        (0.8f + 0.4f * static_cast<float>(cell_hash(std::lround(q.x() / 20.0),
                                                    std::lround(q.y() / 20.0), s.tex_seed + 1)));
  }
  colour *= s.light(q);
  return colour;
}

// The colour of what a scene ray hits (the ceiling when nothing).
cv::Vec3f hit_colour(const SceneShading& s, const Hit& hit, const Eigen::Vector2d& dir,
                     float footprint_cm) {
  switch (hit.type) {
    case Hit::kNone:
      return s.lk.ceiling;
    case Hit::kFloor:
      return floor_colour(s, s.p + hit.t * dir, footprint_cm);
    case Hit::kPanel: {
      const Panel& pn = s.sc.panels[static_cast<std::size_t>(hit.index)];
      return pn.colour * (pn.textured
                              ? block_factor(hit.s, hit.z, 45.0, 35.0,
                                             s.tex_seed + 3 + static_cast<std::uint64_t>(hit.index))
                              : 1.0f);
    }
    case Hit::kColumnSide: {
      const Column& c = s.sc.columns[static_cast<std::size_t>(hit.index)];
      cv::Vec3f colour = hit.z > 0.5 * c.height_cm ? c.top_colour : c.colour;
      if (c.textured)
        colour *= block_factor(hit.s * 50.0, hit.z, 30.0, 25.0,
                               s.tex_seed + 101 + static_cast<std::uint64_t>(hit.index));
      return colour;
    }
    case Hit::kColumnTop:
      return s.sc.columns[static_cast<std::size_t>(hit.index)].top_colour * 1.1f;
  }
  return cv::Vec3f();
}

// Vignetting and the options' linear brightness gradient across the image.
struct PixelGain {
  double vignetting, strength, gd, half_diag;
  Eigen::Vector2d centre;
  [[nodiscard]] float operator()(int u, int v, float radius_frac) const {
    float gain = static_cast<float>(1.0 - vignetting * std::min(1.0f, radius_frac) *
                                              std::min(1.0f, radius_frac));
    if (strength != 0.0) {
      const double along =
          ((u - centre.x()) * std::cos(gd) + (v - centre.y()) * std::sin(gd)) / half_diag;
      gain *= static_cast<float>(1.0 + strength * along);
    }
    return gain;
  }
};

// Lateral colour: red and blue imaged at slightly different magnifications about the centre.
void lateral_colour(cv::Mat3f& img, const TrueOptics& o, double chromatic_px_at_rim) {
  std::vector<cv::Mat> ch;
  cv::split(img, ch);
  const double k = chromatic_px_at_rim / o.mirror_radius_px;
  for (const auto& [index, sign] : {std::pair{0, 1.0}, std::pair{2, -1.0}}) {
    cv::Mat1f mx(img.size()), my(img.size());
    for (int v = 0; v < img.rows; ++v)
      for (int u = 0; u < img.cols; ++u) {
        mx(v, u) = static_cast<float>(o.centre_px.x() + (u - o.centre_px.x()) * (1.0 - sign * k));
        my(v, u) = static_cast<float>(o.centre_px.y() + (v - o.centre_px.y()) * (1.0 - sign * k));
      }
    cv::Mat out;
    cv::remap(ch[static_cast<std::size_t>(index)], out, mx, my, cv::INTER_LINEAR,
              cv::BORDER_REPLICATE);
    ch[static_cast<std::size_t>(index)] = out;
  }
  cv::merge(ch, img);
}

// The camera's own degradations after the optics: blur, sensor noise, 8 bits, JPEG.
cv::Mat camera_output(cv::Mat3f& img, const RenderOptions& opt) {
  if (opt.blur) cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  if (opt.noise_sigma > 0.0) {
    cv::Mat3f noise(img.size());
    cv::RNG nrng(opt.seed);
    nrng.fill(noise, cv::RNG::NORMAL, cv::Scalar::all(0.0), cv::Scalar::all(opt.noise_sigma));
    img += noise;
  }
  cv::Mat out;
  img.convertTo(out, CV_8UC3);
  if (opt.realism.jpeg_quality > 0) {
    std::vector<std::uint8_t> buf;
    cv::imencode(".jpg", out, buf, {cv::IMWRITE_JPEG_QUALITY, opt.realism.jpeg_quality});
    out = cv::imdecode(buf, cv::IMREAD_COLOR);
  }
  return out;
}

}  // namespace

cv::Mat RealisticRenderer::render(const Pose2& pose, const RenderOptions& opt) const {
  return render(pose, opt, realistic_scene(field_, pose, opt));
}

cv::Mat RealisticRenderer::render(const Pose2& pose, const RenderOptions& opt,
                                  const Scene& sc) const {
  if (!opt.realism.enabled)
    throw std::invalid_argument(
        "RealisticRenderer: options.realism.enabled is not set (use realistic(seed))");
  const TrueOptics& o = optics_;
  const RealismOptions& rz = opt.realism;
  const SceneLook& lk = rz.look;
  const bool cast = lk.colour_cast != cv::Vec3f(1.0f, 1.0f, 1.0f);
  const double cy = std::cos(deg_to_rad(pose.yaw_deg)), sy = std::sin(deg_to_rad(pose.yaw_deg));
  const SceneShading shading{field_,
                             sc,
                             lk,
                             Eigen::Vector2d(pose.x_cm, pose.y_cm),
                             colour_at_x_max(field_, rz),
                             opt.seed * 31 + 7,
                             ceiling_lights(field_, opt)};
  const PixelGain gain_at{rz.vignetting, opt.gradient_strength,
                          deg_to_rad(opt.gradient_direction_deg),
                          0.5 * std::hypot(o.width_px, o.height_px), o.centre_px};

  cv::Mat3f img(o.height_px, o.width_px);
  for (int v = 0; v < o.height_px; ++v) {
    auto* row = img.ptr<cv::Vec3f>(v);
    const PixelRay* prs =
        rays_.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(o.width_px);
    for (int u = 0; u < o.width_px; ++u) {
      const PixelRay& pr = prs[u];
      cv::Vec3f colour;
      switch (pr.kind) {
        case Kind::kHousing:
          colour = lk.housing;
          break;
        case Kind::kRing:
          colour = lk.ring;
          break;
        case Kind::kRod:
          colour = lk.rod;
          break;
        case Kind::kBody:
          colour = pr.radius_frac * o.mirror_radius_px <
                           o.lens_fraction * o.radius_px_at_ground(o.body_radius_cm)
                       ? lk.lens
                       : lk.body;
          break;
        case Kind::kScene: {
          const Eigen::Vector2d dir(cy * pr.dx - sy * pr.dy, sy * pr.dx + cy * pr.dy);
          const Hit hit = nearest_hit(sc, shading.p, dir, pr.cot, o.viewpoint_height_cm);
          colour = hit_colour(shading, hit, dir, pr.footprint_cm);
          break;
        }
      }
      const float gain = gain_at(u, v, pr.radius_frac);
      row[u] = cast ? cv::Vec3f(colour.mul(lk.colour_cast)) * gain : colour * gain;
    }
  }
  if (rz.chromatic_px_at_rim != 0.0) lateral_colour(img, o, rz.chromatic_px_at_rim);
  return camera_output(img, opt);
}

}  // namespace omniloc::sim
