// Omni-camera model (the meta.json "camera" contract of issue 7): image centre, a monotonic table
// from pixel radius to ground distance (interpolated linearly both ways), the camera's yaw offset,
// mirroring, and the robot's own body and mast that hide part of the floor.
//
// A floor point at ground distance d and bearing b (robot frame) appears at image radius r =
// radius_px(d) and image angle phi = b + yaw_offset_deg: u = cx + r cos(phi), v = cy - r sin(phi)
// (u = cx - r cos(phi) when mirrored).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "omniloc/config.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

/// One calibration mark: a floor point at ground_cm appears at radius_px from the image centre.
struct RadiusMark {
  double radius_px;
  double ground_cm;
  bool operator==(const RadiusMark&) const = default;
};

/// A sector of bearings (robot frame) hidden by the mast or another part of the robot.
struct MastSector {
  double bearing_deg = 180.0;
  double half_width_deg = 0.0;
  bool operator==(const MastSector&) const = default;
};

/// A camera file (common/cameras/) or meta.json's "camera" block. Every key but "mask" is required,
/// so the files are the only source of these values (the initialisers only make CameraModel{} a
/// well-formed value).
struct CameraModel {
  int width_px = 640;
  int height_px = 480;
  Eigen::Vector2d center_px{320.0, 240.0};
  std::vector<RadiusMark> radius_lut;  // strictly increasing in both columns, at least two rows
  double yaw_offset_deg = 0.0;
  bool mirrored = false;
  double body_radius_px = 0.0;  // everything closer to the centre is the robot itself
  std::vector<MastSector> masts;

  /// How the line extraction sees the floor (the "vision" block; not part of fingerprint()).
  VisionModel vision;

  /// The feature format stores a radius as a sample index in one byte (255 is "no crossing"), so a
  /// ray has at most this many samples: sample k lies k * scan_step_px() px from the centre.
  static constexpr int kMaxScanSample = 254;
  /// Largest radius whose full circle is inside the image and the table.
  [[nodiscard]] double view_radius_px() const;
  /// Pixels between a ray's samples: 1 while the view fits in kMaxScanSample px, else the view
  /// divided into kMaxScanSample samples, so that a camera of any size scans its whole view (a
  /// 1280 x 1024 one as if its image were halved: the feature's resolution, not its reach, is
  /// capped).
  [[nodiscard]] double scan_step_px() const;
  /// The first and last sample index of a ray (ceil(min_radius / step), floor(view / step)).
  [[nodiscard]] int first_scan_sample() const;
  [[nodiscard]] int last_scan_sample() const;
  /// Smallest radius at which the floor is visible (body radius or the table's first row).
  [[nodiscard]] double min_radius_px() const;
  /// Ground distance at pixel radius r (linear in the table); NaN outside the table.
  [[nodiscard]] double ground_cm_at_radius(double radius_px) const;
  /// Pixel radius of a ground distance (inverse of the table); NaN outside the table.
  [[nodiscard]] double radius_px_at_ground(double ground_cm) const;
  /// Image pixel of a floor point given in the robot frame (cm); nullopt if it is out of the table.
  [[nodiscard]] std::optional<Eigen::Vector2d> pixel_of_robot_point(
      const Eigen::Vector2d& p_robot_cm) const;
  /// Floor point (robot frame, cm) seen at pixel (u, v); nullopt outside the calibrated ring.
  [[nodiscard]] std::optional<Eigen::Vector2d> robot_point_of_pixel(
      const Eigen::Vector2d& px) const;
  /// Image angle (deg) of a robot-frame bearing, and back.
  [[nodiscard]] double image_angle_deg(double bearing_deg) const {
    return bearing_deg + yaw_offset_deg;
  }
  /// True when the bearing (robot frame, deg) lies in a mast sector.
  [[nodiscard]] bool bearing_hidden(double bearing_deg) const;
  /// Hash of everything that changes where the floor appears (for database headers).
  [[nodiscard]] std::uint64_t fingerprint() const;

  /// Throws ConfigError "<at>.<field>: <why> (got <value>)": size not in 1..16384, centre outside
  /// the image, fewer than two table rows, a bad "vision" block, a table not strictly increasing in
  /// both columns or with negative values, a mast half width outside [0, 90), no visible floor
  /// ring.
  void validate(const config::Origin& at) const;
  bool operator==(const CameraModel&) const = default;
};

/// Reads and validates a camera from a parsed JSON object (a camera file's root or meta.json's
/// "camera" block): width, height, center_px [u, v], radius_lut [[r_px, d_cm], ...],
/// yaw_offset_deg, mirrored, optional "mask" {body_radius_px, masts: [{bearing_deg,
/// half_width_deg}]}, optional "vision" (vision.hpp), optional "description" (a note, not kept).
[[nodiscard]] CameraModel camera_from_json(const config::Node& node);

/// The key table (config_reader.hpp) of a camera block.
[[nodiscard]] const std::vector<config::Key<CameraModel>>& camera_keys();

/// Loads a camera file by name ("default" -> common/cameras/default.json) or path.
[[nodiscard]] CameraModel load_camera(const std::string& name_or_path);

}  // namespace omniloc
