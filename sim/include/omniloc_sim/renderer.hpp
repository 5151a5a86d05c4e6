// Omni-camera renderer: an image of the field from any pose, for tests, benchmarks and the
// simulated robot. Deterministic for a given seed. Two renderers:
//  - OmniRenderer: the idealised frame through the database's own CameraModel (green carpet,
//    white lines, a darker floor beyond the border, the robot's body and mast, other robots as dark
//    blobs, a lighting gradient, sensor noise and blur). Today's default frames, unchanged.
//  - RealisticRenderer (issue 13 item 6): a frame through a TRUE camera (TrueOptics: a hyperbolic
//    mirror, off centre and tilted, its rods) that is not the database's camera, of a 3-D scene:
//    walls, furniture and people beyond the carpet, coloured goal boxes, other robots and the ball
//    with height, lines of varying width with colour fringes, vignetting, uneven light, noise and
//    JPEG. Selected by RenderOptions::realism (the `realistic(seed)` preset).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/matx.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/field.hpp"

namespace omniloc::sim {

/// Another robot on the field: a dark cylinder, tall enough to hide the floor behind it.
struct Obstacle {
  Eigen::Vector2d position_cm;
  double radius_cm = 20.0;
};

/// How a venue looks (RealisticRenderer): paint colours (BGR, 0..255 before lighting) and the
/// carpet, line and room details a venue varies. The defaults are today's realistic frames (chosen
/// to look like tests/data/: a green-teal carpet, bluish-white lines, a black floor beyond the
/// carpet, saturated goal paint), unchanged byte for byte; venue.hpp samples other venues.
struct SceneLook {
  cv::Vec3f carpet{70.0f, 140.0f, 35.0f};
  cv::Vec3f line{245.0f, 232.0f, 216.0f};
  cv::Vec3f floor_beyond{34.0f, 32.0f, 36.0f};   // the floor beyond the carpet (dark or light)
  cv::Vec3f goal_blue{190.0f, 80.0f, 20.0f};     // OpenCV hue ~109
  cv::Vec3f goal_yellow{30.0f, 200.0f, 230.0f};  // OpenCV hue ~26
  cv::Vec3f ball{20.0f, 110.0f, 250.0f};         // orange, hue ~11
  cv::Vec3f robot_dark{26.0f, 25.0f, 30.0f};
  cv::Vec3f body{52.0f, 48.0f, 48.0f};
  cv::Vec3f lens{14.0f, 14.0f, 16.0f};
  cv::Vec3f rod{24.0f, 24.0f, 27.0f};
  cv::Vec3f ring{9.0f, 9.0f, 10.0f};
  cv::Vec3f housing{58.0f, 56.0f, 62.0f};
  cv::Vec3f ceiling{190.0f, 190.0f, 196.0f};
  /// Wall paints the room's four walls are drawn from (bright, middling, dark, bluish by default).
  std::vector<cv::Vec3f> walls{{205, 208, 212}, {140, 132, 122}, {70, 64, 60}, {120, 150, 170}};
  double carpet_grain = 0.08;          // carpet brightness x (1 - grain/2 + grain h), 3 cm cells
  double carpet_patch_contrast = 0.0;  // textured carpet: 40 cm patches x (1 +- this)
  double line_wear = 0.0;              // fraction of each line's length worn (dimmer or gone)
  cv::Vec3f colour_cast{1.0f, 1.0f, 1.0f};  // per-channel gain (B, G, R) on the whole frame
  bool goals = true;                        // coloured goal boxes (and their painted floor)
  /// How far the carpet stops short of the full carpet (playing area + border) on the sides
  /// x = 0, x = max, y = 0, y = max (cm): a lab field shows only part of a field.
  double carpet_inset_cm[4] = {0.0, 0.0, 0.0, 0.0};
};

/// True when q (field frame, cm) is on the carpet as the look cuts it (on_carpet() less the
/// insets).
[[nodiscard]] bool on_look_carpet(const FieldGeometry& field, const SceneLook& look,
                                  const Eigen::Vector2d& q_cm);

/// The realistic frame's extras (RealisticRenderer; OmniRenderer refuses options with enabled set).
/// The defaults are the `realistic()` preset's; every amount 0 turns its effect off.
struct RealismOptions {
  bool enabled = false;
  int robots = 3;  // other robots on the carpet (random, seeded), besides RenderOptions::obstacles
  bool ball = true;   // an orange ball on the carpet
  int people = 6;     // people standing beyond the carpet
  int furniture = 5;  // boxes (tables, cupboards, bright and dark) beyond the carpet
  double wall_height_cm = 250.0;
  double goal_height_cm = 40.0;
  GoalColour goal_colour_at_x_max = GoalColour::kBlue;  // used when the field does not say
  double line_width_spread = 0.25;  // each line's width is line_width_cm x (1 +- this), seeded
  double chromatic_px_at_rim =
      0.9;  // lateral colour: red and blue scaled apart radially by this at the rim
  double vignetting = 0.35;        // brightness x (1 - this (r / mirror radius)^2)
  double light_unevenness = 0.25;  // ceiling lights: floor brightness varies by about +-this
  int jpeg_quality = 70;           // 0: no JPEG round trip
  SceneLook look;
};

struct RenderOptions {
  std::uint64_t seed = 1;
  double noise_sigma = 6.0;        // Gaussian sensor noise per channel (0..255 scale)
  bool blur = true;                // 3 x 3 Gaussian (optics)
  double gradient_strength = 0.2;  // brightness varies by +-this fraction across the image
  double gradient_direction_deg = 30.0;
  std::vector<Obstacle> obstacles;
  RealismOptions realism;  // ignored unless realism.enabled (then only RealisticRenderer renders)
};

/// Options for an ideal image: no noise, blur or gradient.
[[nodiscard]] RenderOptions noise_free();

/// The realistic preset: realism on with its defaults, sensor noise sigma 4, blur, and a mild
/// +-10 % gradient on top of the ceiling lights.
[[nodiscard]] RenderOptions realistic(std::uint64_t seed);

/// Renders omni images (BGR, camera.width_px x camera.height_px). Holds, per pixel, the floor
/// point in the robot frame (or what hides it), computed once from the camera, so that rendering
/// many poses costs only a rotation and a white-line test per pixel.
class OmniRenderer {
 public:
  OmniRenderer(FieldGeometry field, CameraModel camera);
  [[nodiscard]] cv::Mat render(const Pose2& pose, const RenderOptions& options) const;
  [[nodiscard]] const FieldGeometry& field() const { return field_; }
  [[nodiscard]] const CameraModel& camera() const { return camera_; }

