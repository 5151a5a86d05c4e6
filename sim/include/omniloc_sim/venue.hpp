// A venue sampler for the realistic renderer (issue "[1/4] Vision on cameras it has never seen",
// item 1): from one seed, a camera (image size, mirror profile, centre, tilt, handedness), a robot
// (body, rods, lens) and a venue (field, carpet and line paint, room, light, sensor), so that the
// calibration and the line extraction can be measured on hundreds of venues. Every draw is from
// the seed alone: the same seed gives the same venue, frames and truth, byte for byte.
#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "omniloc/conventions.hpp"
#include "omniloc/field.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc::sim {

/// The field a venue is built on: the two shipped files and the MSL 18 x 12 m layout derived from
/// the MSL file.
enum class VenueField : std::uint8_t { kFira, kMsl, kMsl18x12 };

/// "fira-robosot", "robocup-msl", "robocup-msl-18x12".
[[nodiscard]] const char* venue_field_name(VenueField f);

/// The MSL file's layout at 1800 x 1200 cm: the areas, circles and marks scaled with the field
/// (lengths along x by 18/22, along y by 12/14, circles by the smaller, rounded to 5 cm); line
/// width, border, goal and mark size as in the file.
[[nodiscard]] FieldSpec msl_18x12_spec();

struct Venue {
  std::uint64_t seed = 0;
  VenueField field_kind = VenueField::kFira;
  std::string field_name;     // venue_field_name(field_kind)
  bool field_shipped = true;  // field is exactly common/fields/<field_name>.json
  bool lab = false;  // the carpet stops short on some sides (render.realism.look.carpet_inset_cm)
  FieldGeometry field;         // as painted (its line width may differ from the file's)
  TrueOptics optics;           // the camera and the robot's body, rods and lens as they really are
  double body_fraction = 0.0;  // the body's image radius / the mirror's radius
  RenderOptions render;        // realism on, with the venue's look, light and sensor
};

/// The venue of `seed`. Ranges (venue.cpp's constants): image 400 x 400 .. 1280 x 1024 at 1:1, 5:4,
/// 4:3, 16:10 and 16:9; every MirrorProfile with the rim at 80..105 deg from the axis; mirror
/// centre up to 10 % of the image size off its centre (the rim partly outside the image at times);
/// tilt 0..3 deg; mirrored or not; body 5..35 % of the mirror radius; 0..4 rods 2..15 px wide;
/// carpets green to teal to blue-green and dark green, plain or textured; lines 5..12.5 cm, bluish
/// or yellowish white, worn in places; bright, dark or mixed rooms; dark or light floor beyond the
/// carpet; lab fields whose carpet ends short; goals or none; uneven light, vignetting, colour
/// casts, noise, JPEG; robots, the ball, people and boxes.
[[nodiscard]] Venue sample_venue(std::uint64_t seed);

/// Venue `index` of a run seeded `seed` (a splitmix64 mix of the two).
[[nodiscard]] std::uint64_t venue_seed(std::uint64_t seed, std::uint64_t index);

/// A place on the field whose position a team knows without measuring.
struct KnownSpot {
  std::string name;  // "centre spot", "penalty mark x min", "penalty mark x max"
  Eigen::Vector2d position_cm;
};

/// The two frames of a venue: the robot on a known spot at a random heading (for a calibration),
/// and at a random pose on the carpet.
struct VenueShots {
  KnownSpot spot;
  Pose2 calib_pose;
  Pose2 frame_pose;
  cv::Mat calib;  // BGR
  cv::Mat frame;  // BGR
};

/// The known spot and the two poses (seeded by the venue), without rendering.
[[nodiscard]] VenueShots venue_poses(const Venue& venue);
/// venue_poses() with both frames rendered.
[[nodiscard]] VenueShots render_venue(const Venue& venue);

/// truth.json: field (name, whether shipped, the spec as a geometry file), the true optics, the
/// nominal camera as a camera file, the robot, the known spot, the two poses and the look.
/// `field_file` is the file name the field is in (the shipped name, or a written field-*.json).
[[nodiscard]] std::string venue_truth_json(const Venue& venue, const VenueShots& shots,
                                           const std::string& field_file);

}  // namespace omniloc::sim
