// The windows' heading: the board's gyro, or the wheels (gyro_heading.hpp).
#include "omniloc/gyro_heading.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <utility>

#include "omniloc/regmap.hpp"

namespace omniloc {

const char* heading_trust_name(HeadingTrust trust) {
  switch (trust) {
    case HeadingTrust::kAbsolute:
      return "absolute";
    case HeadingTrust::kRelative:
      return "relative";
    case HeadingTrust::kNone:
      return "none";
  }
  return "none";
}

std::optional<HeadingTrust> parse_heading_trust(const std::string& name) {
  for (HeadingTrust t : {HeadingTrust::kAbsolute, HeadingTrust::kRelative, HeadingTrust::kNone})
    if (name == heading_trust_name(t)) return t;
  return std::nullopt;
}

WheelYawHeading::WheelYawHeading(const RobotConfig& robot)
    : robot_(robot), pinv_(wheel_pseudo_inverse(robot)) {}

double WheelYawHeading::rotation_deg(const EncoderWindow& window) const {
  // The rotation row of eq. (9)'s least-squares inverse: what a gyro would have measured, with the
  // wheels' slip in it (the reason a real gyro is better).
  return rad_to_deg(least_squares_motion(pinv_, wheel_travel_cm(robot_, window.counts)).z());
}

double WheelYawHeading::gyro_yaw_deg(const EncoderWindow& window) {
  yaw_deg_ = wrap_deg(yaw_deg_ + rotation_deg(window));
  return yaw_deg_;
}

GyroHeading::GyroHeading(const RobotConfig& robot, const GyroScale& scale,
                         const GyroHeadingConfig& config)
    : scale_(scale), config_(config), wheels_(robot), wheel_count_(wheel_count(robot)) {
  if (!(scale.lsb_per_dps > 0.0) || !(scale.odr_hz > 0.0) || !std::isfinite(scale.lsb_per_dps) ||
      !std::isfinite(scale.odr_hz))
    throw std::invalid_argument("GyroHeading: the gyro scale needs lsb_per_dps > 0 and odr_hz > 0");
}

bool GyroHeading::wheels_still(const EncoderWindow& window) const {
  for (int i = 0; i < wheel_count_; ++i)
    if (std::abs(window.counts[i]) > config_.standstill_max_counts) return false;
  return true;
}

void GyroHeading::learn_bias(const WindowGyro& g) {
  const double decay =
      std::exp(-static_cast<double>(g.samples) / scale_.odr_hz / config_.bias_time_constant_s);
  bias_sum_lsb_ = bias_sum_lsb_ * decay + static_cast<double>(g.sum_lsb);
  bias_samples_ = bias_samples_ * decay + static_cast<double>(g.samples);
}

double GyroHeading::gyro_yaw_deg(const EncoderWindow& window) {
  const WindowGyro& g = window.gyro;
  if (!g.present) {
    state_ = GyroState::kNoGyro;
    yaw_deg_ = wrap_deg(yaw_deg_ + wheels_.rotation_deg(window));
    return yaw_deg_;
  }
  const std::uint8_t not_running = static_cast<std::uint8_t>(1u << regmap::kGyroFlagNotRunning);
  if (!ever_ran_ && g.flags == not_running && g.samples == 0) {
    // The part's start-up after the board's reset: the wheels bridge the first windows; not a fault
    // (the heading stays aligned: a few milliseconds of the wheels' rotation).
    state_ = GyroState::kStarting;
    still_since_ms_ = -1.0;
    yaw_deg_ = wrap_deg(yaw_deg_ + wheels_.rotation_deg(window));
    return yaw_deg_;
  }
  if (g.flags != 0 || g.samples == 0) {  // never summed: the wheels stand in for this window
    state_ = (g.flags >> regmap::kGyroFlagAbsent) & 1u ? GyroState::kMissing : GyroState::kFault;
    last_flags_ = g.flags;
    clean_run_ = 0;
    ++fault_windows_;
    still_since_ms_ = -1.0;
    yaw_deg_ = wrap_deg(yaw_deg_ + wheels_.rotation_deg(window));
    return yaw_deg_;
  }
  ++clean_run_;
  ever_ran_ = true;
  const bool still = wheels_still(window);
  if (!still) {
    still_since_ms_ = -1.0;
  } else if (still_since_ms_ < 0.0) {
    still_since_ms_ = window.t_end_ms;
  }
  const bool standing =
      still && window.t_end_ms - still_since_ms_ >= config_.standstill_min_s * 1000.0;
  if (standing) {
    learn_bias(g);  // and the heading stays where it is: the robot cannot turn on still wheels
  } else {
    const double bias_lsb = bias_samples_ > 0.0 ? bias_sum_lsb_ / bias_samples_ : 0.0;
    yaw_deg_ =
        wrap_deg(yaw_deg_ + scale_.degrees(static_cast<double>(g.sum_lsb), g.samples, bias_lsb));
  }
  if ((state_ != GyroState::kFault && state_ != GyroState::kMissing) ||
      clean_run_ >= config_.recover_windows)
    state_ = bias_samples_ > 0.0 ? GyroState::kRunning : GyroState::kLearningBias;
  return yaw_deg_;
}

HeadingTrust GyroHeading::trust() const {
  return state_ == GyroState::kRunning || state_ == GyroState::kLearningBias ||
                 state_ == GyroState::kStarting
             ? HeadingTrust::kRelative
             : HeadingTrust::kNone;
}

double GyroHeading::bias_deg_per_s() const {
  return bias_samples_ > 0.0 ? bias_sum_lsb_ / bias_samples_ / scale_.lsb_per_dps : 0.0;
}

std::string GyroHeading::describe() const {
  char buf[96];
  switch (state_) {
    case GyroState::kNoGyro:
      return "wheels (no gyro on the board)";
    case GyroState::kLearningBias:
      return "gyro (bias not learnt yet: no standstill)";
    case GyroState::kRunning:
      std::snprintf(buf, sizeof buf, "gyro (bias %+.3f deg/s)", bias_deg_per_s());
      return buf;
    case GyroState::kMissing:
      return "wheels (gyro missing: no ICM-42688-P answers WHO_AM_I)";
    case GyroState::kStarting:
      return "gyro starting (the wheels until its first sample)";
    case GyroState::kFault:
      if (last_flags_ == 0) return "wheels (gyro gave no sample)";
      std::snprintf(buf, sizeof buf, "wheels (gyro fault flags 0x%02x: %s)",
                    static_cast<unsigned>(last_flags_), gyro_flag_names(last_flags_).c_str());
      return buf;
  }
  return "wheels";
}

std::string GyroHeading::status_token() const {
  switch (state_) {
    case GyroState::kNoGyro:
    case GyroState::kMissing:
      return "wheels-no-gyro";
    case GyroState::kStarting:
    case GyroState::kLearningBias:
    case GyroState::kRunning:
      return "gyro";
    case GyroState::kFault:
      return "wheels-gyro-fault";
  }
  return "wheels";
}

GyroScale GyroScale::of_board() {
  // The part as gyro_ctrl configures it (common/regmap.json "constants": ICM-42688-P at +-2000 dps,
  // 16.4 LSB/(deg/s) by datasheet DS-000347's table, 1 kHz).
  return {regmap::kGyroLsbPerKdps / 1000.0, static_cast<double>(regmap::kGyroOdrHz)};
}

std::string gyro_flag_names(std::uint8_t flags) {
  static constexpr std::pair<std::uint32_t, const char*> kNames[] = {
      {regmap::kGyroFlagWrongId, "wrong WHO_AM_I"},
      {regmap::kGyroFlagTimeout, "data-ready timeout"},
      {regmap::kGyroFlagStuck, "stuck value"},
      {regmap::kGyroFlagInvalid, "invalid value"},
      {regmap::kGyroFlagDropped, "sample dropped"},
      {regmap::kGyroFlagNotRunning, "not running"},
      {regmap::kGyroFlagAbsent, "absent"}};
  std::string out;
  for (const auto& [bit, name] : kNames)
    if ((flags >> bit) & 1u) out += (out.empty() ? "" : ", ") + std::string(name);
  return out.empty() ? "none" : out;
}

}  // namespace omniloc