 private:
  enum class Kind : std::uint8_t { kFloor, kRim, kBody, kMast };
  struct PixelRay {
    float x_cm, y_cm;  // floor point in the robot frame
    Kind kind;
  };
  FieldGeometry field_;
  WhiteLineIndex lines_;  // built from field_ (declared after it)
  CameraModel camera_;
  std::vector<PixelRay> rays_;  // row-major, one per pixel
};

/// One-off rendering (builds an OmniRenderer each call).
[[nodiscard]] cv::Mat render_omni(const FieldGeometry& field, const CameraModel& camera,
                                  const Pose2& pose, const RenderOptions& options);

/// A thin dark bar across the mirror's view (a support rod), at an image angle (deg, about the
/// optical centre, counter-clockwise from the image's +u axis), from the body to the rim.
struct MirrorRod {
  double image_angle_deg = 0.0;
  double width_px = 4.0;
};

/// The mirror's radial mapping: how the angle theta of a ray from the (downward) mirror axis maps
/// to the image radius r. Every one is central (a single effective viewpoint), so a floor point at
/// ground distance D has tan theta = D / h.
///  - kHyperbolic: the unified model below (xi, focal_px).
///  - kTangent: D(r) = tan_a_cm tan(tan_b_per_px r), the ground-distance model many teams fit
///    (theta = atan2((a / h) sin(b r), cos(b r)), so it continues past the horizon at b r = pi /
///    2).
///  - kSpherical: a spherical mirror seen from far below (orthographic): the normal at image radius
///    r leans asin(r / R) from the axis and the reflected ray 2 asin(r / R), R = sphere_radius_px.
///  - kConical: a cone with a rounded tip: theta = cone_tip_deg tanh(r / cone_tip_px) +
///    cone_deg_per_px r (the tip bends rays quickly, the flank adds a near-constant angle per px).
enum class MirrorProfile : std::uint8_t { kHyperbolic, kTangent, kSpherical, kConical };

/// "hyperbolic", "tangent", "spherical", "conical".
[[nodiscard]] const char* mirror_profile_name(MirrorProfile p);

/// The camera as it really is (the realistic renderer's truth), separate from the CameraModel the
/// database uses. A central catadioptric camera whose mirror follows `profile` (MirrorProfile; the
/// default, and what follows, is the hyperbolic mirror of the unified projection model,
/// Geyer & Daniilidis 2000, Barreto & Araujo 2001): a ray leaving the mirror's effective
/// viewpoint at angle theta from the mirror's (downward) axis appears at image radius
///     r(theta) = focal_px sin(theta) / (cos(theta) + xi),   xi = e / sqrt(e^2 + 4 p^2) in (0, 1)
/// (e: distance between the hyperbola's foci, 4p: its latus rectum; xi -> 1 is a parabolic mirror,
/// xi = 0 a pinhole). A floor point at ground distance D seen from the viewpoint at height h
/// (tan theta = D / h) appears at
///     r(D) = focal_px D / (h + xi sqrt(D^2 + h^2))
/// and back (lifting the pixel onto the unit sphere): with m = r / focal_px,
///     lambda = (xi + sqrt(1 + (1 - xi^2) m^2)) / (1 + m^2),   D(r) = h lambda m / (lambda - xi).
/// The horizon (theta = 90 deg) is at r = focal_px / xi; the rim may lie beyond it (walls and
/// people are then seen above the camera's height). The mirror axis is tilted by tilt_deg towards
/// the image angle tilt_towards_deg (rotation about the horizontal axis perpendicular to it), so
/// the mapping is not radially symmetric; the image centre (where the axis meets the sensor) is
/// centre_px. Image angle = bearing + yaw_offset_deg, u = cx + r cos (cx - r cos when mirrored), v
/// = cy - r sin, as in CameraModel. The other profiles replace r(theta) only (theta_rad_at_radius
/// and back); the tilt, centre, yaw offset and mirroring are the same for all.
struct TrueOptics {
  int width_px = 640;
  int height_px = 480;
  Eigen::Vector2d centre_px{323.6, 236.2};  // a few px off the image centre
  double focal_px = 180.0;
  double xi = 0.8;  // horizon at 225 px, just inside the rim
  double viewpoint_height_cm = 60.0;
  double tilt_deg = 1.5;
  double tilt_towards_deg = 35.0;
  double yaw_offset_deg = 8.0;
  bool mirrored = false;
  double mirror_radius_px = 229.0;  // the mirror's rim: beyond it a dark ring, then the housing
  double ring_px = 12.0;            // width of the dark ring just beyond the mirror's view
  double body_radius_cm = 22.0;     // the robot's own body hides the floor closer than this
  std::vector<MirrorRod> rods{{100.0, 4.0}, {220.0, 4.0}, {340.0, 4.0}};
  double lens_fraction = 0.35;  // the dark lens hole: this fraction of the body's image radius
  MirrorProfile profile = MirrorProfile::kHyperbolic;  // the other profiles ignore focal_px and xi
  double tan_a_cm = 100.0;                             // kTangent
  double tan_b_per_px = 0.006;                         // kTangent: the horizon is at r = pi / (2 b)
  double sphere_radius_px = 300.0;  // kSpherical: the view ends at r = R (theta = 180 deg)
  double cone_tip_deg = 30.0;       // kConical
  double cone_tip_px = 20.0;        // kConical
  double cone_deg_per_px = 0.3;     // kConical

