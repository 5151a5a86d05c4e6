// The simulated robot: a three- or four-wheel omni platform (the wheel Jacobian of its RobotConfig:
// equation (9) for the symmetric shorthand, any listed layout otherwise) tracking a Trajectory on
// the FIRA field, with per-wheel slip, carpet bumps, encoder errors and a gyroscope. Time runs in
// board clock cycles; the physics advances in fixed steps (1 ms by default) with a constant body
// twist per step, so the wheel travel is exact for the integrated ground truth.
//
// Each wheel's encoder position is kept in quadrature quarter-steps as fixed point (kFracBits),
// linear within a step. Both outputs read that one position: per-window counts (next_window) and
// the cycle-level A/B waveform (QuadratureStream, encoder_waveform.hpp), so they agree exactly.
#pragma once

#include "omniloc_sim/playing_area.hpp"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "omniloc/conventions.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc_sim/gyro.hpp"
#include "omniloc_sim/trajectory.hpp"

namespace omniloc::sim {

/// Wheel `wheel` (1..wheel count) spins `extra_speed_cm_per_s` faster than the ground under it, in
/// its direction of travel, from start_s for duration_s: the wheel turns, the robot does not
/// follow.
struct SlipEvent {
  int wheel = 1;
  double start_s = 0.0;
  double duration_s = 0.5;
  double extra_speed_cm_per_s = 30.0;
};

/// A smooth (raised-cosine) bump in the carpet: a wheel rolling over it travels further than
/// the ground distance, by the path's slope.
struct CarpetBump {
  Eigen::Vector2d centre_cm{0.0, 0.0};
  double radius_cm = 10.0;
  double height_cm = 1.0;
};

/// The robot is picked up at at_s and put down at `to` at once: the wheels are in the air (no
/// counts), the gyro feels the change of heading. The rest of the trajectory is driven from the new
/// pose (the reference is moved rigidly with the robot); keeping it on the field is up to the
/// caller.
struct KidnapEvent {
  double at_s = 0.0;
  Pose2 to;
};

struct EncoderNoise {
  double scale_sigma = 0.002;  ///< per-wheel effective radius error (wear, tyre), drawn once
  double rolling_noise_cm_per_sqrt_cm = 0.01;  ///< random travel noise (carpet compliance)
};

struct WorldConfig {
  RobotConfig robot;
  std::uint64_t seed = 1;
  /// The simulated board's clock, whose cycles the window timestamps count: the simulator's own
  /// (the host learns a real board's from its PERIOD register). The paper's 40 MHz by default.
  double clock_hz = regmap::kPaperClockHz;
  std::int64_t step_cycles = 40'000;     ///< physics step (1 ms at 40 MHz)
  std::int64_t window_cycles = 400'000;  ///< board window (10 ms at 40 MHz)
  std::int64_t first_window_end_cycles = 400'000;
  EncoderNoise encoder;
  GyroModel gyro;
  std::vector<SlipEvent> slips;
  std::vector<CarpetBump> bumps;
  std::vector<KidnapEvent> kidnaps;
  bool random_encoder_phase = true;  ///< start each encoder at a random quarter-step phase
  double tracking_gain_per_s = 2.0;  ///< feedback pulling the robot back onto the reference

  /// Retimes the world to a board clock: 1 ms physics steps and windows of `window_period_ms`
  /// (the register map's window period unless a test asks for another), the first window ending
  /// one window period after the start.
  void set_clock(double clock_hz, double window_period_ms = regmap::kWindowPeriodMs);

