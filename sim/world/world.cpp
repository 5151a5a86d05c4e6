#include "omniloc_sim/world.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "omniloc_sim/playing_area.hpp"

namespace omniloc::sim {
namespace {

std::int64_t cycles_for(double clock_hz, double ms) {
  return std::llround(clock_hz * ms / 1000.0);
}

WorldConfig timed(const RobotConfig& robot, std::uint64_t seed) {
  WorldConfig c;
  c.robot = robot;
  c.seed = seed;
  c.set_clock(c.clock_hz);
  return c;
}

// Height profile h(rho) = height/2 * (1 + cos(pi rho / radius)); returns the gradient at p.
Eigen::Vector2d bump_gradient(const CarpetBump& b, const Eigen::Vector2d& p) {
  const Eigen::Vector2d rel = p - b.centre_cm;
  const double rho = rel.norm();
  if (rho >= b.radius_cm || rho <= 0.0) return {0.0, 0.0};
  const double dh = -0.5 * b.height_cm * kPi / b.radius_cm * std::sin(kPi * rho / b.radius_cm);
  return dh * rel / rho;
}

}  // namespace

void WorldConfig::set_clock(double hz, double window_period_ms) {
  clock_hz = hz;
  step_cycles = cycles_for(hz, 1.0);
  window_cycles = cycles_for(hz, window_period_ms);
  first_window_end_cycles = window_cycles;
}

WorldConfig WorldConfig::noise_free(const RobotConfig& robot, std::uint64_t seed) {
  WorldConfig c = timed(robot, seed);
  c.encoder = {0.0, 0.0};
  c.gyro = GyroModel::noise_free();
  return c;
}

WorldConfig WorldConfig::default_noise(const RobotConfig& robot, std::uint64_t seed,
                                       const PlayingArea& f) {
  WorldConfig c = timed(robot, seed);
  std::mt19937_64 rng(seed ^ 0xB0B5ULL);
  std::uniform_real_distribution<double> ux(f.x_min_cm, f.x_max_cm), uy(f.y_min_cm, f.y_max_cm);
  for (int i = 0; i < 8; ++i) c.bumps.push_back({{ux(rng), uy(rng)}, 15.0, 0.8});
  return c;
}

std::int64_t position_at(const StepSpan& span, int w, std::int64_t cycle) {
  const auto i = static_cast<std::size_t>(w);
  const std::int64_t n = span.end_cycle - span.begin_cycle;
  const std::int64_t k = cycle - span.begin_cycle;
  return span.begin_pos[i] + floor_div((span.end_pos[i] - span.begin_pos[i]) * k, n);
}

std::int64_t decoded_count(std::int64_t q, int decoding) {
  switch (decoding) {
    case 4:
      return q;
    case 2:
      return floor_div(q + 3, 4) + floor_div(q + 1, 4);
    case 1:
      return floor_div(q + 3, 4);
    default:
      throw std::invalid_argument("decoded_count: decoding must be 1, 2 or 4, got " +
                                  std::to_string(decoding));
  }
}

World::World(const WorldConfig& config, Trajectory trajectory)
    : config_((validate_robot_config(config.robot, "WorldConfig.robot"), config)),
      trajectory_(std::move(trajectory)),
      rng_(config.seed),
      wheels_(wheel_count(config.robot)),
      jacobian_(padded_wheel_jacobian(config.robot)),
      pose_(trajectory_.start()),
      prev_pose_(pose_),
      gyro_(config.gyro, pose_.yaw_deg, rng_),
      next_window_end_(config.first_window_end_cycles) {
  const std::vector<Eigen::Vector2d> positions = wheel_positions_cm(config.robot);
  const std::vector<WheelConfig> layout = wheel_layout(config.robot);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    wheel_position_[i] = positions[i];
    // The simulator counts X4 quarter-steps; the decoding is applied when a window is read.
    cm_per_quarter_[i] = 2.0 * kPi * layout[i].wheel_radius_cm /
                         (4.0 * layout[i].counts_per_rev * layout[i].gear_ratio);
  }
  if (config.step_cycles <= 0 || config.window_cycles < config.step_cycles ||
      config.first_window_end_cycles <= 0)
    throw std::invalid_argument(
        "WorldConfig: need step_cycles > 0, window_cycles >= step_cycles (got " +
        std::to_string(config.step_cycles) + ", " + std::to_string(config.window_cycles) +
        ") and first_window_end_cycles > 0");
  for (std::size_t k = 1; k < config_.kidnaps.size(); ++k)
    if (config_.kidnaps[k].at_s < config_.kidnaps[k - 1].at_s)
      throw std::invalid_argument("WorldConfig: kidnap events must be in time order");
  for (const SlipEvent& s : config.slips)
    if (s.wheel < 1 || s.wheel > wheels_)
      throw std::invalid_argument("WorldConfig: slip event wheel must be 1.." +
                                  std::to_string(wheels_) + " for this robot, got " +
                                  std::to_string(s.wheel));
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> phase(0.0, 4.0);
  // Only the robot's wheels draw (a fourth, absent encoder stays at 0 and never moves).
  for (std::size_t i = 0; i < static_cast<std::size_t>(wheels_); ++i) {
    wheel_scale_[i] = config.encoder.scale_sigma * n(rng_);
    quarters_[i] = config.random_encoder_phase ? phase(rng_) : 0.0;
    span_.end_pos[i] =
        std::llround(quarters_[i] * static_cast<double>(std::int64_t{1} << kFracBits));
    window_start_quarter_[i] = decoded_count(quarter_of(span_.end_pos[i]), config.robot.decoding);
  }
  span_.begin_pos = span_.end_pos;
  prev_gyro_raw_deg_ = gyro_.raw_yaw_deg();
}