  /// Angle (rad) from the downward axis of the ray at untilted image radius r, and back; the
  /// profile's own mapping (r beyond its domain is clamped to it).
  [[nodiscard]] double theta_rad_at_radius(double radius_px) const;
  [[nodiscard]] double radius_px_at_theta(double theta_rad) const;
  /// The largest ray angle (rad) the mirror maps at all (pi for most; the hyperbola's asymptote).
  [[nodiscard]] double max_theta_rad() const;

  /// Unit direction of the ray seen at pixel px, robot frame (x forward, y left, z DOWN).
  [[nodiscard]] Eigen::Vector3d ray_of_pixel(const Eigen::Vector2d& px) const;
  /// Pixel of a point (robot frame cm, z = height above the floor); nullopt behind the mirror.
  [[nodiscard]] std::optional<Eigen::Vector2d> pixel_of_robot_point(
      const Eigen::Vector3d& p_robot_cm) const;
  /// The untilted radial mapping: r(D) of the formula above, and its inverse (NaN beyond the
  /// horizon).
  [[nodiscard]] double radius_px_at_ground(double ground_cm) const;
  [[nodiscard]] double ground_cm_at_radius(double radius_px) const;
};

/// The CameraModel closest to the optics that the database's model can express: centre, the
/// untilted radial mapping sampled every 4 px up to `max_ground_cm` (or the mirror rim), yaw
/// offset, mirroring, the body radius; the rods are NOT in its mask (a calibration finds them).
[[nodiscard]] CameraModel nominal_camera(const TrueOptics& optics, double max_ground_cm = 600.0);

/// Something of the 3-D scene that stands on the floor: a vertical cylinder (robot, person, ball,
/// furniture) with its colour (BGR) and, for a person, a second colour above half its height.
struct Column {
  Eigen::Vector2d position_cm;
  double radius_cm = 20.0;
  double height_cm = 60.0;
  cv::Vec3f colour{20.0f, 20.0f, 24.0f};
  cv::Vec3f top_colour{20.0f, 20.0f, 24.0f};  // colour of the upper half (and the top face)
  bool textured = false;                      // blocks of brighter and darker (furniture)
};

/// A vertical wall panel standing on the floor between a and b (field frame).
struct Panel {
  Eigen::Vector2d a_cm, b_cm;
  double height_cm = 250.0;
  cv::Vec3f colour{150.0f, 150.0f, 150.0f};
  bool textured = true;  // posters, doors, shelves: blocks of brighter and darker
};

/// The scene a realistic frame shows, built from the field, the pose and the options' seed:
/// the room's walls at varying distances, the two goal boxes, robots, the ball, people and
/// furniture.
struct Scene {
  std::vector<Panel> panels;
  std::vector<Column> columns;
  std::vector<double>
      line_width_cm;  // per line: segments, then arcs, then discs (FieldGeometry order)
  Eigen::Vector2d ball_cm{-1.0, -1.0};
};
[[nodiscard]] Scene realistic_scene(const FieldGeometry& field, const Pose2& pose,
                                    const RenderOptions& options);

/// Renders realistic frames (BGR, optics.width_px x optics.height_px) through the true optics.
/// Holds the per-pixel rays (computed once from the optics).
class RealisticRenderer {
 public:
  RealisticRenderer(FieldGeometry field, TrueOptics optics);
  /// options.realism.enabled must be set (the `realistic(seed)` preset).
  [[nodiscard]] cv::Mat render(const Pose2& pose, const RenderOptions& options) const;
  [[nodiscard]] cv::Mat render(const Pose2& pose, const RenderOptions& options,
                               const Scene& scene) const;
  [[nodiscard]] const FieldGeometry& field() const { return field_; }
  [[nodiscard]] const TrueOptics& optics() const { return optics_; }

 private:
  enum class Kind : std::uint8_t { kScene, kBody, kRod, kRing, kHousing };
  struct PixelRay {
    float dx, dy;        // horizontal unit direction, robot frame
    float cot;           // descent per cm of horizontal travel (> 0: towards the floor)
    float footprint_cm;  // floor cm per pixel here (radially), for anti-aliased lines
    float radius_frac;   // radius / mirror radius (vignetting)
    Kind kind;
  };
  FieldGeometry field_;
  TrueOptics optics_;
  std::vector<PixelRay> rays_;
};

/// `count` robots placed at random (seeded) on the carpet between 60 and 250 cm from `pose`, not
/// overlapping each other.
[[nodiscard]] std::vector<Obstacle> random_obstacles(const FieldGeometry& field, const Pose2& pose,
                                                     int count, std::uint64_t seed);

}  // namespace omniloc::sim
