// Where a window's heading comes from (the gyro_yaw_deg of equations (11)-(15) and of the
// least-squares odometry): the board's gyroscope (GyroHeading), or, without one, the wheels' own
// rotation (WheelYawHeading). docs/ODOMETRY.md "Heading" says what each does and why.
//
// GyroHeading turns the board's raw gyro windows (EncoderWindow::gyro: the sum of the part's
// yaw-rate samples over the 10 ms window, latched at the same tick as the encoder counts) into a
// heading:
//   scale     degrees = (sum_lsb - bias_lsb * samples) / (lsb_per_dps * odr_hz): every sample
//             stands for 1 / odr_hz seconds of rotation at its rate (GyroScale, from the part's
//             configuration in common/regmap.json's "gyro" section);
//   bias      learnt while the wheels stand still (every wheel within standstill_max_counts for at
//             least standstill_min_s): the mean of those samples, forgetting older standstill with
//             bias_time_constant_s; while standing the heading does not move (a zero-velocity
//             update: the robot cannot turn without turning its wheels). Between standstills the
//             image tracks what is left (the localizer's HeadingFilter, heading_filter.hpp);
//   faults    a window with any fault flag from the board, or no sample at all, is not summed:
//             its rotation comes from the wheels (the least-squares rotation row), the trust drops
//             to kNone and the status says why, until recover_windows clean windows in a row.
// The heading starts at 0 and is relative (HeadingTrust::kRelative): the localizer aligns it with
// the field at the first fix (the kick-off rule of the team's side decides the twin there) and
// from then on the gyro holds it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "omniloc/odometry.hpp"
#include "omniloc/robot_config.hpp"

namespace omniloc {

/// What the windows' heading is (the daemon asks once per window).
class HeadingSource {
 public:
  virtual ~HeadingSource() = default;
  /// The integrated yaw at the end of `window` (its counts and raw gyro fields are filled in).
  [[nodiscard]] virtual double gyro_yaw_deg(const EncoderWindow& window) = 0;
  /// True if gyro_yaw_deg is aligned with the field from the start (the simulator's gyro).
  [[nodiscard]] virtual bool is_absolute() const = 0;
  /// How far the last answer can be trusted (it may change window to window: a gyro fault).
  [[nodiscard]] virtual HeadingTrust trust() const {
    return is_absolute() ? HeadingTrust::kAbsolute : HeadingTrust::kNone;
  }
  /// One phrase for people: "gyro (bias +0.012 deg/s)", "wheels (no gyro on the board)", ...
  [[nodiscard]] virtual std::string describe() const { return status_token(); }
  /// One word for the status line's heading= field: gyro, wheels, absolute, or wheels-gyro-fault.
  [[nodiscard]] virtual std::string status_token() const {
    return is_absolute() ? "absolute" : "wheels";
  }
};

/// Without a gyro: the heading integrated from the wheels (eq. (9) least squares), starting at 0.
class WheelYawHeading final : public HeadingSource {
 public:
  explicit WheelYawHeading(const RobotConfig& robot);
  double gyro_yaw_deg(const EncoderWindow& window) override;
  [[nodiscard]] bool is_absolute() const override { return false; }
  [[nodiscard]] std::string describe() const override { return "wheels (no gyro)"; }
  /// The rotation of one window from the wheels alone, degrees.
  [[nodiscard]] double rotation_deg(const EncoderWindow& window) const;

 private:
  RobotConfig robot_;
  Eigen::Matrix<double, 3, 4> pinv_;
  double yaw_deg_ = 0.0;
};

/// The part's scale as the board configures it.
struct GyroScale {
  double lsb_per_dps = 0.0;  ///< sensitivity at the configured full scale, LSB per deg/s
  double odr_hz = 0.0;       ///< output data rate: each sample stands for 1 / odr_hz seconds
  /// The board's part and settings (common/regmap.json "constants" GYRO_*: ICM-42688-P, +-2000 dps,
  /// 1 kHz).
  [[nodiscard]] static GyroScale of_board();
  /// Degrees turned by `samples` samples summing to sum_lsb at a bias of bias_lsb per sample.
  [[nodiscard]] double degrees(double sum_lsb, double samples, double bias_lsb) const {
    return (sum_lsb - bias_lsb * samples) / (lsb_per_dps * odr_hz);
  }
};

struct GyroHeadingConfig {
  int standstill_max_counts = 0;       ///< a window is still when every wheel's |count| <= this
  double standstill_min_s = 0.2;       ///< ... and the wheels have been still this long
  double bias_time_constant_s = 60.0;  ///< older standstill counts for exp(-age / this) of the bias
  int recover_windows = 10;  ///< clean windows in a row after a fault before it is trusted
};

enum class GyroState {
  kNoGyro,        ///< no gyro field in the windows (a board without one): the wheels
  kStarting,      ///< the part has not given its first sample since the board's reset (NOT_RUNNING
                  ///< only, 31 ms of start-up): the wheels bridge it, and it is not a fault
  kLearningBias,  ///< running, no standstill yet: the bias is taken as 0
  kRunning,       ///< running with a learnt bias
  kFault,         ///< a fault was flagged recently: the wheels
  kMissing,       ///< the board has its gyro reader but no part answers (flag ABSENT): the wheels
};

/// The names of a window's gyro flags (regmap GYRO_FLAG_*), "none" for 0: "stuck value, not
/// running".
[[nodiscard]] std::string gyro_flag_names(std::uint8_t flags);

class GyroHeading final : public HeadingSource {
 public:
  GyroHeading(const RobotConfig& robot, const GyroScale& scale,
              const GyroHeadingConfig& config = {});
  double gyro_yaw_deg(const EncoderWindow& window) override;
  [[nodiscard]] bool is_absolute() const override { return false; }
  [[nodiscard]] HeadingTrust trust() const override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string status_token() const override;

  [[nodiscard]] GyroState state() const { return state_; }
  /// The bias learnt at standstill, deg/s (0 until learnt).
  [[nodiscard]] double bias_deg_per_s() const;
  /// Windows whose rotation came from the wheels because of a fault flag or no sample.
  [[nodiscard]] std::uint64_t fault_windows() const { return fault_windows_; }

 private:
  [[nodiscard]] bool wheels_still(const EncoderWindow& window) const;
  void learn_bias(const WindowGyro& g);

  GyroScale scale_;
  GyroHeadingConfig config_;
  WheelYawHeading wheels_;
  int wheel_count_;
  GyroState state_ = GyroState::kNoGyro;
  double yaw_deg_ = 0.0;
  double still_since_ms_ = -1.0;  ///< board time the wheels stopped (< 0: moving)
  double bias_sum_lsb_ = 0.0;     ///< decayed sums of the standstill samples
  double bias_samples_ = 0.0;
  int clean_run_ = 0;            ///< clean windows in a row since the last fault
  std::uint8_t last_flags_ = 0;  ///< the last fault's flags (0: no sample at all)
  std::uint64_t fault_windows_ = 0;
  bool ever_ran_ = false;  ///< a clean window with samples has been seen
};

}  // namespace omniloc
