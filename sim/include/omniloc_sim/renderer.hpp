// Omni-camera renderer: a realistic image of the field from any pose through the camera model,
// for tests, benchmarks and the simulated robot. Green carpet with white lines, a darker floor
// beyond the border, the robot's own body and mast, other robots as dark blobs, a lighting
// gradient, sensor noise and blur. Deterministic for a given seed.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/field.hpp"

namespace omniloc::sim {

/// Another robot on the field: a dark cylinder, tall enough to hide the floor behind it.
struct Obstacle {
  Eigen::Vector2d position_cm;
  double radius_cm = 20.0;
};

struct RenderOptions {
  std::uint64_t seed = 1;
  double noise_sigma = 6.0;          // Gaussian sensor noise per channel (0..255 scale)
  bool blur = true;                  // 3 x 3 Gaussian (optics)
  double gradient_strength = 0.2;    // brightness varies by +-this fraction across the image
  double gradient_direction_deg = 30.0;
  std::vector<Obstacle> obstacles;
};

/// Options for an ideal image: no noise, blur or gradient.
[[nodiscard]] RenderOptions noise_free();

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
[[nodiscard]] cv::Mat render_omni(const FieldGeometry& field, const CameraModel& camera, const Pose2& pose,
                                  const RenderOptions& options);

/// `count` robots placed at random (seeded) on the carpet between 60 and 250 cm from `pose`, not
/// overlapping each other.
[[nodiscard]] std::vector<Obstacle> random_obstacles(const FieldGeometry& field, const Pose2& pose, int count,
                                                     std::uint64_t seed);

}  // namespace omniloc::sim
