// Scripted robot motions: paths of lines and arcs driven with trapezoidal speed profiles (bounded
// acceleration), headings either following a trapezoidal yaw profile or the path's tangent.
// A trajectory is a pure function of time: the world simulator tracks it and integrates the truth.
#pragma once

#include "omniloc_sim/playing_area.hpp"

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "omniloc/conventions.hpp"

namespace omniloc::sim {

struct MotionLimits {
  double max_speed_cm_per_s = 100.0;
  double max_accel_cm_per_s2 = 200.0;
  double max_yaw_rate_deg_per_s = 180.0;
  double max_yaw_accel_deg_per_s2 = 360.0;
};

/// Reference state at one instant, in the field frame. yaw_deg is unwrapped (continuous).
struct TrajectorySample {
  Pose2 pose;
  Eigen::Vector2d velocity_cm_per_s{0.0, 0.0};
  double yaw_rate_deg_per_s = 0.0;
};

/// Distance covered by a rest-to-rest trapezoidal (or triangular) speed profile.
struct Trapezoid {
  double distance = 0.0;
  double peak_speed = 0.0;
  double accel = 1.0;
  double t_accel = 0.0;
  double t_cruise = 0.0;
  static Trapezoid make(double distance, double max_speed, double max_accel);
  [[nodiscard]] double duration() const { return 2.0 * t_accel + t_cruise; }
  [[nodiscard]] double position(double t) const;
  [[nodiscard]] double speed(double t) const;
};

class Trajectory {
 public:
  Trajectory(std::string name, const Pose2& start);

  /// Straight line to `target` while turning (the short way) to `yaw_deg`.
  Trajectory& line_to(const Eigen::Vector2d& target, double yaw_deg, const MotionLimits& limits);
  /// Turn on the spot by `delta_deg` (may exceed a full turn).
  Trajectory& rotate_by(double delta_deg, const MotionLimits& limits);
  /// Arc around `centre` by `sweep_deg` (positive = counter-clockwise); the heading follows the
  /// tangent (keeping its current offset to it) or stays fixed.
  Trajectory& arc(const Eigen::Vector2d& centre, double sweep_deg, bool yaw_follows_tangent,
                  const MotionLimits& limits);
  /// A figure eight of two tangent circles of `radius_cm` (first counter-clockwise, then
  /// clockwise) driven in one profile, heading fixed.
  Trajectory& figure_eight(double radius_cm, const MotionLimits& limits);
  Trajectory& wait(double seconds);

  [[nodiscard]] TrajectorySample sample(double t_s) const;
  [[nodiscard]] double duration_s() const { return duration_s_; }
  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] const Pose2& start() const { return start_; }
  /// Path length of the reference (translation only), cm.
  [[nodiscard]] double length_cm() const;

 private:
  enum class Kind { kLine, kArc, kEight, kWait };
  struct Leg {
    Kind kind = Kind::kWait;
    double t0 = 0.0;
    double duration = 0.0;
    Pose2 start;
    Trapezoid move;  // along the path (cm)
    Trapezoid turn;  // yaw (deg), for non-tangent headings
    double turn_sign = 1.0;
    Eigen::Vector2d direction{1.0, 0.0};  // line
    Eigen::Vector2d centre{0.0, 0.0};     // arc
    double radius = 0.0;
    double start_angle_rad = 0.0;
    double sweep_sign = 1.0;
    bool yaw_tangent = false;
  };
  void push(Leg leg);
  [[nodiscard]] Pose2 end_pose() const;

  std::string name_;
  Pose2 start_;
  std::vector<Leg> legs_;
  double duration_s_ = 0.0;
};

/// The trajectories of issue 5, all on the FIRA field (PlayingArea):
/// "straight", "rotate_in_place", "circle", "figure_eight", "boundary_tour", "random_walk".
[[nodiscard]] std::vector<std::string> standard_trajectory_names();
/// Throws std::invalid_argument for an unknown name (listing the known ones). `seed` only
/// matters for "random_walk". Each is placed on `area` (its centre, lines and size): on the FIRA
/// field by default, on any field with playing_area(field).
[[nodiscard]] Trajectory make_trajectory(std::string_view name, std::uint64_t seed = 1,
                                         const PlayingArea& area = fira_robosot_area());

}  // namespace omniloc::sim