double World::time_s() const {
  return static_cast<double>(span_.end_cycle) / config_.clock_hz;
}

bool World::finished() const {
  return time_s() >= trajectory_.duration_s();
}

Eigen::Vector2d World::wheel_position_cm(int w) const {
  return wheel_position_.at(static_cast<std::size_t>(w));
}

TrajectorySample World::reference(double t_s) const {
  TrajectorySample s = trajectory_.sample(t_s);
  const Eigen::Vector2d p = robot_to_field({s.pose.x_cm, s.pose.y_cm}, ref_yaw_deg_) + ref_shift_;
  s.pose = {p.x(), p.y(), s.pose.yaw_deg + ref_yaw_deg_};
  s.velocity_cm_per_s = robot_to_field(s.velocity_cm_per_s, ref_yaw_deg_);
  return s;
}

void World::kidnap(const Pose2& to) {
  // K(p) = to + R(dk) (p - here); the reference map becomes K o (current map).
  const double dk = angle_diff_deg(to.yaw_deg, pose_.yaw_deg);
  ref_shift_ = to.position_cm() + robot_to_field(ref_shift_ - pose_.position_cm(), dk);
  ref_yaw_deg_ += dk;
  pose_ = {to.x_cm, to.y_cm, pose_.yaw_deg + dk};
  gyro_.step(dk, 0.0, rng_);
  kidnap_flag_ = true;
}

