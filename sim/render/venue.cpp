// The venue sampler (venue.hpp): one seed, one camera, robot and venue for the realistic renderer.
#include "omniloc_sim/venue.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/detail/config_reader.hpp"

namespace omniloc::sim {

namespace {

// The sampler's ranges (venue.hpp, sim/README.md).
constexpr int kMinWidthPx = 400, kMaxWidthPx = 1280, kMinHeightPx = 400, kMaxHeightPx = 1024;
constexpr double kMaxCentreOffsetFraction = 0.10;  // of the image's width and height
constexpr double kMaxTiltDeg = 3.0;
constexpr double kMinRimThetaDeg = 80.0, kMaxRimThetaDeg = 105.0;  // the rim's ray from the axis
constexpr double kMinBodyFraction = 0.05, kMaxBodyFraction = 0.35;
constexpr int kMaxRods = 4;
constexpr double kMinRodPx = 2.0, kMaxRodPx = 15.0;
constexpr double kMinLineCm = 5.0, kMaxLineCm = 12.5;

// The venue's one random stream: every draw in a fixed order, so a seed is a venue. Two draws are
// never arguments of one call: C++ leaves their order open (gcc and clang differ), and a seed named
// two venues. Draws that were once arguments are made in the order gcc took, the right-most first,
// so each seed still names the venue it was tested on.
struct Draw {
  std::mt19937_64 rng;
  double uni(double a, double b) {
    return a + (b - a) * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(rng); }
  bool chance(double p) { return uni(0.0, 1.0) < p; }
};

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

double round5(double v) {
  return 5.0 * std::round(v / 5.0);
}

cv::Vec3f bgr_of_hsv(double hue_deg, double s, double v) {
  cv::Mat3f px(
      1, 1, cv::Vec3f(static_cast<float>(hue_deg), static_cast<float>(s), static_cast<float>(v)));
  cv::Mat3f out;
  cv::cvtColor(px, out, cv::COLOR_HSV2BGR);  // float HSV: hue in degrees, s and v in 0..1
  return out(0, 0) * 255.0f;
}

// A colour drawn in hue, saturation and value ranges: the value first, then saturation, then hue
// (Draw).
cv::Vec3f draw_hsv(Draw& d, std::pair<double, double> hue_deg, std::pair<double, double> s,
                   std::pair<double, double> v) {
  const double value = d.uni(v.first, v.second);
  const double sat = d.uni(s.first, s.second);
  return bgr_of_hsv(d.uni(hue_deg.first, hue_deg.second), sat, value);
}

void sample_image_size(Draw& d, TrueOptics& o) {
  // The common sensor sizes (the range's corners among them) or any width at a common aspect.
  static constexpr std::array<std::pair<int, int>, 7> kNamed{
      {{400, 400}, {640, 480}, {1280, 1024}, {1280, 720}, {1024, 768}, {800, 600}, {480, 480}}};
  static constexpr std::array<double, 5> kAspect{1.0, 1.25, 4.0 / 3.0, 1.6, 16.0 / 9.0};
  if (d.chance(0.35)) {
    const auto& [w, h] = kNamed[static_cast<std::size_t>(d.integer(0, kNamed.size() - 1))];
    o.width_px = w;
    o.height_px = h;
    return;
  }
  const double aspect = kAspect[static_cast<std::size_t>(d.integer(0, kAspect.size() - 1))];
  o.width_px = 2 * static_cast<int>(std::lround(d.uni(kMinWidthPx, kMaxWidthPx) / 2.0));
  o.height_px = std::clamp(2 * static_cast<int>(std::lround(o.width_px / aspect / 2.0)),
                           kMinHeightPx, kMaxHeightPx);
}

// The profile's parameters from the ray angle at the rim, so that every profile shows the floor
// out to (or past) the horizon within the mirror.
void sample_profile(Draw& d, TrueOptics& o) {
  o.profile = static_cast<MirrorProfile>(d.integer(0, 3));
  const double theta_rim = deg_to_rad(d.uni(kMinRimThetaDeg, kMaxRimThetaDeg));
  const double rim = o.mirror_radius_px;
  switch (o.profile) {
    case MirrorProfile::kHyperbolic:
      // Away from the hyperbola's asymptote (cos theta = -xi), where the walls would fill the
      // image.
      o.xi = d.uni(std::max(0.5, 0.35 - std::cos(theta_rim)), 0.95);
      o.focal_px = rim * (std::cos(theta_rim) + o.xi) / std::sin(theta_rim);
      break;
    case MirrorProfile::kTangent:
      // tan theta = (a / h) tan(b r): a / h sets where the floor is compressed, theta_rim fixes b.
      o.tan_a_cm = o.viewpoint_height_cm * d.uni(0.6, 1.6);
      o.tan_b_per_px = std::atan2(o.viewpoint_height_cm / o.tan_a_cm * std::sin(theta_rim),
                                  std::cos(theta_rim)) /
                       rim;
      break;
    case MirrorProfile::kSpherical:
      o.sphere_radius_px = rim / std::sin(theta_rim / 2.0);
      break;
    case MirrorProfile::kConical:
      o.cone_tip_deg = d.uni(10.0, 35.0);
      o.cone_tip_px = rim * d.uni(0.04, 0.15);
      o.cone_deg_per_px =
          (rad_to_deg(theta_rim) - o.cone_tip_deg * std::tanh(rim / o.cone_tip_px)) / rim;
      break;
  }
}

void sample_camera(Draw& d, TrueOptics& o) {
  sample_image_size(d, o);
  const double half_min = 0.5 * std::min(o.width_px, o.height_px);
  o.centre_px = {0.5 * o.width_px + d.uni(-1.0, 1.0) * kMaxCentreOffsetFraction * o.width_px,
                 0.5 * o.height_px + d.uni(-1.0, 1.0) * kMaxCentreOffsetFraction * o.height_px};
  o.mirror_radius_px = half_min * d.uni(0.78, 1.05);  // past the image's edge at times
  o.ring_px = o.mirror_radius_px * d.uni(0.02, 0.07);
  o.viewpoint_height_cm = d.uni(35.0, 90.0);
  o.tilt_deg = d.uni(0.0, kMaxTiltDeg);
  o.tilt_towards_deg = d.uni(0.0, 360.0);
  o.yaw_offset_deg = d.uni(-180.0, 180.0);
  o.mirrored = d.chance(0.5);
  sample_profile(d, o);
}

// The robot seen in its own mirror: the body (a fraction of the mirror's radius), rods, the lens.
double sample_robot(Draw& d, TrueOptics& o) {
  const double fraction = d.uni(kMinBodyFraction, kMaxBodyFraction);
  o.body_radius_cm = o.ground_cm_at_radius(fraction * o.mirror_radius_px);
  if (!std::isfinite(o.body_radius_cm))
    throw std::logic_error("sample_robot: the body reaches past the horizon");
  o.lens_fraction = d.uni(0.2, 0.6);
  o.rods.clear();
  const int rods = d.integer(0, kMaxRods);
  const double start_deg = d.uni(0.0, 360.0);
  for (int k = 0; k < rods; ++k)
    o.rods.push_back({std::fmod(start_deg + 360.0 * k / rods + d.uni(-15.0, 15.0) + 360.0, 360.0),
                      d.uni(kMinRodPx, kMaxRodPx)});
  return fraction;
}

}  // namespace

const char* venue_field_name(VenueField f) {
  switch (f) {
    case VenueField::kFira:
      return "fira-robosot";
    case VenueField::kMsl:
      return "robocup-msl";
    case VenueField::kMsl18x12:
      return "robocup-msl-18x12";
  }
  return "unknown";
}

FieldSpec msl_18x12_spec() {
  FieldSpec s = load_field("robocup-msl").spec;
  const double sx = 1800.0 / s.field_length_cm, sy = 1200.0 / s.field_width_cm,
               sr = std::min(sx, sy);
  s.name = venue_field_name(VenueField::kMsl18x12);
  s.field_length_cm = 1800.0;
  s.field_width_cm = 1200.0;
  s.centre_circle_radius_cm = round5(s.centre_circle_radius_cm * sr);
  s.goal_area = {round5(s.goal_area.depth_cm * sx), round5(s.goal_area.width_cm * sy)};
  s.penalty_area = {round5(s.penalty_area.depth_cm * sx), round5(s.penalty_area.width_cm * sy)};
  s.penalty_arc = {round5(s.penalty_arc.radius_cm * sr),
                   round5(s.penalty_arc.centre_from_goal_line_cm * sx)};
  s.corner_arc_radius_cm = round5(s.corner_arc_radius_cm * sr);
  for (auto& m : s.marks_from_centre_cm) m = {round5(m.x() * sx), round5(m.y() * sy)};
  s.validate(config::Origin(s.name));
  return s;
}

std::uint64_t venue_seed(std::uint64_t seed, std::uint64_t index) {
  return splitmix64(splitmix64(seed) ^ (index + 1));
}

namespace {

cv::Vec3f sample_carpet(Draw& d) {
  // Green (120 deg) through teal (165) to blue-green (185); a fifth are dark green.
  if (d.chance(0.2)) return draw_hsv(d, {105.0, 140.0}, {0.5, 0.8}, {0.22, 0.35});
  return draw_hsv(d, {110.0, 185.0}, {0.45, 0.85}, {0.35, 0.65});
}

cv::Vec3f sample_line_paint(Draw& d) {
  const float base = static_cast<float>(d.uni(225.0, 250.0)),
              tint = static_cast<float>(d.uni(5.0, 25.0));
  // Bluish white: blue above red; yellowish white: red and green above blue (BGR).
  return d.chance(0.5) ? cv::Vec3f(base, base - 0.4f * tint, base - tint)
                       : cv::Vec3f(base - tint, base - 0.2f * tint, base);
}

std::vector<cv::Vec3f> sample_walls(Draw& d) {
  const int room = d.integer(0, 2);  // 0 bright (white walls, windows), 1 dark, 2 mixed
  std::vector<cv::Vec3f> walls;
  for (int k = 0; k < 4; ++k) {
    const double v = room == 0   ? d.uni(195.0, 250.0)
                     : room == 1 ? d.uni(25.0, 80.0)
                                 : d.uni(40.0, 230.0);
    const float tint = static_cast<float>(d.uni(-12.0, 12.0));
    walls.emplace_back(static_cast<float>(v) + tint, static_cast<float>(v),
                       static_cast<float>(v) - tint);
  }
  return walls;
}

void sample_look(Draw& d, SceneLook& lk) {
  lk.carpet = sample_carpet(d);
  const bool textured = d.chance(0.5);
  lk.carpet_grain = textured ? d.uni(0.08, 0.25) : d.uni(0.02, 0.08);
  lk.carpet_patch_contrast = textured ? d.uni(0.03, 0.12) : 0.0;
  lk.line = sample_line_paint(d);
  lk.line_wear = d.chance(0.4) ? d.uni(0.1, 0.5) : 0.0;
  lk.walls = sample_walls(d);
  // Beyond the carpet: a dark floor (as today), or a light one (concrete, wood, lino).
  lk.floor_beyond = d.chance(0.3) ? draw_hsv(d, {20.0, 45.0}, {0.0, 0.4}, {0.55, 0.85})
                                  : draw_hsv(d, {0.0, 360.0}, {0.0, 0.2}, {0.08, 0.2});
  lk.ceiling = cv::Vec3f::all(static_cast<float>(d.uni(120.0, 240.0)));
  lk.housing = cv::Vec3f::all(static_cast<float>(d.uni(20.0, 90.0)));
  lk.body = cv::Vec3f::all(static_cast<float>(d.uni(30.0, 110.0)));
  lk.rod = cv::Vec3f::all(static_cast<float>(d.uni(15.0, 50.0)));
  lk.colour_cast = cv::Vec3f(1.0f, 1.0f, 1.0f);
  if (d.chance(0.6)) {
    for (int ch = 2; ch >= 0; --ch)  // red first (Draw)
      lk.colour_cast[ch] = static_cast<float>(ch == 1 ? d.uni(0.9, 1.1) : d.uni(0.85, 1.15));
  }
  lk.goals = d.chance(0.75);
}

void sample_light_and_sensor(Draw& d, RenderOptions& r) {
  RealismOptions& z = r.realism;
  z.light_unevenness = d.uni(0.0, 0.4);
  z.vignetting = d.uni(0.0, 0.5);
  z.chromatic_px_at_rim = d.uni(0.0, 1.5);
  z.jpeg_quality = d.chance(0.2) ? 0 : d.integer(40, 95);
  z.line_width_spread = d.uni(0.0, 0.3);
  z.goal_colour_at_x_max = d.chance(0.5) ? GoalColour::kBlue : GoalColour::kYellow;
  z.robots = d.integer(0, 5);
  z.ball = d.chance(0.7);
  z.people = d.integer(0, 10);
  z.furniture = d.integer(0, 8);
  r.noise_sigma = d.uni(1.0, 8.0);
  r.gradient_strength = d.uni(0.0, 0.2);
  r.gradient_direction_deg = d.uni(0.0, 360.0);
}

// The field: a shipped file or the 18 x 12 layout, its lines repainted at 5..12.5 cm in three
// venues of four; a lab field's carpet ends short on some sides (into the playing area at most a
// quarter of its half-length, so that the centre stays on the carpet).
void sample_field(Draw& d, Venue& v) {
  v.field_kind = static_cast<VenueField>(d.integer(0, 2));
  v.field_name = venue_field_name(v.field_kind);
  FieldSpec spec =
      v.field_kind == VenueField::kMsl18x12 ? msl_18x12_spec() : load_field(v.field_name).spec;
  v.field_shipped = v.field_kind != VenueField::kMsl18x12;
  if (d.chance(0.75)) {
    spec.line_width_cm = 0.5 * std::round(2.0 * d.uni(kMinLineCm, kMaxLineCm));  // to 5 mm
    v.field_shipped =
        v.field_shipped && spec.line_width_cm == load_field(v.field_name).spec.line_width_cm;
  }
  spec.validate(config::Origin(v.field_name));
  v.field = build_field(spec, v.field_shipped ? v.field_name : "venue " + std::to_string(v.seed));
  v.lab = d.chance(0.3);
  double* inset = v.render.realism.look.carpet_inset_cm;
  const double half[4] = {spec.field_length_cm / 2, spec.field_length_cm / 2,
                          spec.field_width_cm / 2, spec.field_width_cm / 2};
  for (int side = 0; side < 4; ++side)
    inset[side] = v.lab && d.chance(0.6)
                      ? d.uni(0.2 * spec.border_cm, spec.border_cm + 0.25 * half[side])
                      : 0.0;
}

}  // namespace

Venue sample_venue(std::uint64_t seed) {
  Draw d{std::mt19937_64(splitmix64(seed))};
  Venue v;
  v.seed = seed;
  v.render = realistic(splitmix64(seed ^ 0x5EED));
  sample_field(d, v);
  sample_camera(d, v.optics);
  v.body_fraction = sample_robot(d, v.optics);
  sample_look(d, v.render.realism.look);
  sample_light_and_sensor(d, v.render);
  return v;
}

namespace {

// The known spots of a field that lie well on the venue's carpet: the centre spot, and the
// penalty marks (the marks on the long axis, as MSL has; FIRA's four marks are free-ball marks).
std::vector<KnownSpot> known_spots(const Venue& v) {
  const Eigen::Vector2d c = v.field.centre_cm();
  std::vector<KnownSpot> spots{{"centre spot", c}};
  for (const auto& m : v.field.spec.marks_from_centre_cm)
    if (m.y() == 0.0 && m.x() != 0.0)
      spots.push_back({m.x() < 0 ? "penalty mark x min" : "penalty mark x max", c + m});
  const SceneLook& lk = v.render.realism.look;
  std::erase_if(spots, [&](const KnownSpot& s) {
    for (const Eigen::Vector2d& off : {Eigen::Vector2d(60, 0), Eigen::Vector2d(-60, 0),
                                       Eigen::Vector2d(0, 60), Eigen::Vector2d(0, -60)})
      if (!on_look_carpet(v.field, lk, s.position_cm + off)) return true;
    return false;
  });
  return spots;
}

config::Json pose_json(const Pose2& p) {
  return {{"x_cm", p.x_cm}, {"y_cm", p.y_cm}, {"yaw_deg", p.yaw_deg}};
}
config::Json bgr_json(const cv::Vec3f& c) {
  return config::Json::array({c[0], c[1], c[2]});
}

// The parameters the profile uses (the others keep their defaults and mean nothing here).
config::Json profile_json(const TrueOptics& o) {
  switch (o.profile) {
    case MirrorProfile::kHyperbolic:
      return {{"focal_px", o.focal_px}, {"xi", o.xi}};
    case MirrorProfile::kTangent:
      return {{"tan_a_cm", o.tan_a_cm}, {"tan_b_per_px", o.tan_b_per_px}};
    case MirrorProfile::kSpherical:
      return {{"sphere_radius_px", o.sphere_radius_px}};
    case MirrorProfile::kConical:
      return {{"cone_tip_deg", o.cone_tip_deg},
              {"cone_tip_px", o.cone_tip_px},
              {"cone_deg_per_px", o.cone_deg_per_px}};
  }
  return config::Json::object();
}

config::Json optics_json(const TrueOptics& o) {
  config::Json rods = config::Json::array();
  for (const auto& r : o.rods)
    rods.push_back({{"image_angle_deg", r.image_angle_deg}, {"width_px", r.width_px}});
  return {{"profile", mirror_profile_name(o.profile)},
          {"profile_parameters", profile_json(o)},
          {"rim_theta_deg", rad_to_deg(o.theta_rad_at_radius(o.mirror_radius_px))},
          {"width_px", o.width_px},
          {"height_px", o.height_px},
          {"centre_px", {o.centre_px.x(), o.centre_px.y()}},
          {"viewpoint_height_cm", o.viewpoint_height_cm},
          {"tilt_deg", o.tilt_deg},
          {"tilt_towards_deg", o.tilt_towards_deg},
          {"yaw_offset_deg", o.yaw_offset_deg},
          {"mirrored", o.mirrored},
          {"mirror_radius_px", o.mirror_radius_px},
          {"ring_px", o.ring_px},
          {"body_radius_cm", o.body_radius_cm},
          {"lens_fraction", o.lens_fraction},
          {"rods", rods}};
}

config::Json look_json(const RenderOptions& r) {
  const SceneLook& lk = r.realism.look;
  const RealismOptions& z = r.realism;
  config::Json walls = config::Json::array();
  for (const auto& w : lk.walls) walls.push_back(bgr_json(w));
  return {{"colours_bgr",
           {{"carpet", bgr_json(lk.carpet)},
            {"line", bgr_json(lk.line)},
            {"floor_beyond", bgr_json(lk.floor_beyond)},
            {"ceiling", bgr_json(lk.ceiling)},
            {"body", bgr_json(lk.body)},
            {"rod", bgr_json(lk.rod)},
            {"housing", bgr_json(lk.housing)},
            {"walls", walls}}},
          {"carpet_grain", lk.carpet_grain},
          {"carpet_patch_contrast", lk.carpet_patch_contrast},
          {"line_wear", lk.line_wear},
          {"colour_cast_bgr", bgr_json(lk.colour_cast)},
          {"goals", lk.goals},
          {"goal_colour_at_x_max", goal_colour_name(z.goal_colour_at_x_max)},
          {"carpet_inset_cm",
           {lk.carpet_inset_cm[0], lk.carpet_inset_cm[1], lk.carpet_inset_cm[2],
            lk.carpet_inset_cm[3]}},
          {"line_width_spread", z.line_width_spread},
          {"light_unevenness", z.light_unevenness},
          {"vignetting", z.vignetting},
          {"chromatic_px_at_rim", z.chromatic_px_at_rim},
          {"jpeg_quality", z.jpeg_quality},
          {"noise_sigma", r.noise_sigma},
          {"gradient_strength", r.gradient_strength},
          {"gradient_direction_deg", r.gradient_direction_deg},
          {"robots", z.robots},
          {"ball", z.ball},
          {"people", z.people},
          {"furniture", z.furniture},
          {"render_seed", r.seed}};
}

config::Json nominal_json(const TrueOptics& o) {
  const CameraModel cam = nominal_camera(o);
  config::Json j = {{"camera", config::write_keys(cam, camera_keys())}, {"valid", true}};
  try {
    cam.validate(config::Origin("nominal camera"));
  } catch (const std::exception& e) {
    // A camera the model cannot say (none is known today): recorded, not hidden.
    j["valid"] = false;
    j["problem"] = e.what();
  }
  return j;
}

}  // namespace

VenueShots venue_poses(const Venue& v) {
  Draw d{std::mt19937_64(splitmix64(v.seed ^ 0x9053ull))};
  VenueShots s;
  const std::vector<KnownSpot> spots = known_spots(v);
  if (spots.empty())
    throw std::logic_error("venue " + std::to_string(v.seed) + ": no known spot on the carpet");
  s.spot = spots[static_cast<std::size_t>(d.integer(0, static_cast<int>(spots.size()) - 1))];
  s.calib_pose = {s.spot.position_cm.x(), s.spot.position_cm.y(), d.uni(-180.0, 180.0)};
  // Anywhere on the venue's carpet, 40 cm in from its edges.
  const double* in = v.render.realism.look.carpet_inset_cm;
  const double m = 40.0;
  s.frame_pose = {d.uni(in[0] + m, v.field.total_x_cm() - in[1] - m),
                  d.uni(in[2] + m, v.field.total_y_cm() - in[3] - m), d.uni(-180.0, 180.0)};
  return s;
}

VenueShots render_venue(const Venue& v) {
  VenueShots s = venue_poses(v);
  const RealisticRenderer rr(v.field, v.optics);
  s.calib = rr.render(s.calib_pose, v.render);
  RenderOptions second = v.render;
  second.seed = v.render.seed + 1;  // another moment: the people and robots have moved
  s.frame = rr.render(s.frame_pose, second);
  return s;
}

std::string venue_truth_json(const Venue& v, const VenueShots& s, const std::string& field_file) {
  config::Json j;
  j["seed"] = v.seed;
  j["field"] = {{"name", v.field_name},
                {"shipped", v.field_shipped},
                {"file", field_file},
                {"lab", v.lab},
                {"spec", config::write_keys(v.field.spec, field_spec_keys())}};
  j["optics"] = optics_json(v.optics);
  j["robot"] = {{"body_fraction", v.body_fraction},
                {"body_radius_cm", v.optics.body_radius_cm},
                {"rods", v.optics.rods.size()},
                {"lens_fraction", v.optics.lens_fraction}};
  j["nominal_camera"] = nominal_json(v.optics);
  j["known_spot"] = {{"name", s.spot.name},
                     {"position_cm", {s.spot.position_cm.x(), s.spot.position_cm.y()}}};
  j["calib_pose"] = pose_json(s.calib_pose);
  j["frame_pose"] = pose_json(s.frame_pose);
  j["look"] = look_json(v.render);
  return j.dump(2) + "\n";
}

}  // namespace omniloc::sim