  /// Quantisation only: no encoder noise, gyro only quantised, no faults. At the default clock.
  [[nodiscard]] static WorldConfig noise_free(const RobotConfig& robot, std::uint64_t seed = 1);
  /// The default noise of issue 5: encoder scale and rolling noise, a realistic gyro, a few bumps
  /// on `area`'s playing field.
  [[nodiscard]] static WorldConfig default_noise(const RobotConfig& robot, std::uint64_t seed = 1,
                                                 const PlayingArea& area = fira_robosot_area());
};

/// One board window as the host sees it, with the simulator's truth beside it.
struct SimWindow {
  EncoderWindow window;
  std::int64_t t_end_cycles = 0;
  Pose2 truth;                     ///< at the end of the window (yaw wrapped)
  double truth_distance_cm = 0.0;  ///< path length of the robot centre since the start
  std::uint8_t slip_wheels = 0;    ///< bit i: wheel i+1 slipped during this window
  std::uint8_t bump_wheels = 0;    ///< bit i: wheel i+1 was on a bump during this window
  bool kidnapped = false;          ///< the robot was carried during this window
};

/// Quarter-step positions of the four encoder slots over the last physics step (a three-wheel
/// robot's fourth slot never moves).
struct StepSpan {
  std::int64_t begin_cycle = 0;
  std::int64_t end_cycle = 0;
  std::array<std::int64_t, 4> begin_pos{};  ///< fixed point, kFracBits fractional bits
  std::array<std::int64_t, 4> end_pos{};
};

inline constexpr int kFracBits = 16;

/// floor(a / b) for b > 0.
[[nodiscard]] constexpr std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// Fixed-point position of wheel index `w` at `cycle` inside the span (linear, floored).
[[nodiscard]] std::int64_t position_at(const StepSpan& span, int w, std::int64_t cycle);

/// Whole quarter-steps at a fixed-point position.
[[nodiscard]] constexpr std::int64_t quarter_of(std::int64_t pos) {
  return floor_div(pos, std::int64_t{1} << kFracBits);
}

/// Decoded count at quarter-step index q, as the RTL decoder counts (rtl/quadrature_decoder.v):
/// X4 every transition, X2 the A transitions, X1 only the 00<->10 transition.
[[nodiscard]] std::int64_t decoded_count(std::int64_t quarter, int decoding);

class World {
 public:
  World(const WorldConfig& config, Trajectory trajectory);

  /// Advances one physics step.
  void step();
  /// Advances to the next window end and returns that window.
  SimWindow next_window();
  /// True once the trajectory (including its final wait) is over.
  [[nodiscard]] bool finished() const;

  [[nodiscard]] std::int64_t cycle() const { return span_.end_cycle; }
  [[nodiscard]] double time_s() const;
  [[nodiscard]] const Pose2& truth() const { return pose_; }
  [[nodiscard]] const StepSpan& last_step() const { return span_; }
  [[nodiscard]] const WorldConfig& config() const { return config_; }
  [[nodiscard]] const Trajectory& trajectory() const { return trajectory_; }
  [[nodiscard]] const Gyro& gyro() const { return gyro_; }
  /// Wheel i's contact point in the robot frame (wheel_positions_cm of the robot config).
  [[nodiscard]] Eigen::Vector2d wheel_position_cm(int wheel_index) const;
  /// The robot's number of wheels (3 or 4).
  [[nodiscard]] int wheels() const { return wheels_; }

 private:
  WorldConfig config_;
  Trajectory trajectory_;
  std::mt19937_64 rng_;
  int wheels_;
  Eigen::Matrix<double, 4, 3> jacobian_;  // padded: a three-wheel robot's fourth row is zero
  std::array<double, 4> cm_per_quarter_{};
  std::array<Eigen::Vector2d, 4> wheel_position_{};
  std::array<double, 4> wheel_scale_{};
  std::array<double, 4> quarters_{};  // exact encoder position, quarter-steps
  Pose2 pose_;                        // truth, yaw unwrapped
  Pose2 prev_pose_;
  double distance_cm_ = 0.0;
  double prev_distance_cm_ = 0.0;
  Gyro gyro_;
  double prev_gyro_raw_deg_ = 0.0;
  StepSpan span_;
  std::int64_t next_window_end_;
  std::array<std::int64_t, 4> window_start_quarter_{};
  std::uint32_t seq_ = 0;
  std::uint8_t slip_mask_ = 0;
  std::uint8_t bump_mask_ = 0;
  bool kidnap_flag_ = false;
  std::size_t next_kidnap_ = 0;
  // Rigid map applied to the trajectory's reference after kidnappings: p -> R(ref_yaw) p +
  // ref_shift.
  double ref_yaw_deg_ = 0.0;
  Eigen::Vector2d ref_shift_{0.0, 0.0};
  [[nodiscard]] TrajectorySample reference(double t_s) const;
  void kidnap(const Pose2& to);
};

}  // namespace omniloc::sim