namespace {

// The commanded field velocity and turn rate: the reference's velocity (mid-step) plus a gentle
// pull back onto its path (gain k per second).
void tracking_command(const TrajectorySample& now, const TrajectorySample& mid, const Pose2& pose,
                      double k, Eigen::Vector2d& v_field, double& omega_deg) {
  v_field = mid.velocity_cm_per_s + k * (now.pose.position_cm() - pose.position_cm());
  omega_deg = mid.yaw_rate_deg_per_s + k * angle_diff_deg(now.pose.yaw_deg, pose.yaw_deg);
}

// Exact motion under a constant body twist over the step: the chord, in the field frame.
Eigen::Vector2d twist_chord(const Eigen::Vector2d& v_body, double omega_rad, double dt,
                            double yaw_deg) {
  const double dth = omega_rad * dt;
  const double a = std::abs(dth) < 1e-9 ? 1.0 : std::sin(dth) / dth;
  const double b = std::abs(dth) < 1e-9 ? 0.5 * dth : (1.0 - std::cos(dth)) / dth;
  const Eigen::Vector2d chord_body(dt * (a * v_body.x() - b * v_body.y()),
                                   dt * (b * v_body.x() + a * v_body.y()));
  return robot_to_field(chord_body, yaw_deg);
}

// Slip: extra spin in the wheel's direction of travel, for the part of the step [t0, t0 + dt] it
// overlaps. Returns the mask of the wheels that slipped.
std::uint8_t add_slips(const std::vector<SlipEvent>& slips, double t0, double dt,
                       const Eigen::Vector4d& ground, Eigen::Vector4d& travel) {
  std::uint8_t mask = 0;
  for (const SlipEvent& s : slips) {
    const double overlap = std::min(t0 + dt, s.start_s + s.duration_s) - std::max(t0, s.start_s);
    if (overlap <= 0.0) continue;
    const int w = s.wheel - 1;
    const double sign = ground[w] < 0.0 ? -1.0 : 1.0;
    travel[w] += sign * s.extra_speed_cm_per_s * overlap;
    mask |= static_cast<std::uint8_t>(1u << w);
  }
  return mask;
}

// The robot's motion over a step, as the bumps need it: centre and heading at mid-step, body
// velocity and turn rate.
struct StepMotion {
  Eigen::Vector2d centre;
  double mid_yaw_deg;
  Eigen::Vector2d v_body;
  double omega_rad;
};

// Bumps: the wheel's path over the raised cosine is longer by sqrt(1 + slope^2). Returns the mask
// of the wheels that went over one.
std::uint8_t add_bumps(const std::vector<CarpetBump>& bumps, const World& world,
                       const StepMotion& m, const Eigen::Vector4d& ground,
                       Eigen::Vector4d& travel) {
  std::uint8_t mask = 0;
  for (int w = 0; w < world.wheels(); ++w) {
    const Eigen::Vector2d p_body = world.wheel_position_cm(w);
    const Eigen::Vector2d contact = m.centre + robot_to_field(p_body, m.mid_yaw_deg);
    const Eigen::Vector2d v_contact = robot_to_field(
        m.v_body + m.omega_rad * Eigen::Vector2d(-p_body.y(), p_body.x()), m.mid_yaw_deg);
    const double speed = v_contact.norm();
    if (speed <= 1e-9) continue;
    for (const CarpetBump& bump : bumps) {
      const double slope = bump_gradient(bump, contact).dot(v_contact / speed);
      if (slope == 0.0) continue;
      travel[w] += ground[w] * (std::sqrt(1.0 + slope * slope) - 1.0);
      mask |= static_cast<std::uint8_t>(1u << w);
    }
  }
  return mask;
}

}  // namespace

void World::step() {
  const double clock = config_.clock_hz;
  const std::int64_t c0 = span_.end_cycle;
  const std::int64_t c1 = c0 + config_.step_cycles;
  const double t0 = static_cast<double>(c0) / clock;
  const double dt = static_cast<double>(config_.step_cycles) / clock;
  while (next_kidnap_ < config_.kidnaps.size() && config_.kidnaps[next_kidnap_].at_s < t0 + dt) {
    kidnap(config_.kidnaps[next_kidnap_++].to);
  }
  double omega_deg = 0.0;
  Eigen::Vector2d v_field(0.0, 0.0);
  if (t0 < trajectory_.duration_s()) {
    const TrajectorySample now = reference(t0);
    const TrajectorySample mid = reference(t0 + 0.5 * dt);
    tracking_command(now, mid, pose_, config_.tracking_gain_per_s, v_field, omega_deg);
  }
  const Eigen::Vector2d v_body = field_to_robot(v_field, pose_.yaw_deg + 0.5 * omega_deg * dt);
  const double omega_rad = deg_to_rad(omega_deg);
  const double dth = omega_rad * dt;
  const Eigen::Vector2d dp = twist_chord(v_body, omega_rad, dt, pose_.yaw_deg);
  const Eigen::Vector4d ground =
      jacobian_ * Eigen::Vector3d(v_body.x(), v_body.y(), omega_rad) * dt;
  Eigen::Vector4d travel = ground;
  slip_mask_ |= add_slips(config_.slips, t0, dt, ground, travel);
  if (!config_.bumps.empty()) {
    const StepMotion m{pose_.position_cm() + 0.5 * dp, pose_.yaw_deg + 0.5 * rad_to_deg(dth),
                       v_body, omega_rad};
    bump_mask_ |= add_bumps(config_.bumps, *this, m, ground, travel);
  }
  // Encoder errors, then the position in quarter-steps.
  std::normal_distribution<double> n(0.0, 1.0);
  span_.begin_cycle = c0;
  span_.end_cycle = c1;
  span_.begin_pos = span_.end_pos;
  for (int w = 0; w < wheels_; ++w) {
    const auto i = static_cast<std::size_t>(w);
    double meas = travel[w] * (1.0 + wheel_scale_[i]);
    if (config_.encoder.rolling_noise_cm_per_sqrt_cm > 0.0)
      meas +=
          config_.encoder.rolling_noise_cm_per_sqrt_cm * std::sqrt(std::abs(ground[w])) * n(rng_);
    quarters_[i] += meas / cm_per_quarter_[i];
    span_.end_pos[i] =
        std::llround(quarters_[i] * static_cast<double>(std::int64_t{1} << kFracBits));
  }
  prev_pose_ = pose_;
  prev_distance_cm_ = distance_cm_;
  pose_ = pose_.shifted(dp);
  pose_.yaw_deg += rad_to_deg(dth);  // unwrapped: the truth's yaw is wrapped when it is reported
  distance_cm_ += dp.norm();
  prev_gyro_raw_deg_ = gyro_.raw_yaw_deg();
  gyro_.step(rad_to_deg(dth), dt, rng_);
}

SimWindow World::next_window() {
  while (span_.end_cycle < next_window_end_) step();
  const std::int64_t c = next_window_end_;
  // Where inside the last step the window ends (1 when aligned with the step end).
  const double f = static_cast<double>(c - span_.begin_cycle) /
                   static_cast<double>(span_.end_cycle - span_.begin_cycle);
  SimWindow out;
  out.t_end_cycles = c;
  out.window.seq = seq_++;
  out.window.t_end_ms = static_cast<double>(c) * 1000.0 / config_.clock_hz;
  for (int w = 0; w < 4; ++w) {
    const auto i = static_cast<std::size_t>(w);
    const std::int64_t count =
        decoded_count(quarter_of(position_at(span_, w, c)), config_.robot.decoding);
    out.window.counts[i] = static_cast<std::int32_t>(count - window_start_quarter_[i]);
    window_start_quarter_[i] = count;
  }
  out.window.gyro_yaw_deg =
      gyro_.report(prev_gyro_raw_deg_ + f * (gyro_.raw_yaw_deg() - prev_gyro_raw_deg_));
  out.truth = interpolate(prev_pose_, pose_, f);  // a step turns far less than half a turn
  out.truth_distance_cm = prev_distance_cm_ + f * (distance_cm_ - prev_distance_cm_);
  out.slip_wheels = slip_mask_;
  out.bump_wheels = bump_mask_;
  out.kidnapped = kidnap_flag_;
  // A step straddling the window end counts for both windows' fault masks.
  const bool straddles = c < span_.end_cycle;
  if (!straddles) {
    slip_mask_ = bump_mask_ = 0;
    kidnap_flag_ = false;
  }
  next_window_end_ += config_.window_cycles;
  return out;
}

}  // namespace omniloc::sim
