#include "omniloc_sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "omniloc_sim/playing_area.hpp"

namespace omniloc::sim {

Trapezoid Trapezoid::make(double distance, double max_speed, double max_accel) {
  if (!(distance >= 0.0) || !(max_speed > 0.0) || !(max_accel > 0.0))
    throw std::invalid_argument("Trapezoid: distance must be >= 0 and speed, acceleration > 0");
  Trapezoid p;
  p.distance = distance;
  p.accel = max_accel;
  const double d_ramp = max_speed * max_speed / max_accel;  // accelerate + brake
  if (distance <= d_ramp) {
    p.peak_speed = std::sqrt(distance * max_accel);
    p.t_accel = p.peak_speed / max_accel;
    p.t_cruise = 0.0;
  } else {
    p.peak_speed = max_speed;
    p.t_accel = max_speed / max_accel;
    p.t_cruise = (distance - d_ramp) / max_speed;
  }
  return p;
}

double Trapezoid::position(double t) const {
  if (t <= 0.0) return 0.0;
  if (t >= duration()) return distance;
  if (t < t_accel) return 0.5 * accel * t * t;
  const double d_acc = 0.5 * accel * t_accel * t_accel;
  if (t < t_accel + t_cruise) return d_acc + peak_speed * (t - t_accel);
  const double tb = duration() - t;
  return distance - 0.5 * accel * tb * tb;
}

double Trapezoid::speed(double t) const {
  if (t <= 0.0 || t >= duration()) return 0.0;
  if (t < t_accel) return accel * t;
  if (t < t_accel + t_cruise) return peak_speed;
  return accel * (duration() - t);
}

Trajectory::Trajectory(std::string name, const Pose2& start)
    : name_(std::move(name)), start_(start) {}

void Trajectory::push(Leg leg) {
  leg.t0 = duration_s_;
  leg.start = end_pose();
  duration_s_ += leg.duration;
  legs_.push_back(leg);
}

Pose2 Trajectory::end_pose() const {
  if (legs_.empty()) return start_;
  return sample(duration_s_).pose;
}

Trajectory& Trajectory::line_to(const Eigen::Vector2d& target, double yaw_deg,
                                const MotionLimits& lim) {
  const Pose2 s = end_pose();
  Leg leg;
  leg.kind = Kind::kLine;
  const Eigen::Vector2d delta = target - Eigen::Vector2d(s.x_cm, s.y_cm);
  const double len = delta.norm();
  leg.direction = len > 0.0 ? Eigen::Vector2d(delta / len) : Eigen::Vector2d(1.0, 0.0);
  leg.move = Trapezoid::make(len, lim.max_speed_cm_per_s, lim.max_accel_cm_per_s2);
  const double dyaw = angle_diff_deg(yaw_deg, s.yaw_deg);
  leg.turn =
      Trapezoid::make(std::abs(dyaw), lim.max_yaw_rate_deg_per_s, lim.max_yaw_accel_deg_per_s2);
  leg.turn_sign = dyaw < 0.0 ? -1.0 : 1.0;
  leg.duration = std::max(leg.move.duration(), leg.turn.duration());
  push(leg);
  return *this;
}

Trajectory& Trajectory::rotate_by(double delta_deg, const MotionLimits& lim) {
  Leg leg;
  leg.kind = Kind::kLine;
  leg.move = Trapezoid::make(0.0, 1.0, 1.0);
  leg.turn = Trapezoid::make(std::abs(delta_deg), lim.max_yaw_rate_deg_per_s,
                             lim.max_yaw_accel_deg_per_s2);
  leg.turn_sign = delta_deg < 0.0 ? -1.0 : 1.0;
  leg.duration = leg.turn.duration();
  push(leg);
  return *this;
}

Trajectory& Trajectory::arc(const Eigen::Vector2d& centre, double sweep_deg,
                            bool yaw_follows_tangent, const MotionLimits& lim) {
  const Pose2 s = end_pose();
  Leg leg;
  leg.kind = Kind::kArc;
  leg.centre = centre;
  const Eigen::Vector2d rel = Eigen::Vector2d(s.x_cm, s.y_cm) - centre;
  leg.radius = rel.norm();
  if (!(leg.radius > 0.0))
    throw std::invalid_argument("Trajectory::arc: the robot is at the centre");
  leg.start_angle_rad = std::atan2(rel.y(), rel.x());
  leg.sweep_sign = sweep_deg < 0.0 ? -1.0 : 1.0;
  leg.move = Trapezoid::make(deg_to_rad(std::abs(sweep_deg)) * leg.radius, lim.max_speed_cm_per_s,
                             lim.max_accel_cm_per_s2);
  leg.turn = Trapezoid::make(0.0, 1.0, 1.0);
  leg.yaw_tangent = yaw_follows_tangent;
  leg.duration = leg.move.duration();
  push(leg);
  return *this;
}

Trajectory& Trajectory::figure_eight(double radius_cm, const MotionLimits& lim) {
  if (!(radius_cm > 0.0))
    throw std::invalid_argument("Trajectory::figure_eight: radius_cm must be > 0");
  Leg leg;
  leg.kind = Kind::kEight;
  leg.radius = radius_cm;
  leg.move =
      Trapezoid::make(4.0 * kPi * radius_cm, lim.max_speed_cm_per_s, lim.max_accel_cm_per_s2);
  leg.turn = Trapezoid::make(0.0, 1.0, 1.0);
  leg.duration = leg.move.duration();
  push(leg);
  return *this;
}

Trajectory& Trajectory::wait(double seconds) {
  if (!(seconds >= 0.0) || !std::isfinite(seconds))
    throw std::invalid_argument("Trajectory::wait: seconds must be finite and >= 0");
  Leg leg;
  leg.kind = Kind::kWait;
  leg.duration = seconds;
  push(leg);
  return *this;
}

TrajectorySample Trajectory::sample(double t_s) const {
  TrajectorySample out;
  if (legs_.empty() || t_s <= 0.0) {
    out.pose = start_;
    return out;
  }
  // Last leg starting at or before t.
  auto it = std::upper_bound(legs_.begin(), legs_.end(), t_s,
                             [](double t, const Leg& l) { return t < l.t0; });
  const Leg& leg = *std::prev(it);
  const double tau = std::min(t_s - leg.t0, leg.duration);
  const bool ended = t_s >= duration_s_;
  const double s = leg.move.position(tau);
  const double v = ended ? 0.0 : leg.move.speed(tau);
  const Eigen::Vector2d p0(leg.start.x_cm, leg.start.y_cm);
  Eigen::Vector2d p = p0;
  Eigen::Vector2d vel(0.0, 0.0);
  double yaw = leg.start.yaw_deg + leg.turn_sign * leg.turn.position(tau);
  double yaw_rate = ended ? 0.0 : leg.turn_sign * leg.turn.speed(tau);
  switch (leg.kind) {
    case Kind::kLine:
      p = p0 + leg.direction * s;
      vel = leg.direction * v;
      break;
    case Kind::kArc: {
      const double a = leg.start_angle_rad + leg.sweep_sign * s / leg.radius;
      p = leg.centre + leg.radius * Eigen::Vector2d(std::cos(a), std::sin(a));
      vel = leg.sweep_sign * v * Eigen::Vector2d(-std::sin(a), std::cos(a));
      if (leg.yaw_tangent) {
        yaw = leg.start.yaw_deg + leg.sweep_sign * rad_to_deg(s / leg.radius);
        yaw_rate = leg.sweep_sign * rad_to_deg(v / leg.radius);
      }
      break;
    }
    case Kind::kEight: {
      const double lap = 2.0 * kPi * leg.radius;
      if (s <= lap) {  // counter-clockwise around the centre above the start
        const double a = -0.5 * kPi + s / leg.radius;
        p = p0 + Eigen::Vector2d(0.0, leg.radius) +
            leg.radius * Eigen::Vector2d(std::cos(a), std::sin(a));
        vel = v * Eigen::Vector2d(-std::sin(a), std::cos(a));
      } else {  // clockwise around the centre below it
        const double a = 0.5 * kPi - (s - lap) / leg.radius;
        p = p0 - Eigen::Vector2d(0.0, leg.radius) +
            leg.radius * Eigen::Vector2d(std::cos(a), std::sin(a));
        vel = v * Eigen::Vector2d(std::sin(a), -std::cos(a));
      }
      break;
    }
    case Kind::kWait:
      break;
  }
  out.pose = {p.x(), p.y(), yaw};
  out.velocity_cm_per_s = vel;
  out.yaw_rate_deg_per_s = yaw_rate;
  return out;
}

double Trajectory::length_cm() const {
  double total = 0.0;
  for (const Leg& l : legs_) total += l.move.distance;
  return total;
}

std::vector<std::string> standard_trajectory_names() {
  return {"straight", "rotate_in_place", "circle", "figure_eight", "boundary_tour", "random_walk"};
}

namespace {

Trajectory boundary_tour(const PlayingArea& f) {
  const double in = 25.0;   // centre this far inside a line while driving along it
  const double out = 40.0;  // and this far outside it at each excursion across it
  const double x0 = f.x_min_cm + in, x1 = f.x_max_cm - in, y0 = f.y_min_cm + in,
               y1 = f.y_max_cm - in;
  const double xm = 0.5 * (f.x_min_cm + f.x_max_cm), ym = 0.5 * (f.y_min_cm + f.y_max_cm);
  const MotionLimits lim{100.0, 200.0, 120.0, 240.0};
  Trajectory t("boundary_tour", {x0, y0, 0.0});
  t.line_to({xm, y0}, 0.0, lim)
      .line_to({xm, f.y_min_cm - out}, 0.0, lim)
      .line_to({xm, y0}, 0.0, lim);
  t.line_to({x1, y0}, 0.0, lim).line_to({x1, ym}, 90.0, lim);
  t.line_to({f.x_max_cm + out, ym}, 90.0, lim).line_to({x1, ym}, 90.0, lim);
  t.line_to({x1, y1}, 90.0, lim).line_to({xm, y1}, 180.0, lim);
  t.line_to({xm, f.y_max_cm + out}, 180.0, lim).line_to({xm, y1}, 180.0, lim);
  t.line_to({x0, y1}, 180.0, lim).line_to({x0, ym}, -90.0, lim);
  t.line_to({f.x_min_cm - out, ym}, -90.0, lim).line_to({x0, ym}, -90.0, lim);
  t.line_to({x0, y0}, 0.0, lim).wait(0.3);
  return t;
}

Trajectory random_walk(std::uint64_t seed, const PlayingArea& f) {
  const double margin = f.robot_half_size_cm + 20.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(f.x_min_cm + margin, f.x_max_cm - margin);
  std::uniform_real_distribution<double> uy(f.y_min_cm + margin, f.y_max_cm - margin);
  std::uniform_real_distribution<double> uyaw(-180.0, 180.0);
  std::uniform_real_distribution<double> uspeed(40.0, 130.0);
  std::uniform_real_distribution<double> uaccel(150.0, 350.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Trajectory t("random_walk", {ux(rng), uy(rng), uyaw(rng)});
  while (t.duration_s() < 25.0) {
    const MotionLimits lim{uspeed(rng), uaccel(rng), 60.0 + 120.0 * u01(rng), 360.0};
    const double pick = u01(rng);
    if (pick < 0.1) {
      t.rotate_by(uyaw(rng), lim);
    } else if (pick < 0.15) {
      t.wait(0.2 + 0.5 * u01(rng));
    } else {
      const double yaw = uyaw(rng);  // before the point: the order gcc took as arguments
      t.line_to({ux(rng), uy(rng)}, yaw, lim);
    }
  }
  return t.wait(0.3);
}

}  // namespace

Trajectory make_trajectory(std::string_view name, std::uint64_t seed, const PlayingArea& area) {
  // Placed on the area's centre and lines: on the FIRA field the centre is (375, 275) and the
  // straight run goes from 45 cm inside one goal line to 45 cm inside the other.
  const double cx = area.centre_x_cm(), cy = area.centre_y_cm();
  if (name == "straight") {
    Trajectory t("straight", {area.x_min_cm + 45.0, cy, 0.0});
    return t.line_to({area.x_max_cm - 45.0, cy}, 0.0, {100.0, 200.0, 90.0, 180.0}).wait(0.3);
  }
  if (name == "rotate_in_place") {
    Trajectory t("rotate_in_place", {cx, cy, 0.0});
    const MotionLimits lim{0.0 + 1.0, 1.0, 180.0, 360.0};
    return t.rotate_by(720.0, lim).wait(0.3).rotate_by(-450.0, lim).wait(0.3);
  }
  if (name == "circle") {
    Trajectory t("circle", {cx, cy - 100.0, 0.0});
    return t.arc({cx, cy}, 720.0, true, {80.0, 150.0, 90.0, 180.0}).wait(0.3);
  }
  if (name == "figure_eight") {
    Trajectory t("figure_eight", {cx, cy, 30.0});
    return t.figure_eight(80.0, {80.0, 150.0, 90.0, 180.0}).wait(0.3);
  }
  if (name == "boundary_tour") return boundary_tour(area);
  if (name == "random_walk") return random_walk(seed, area);
  std::string known;
  for (const auto& n : standard_trajectory_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("make_trajectory: unknown trajectory '" + std::string(name) +
                              "' (known: " + known + ")");
}

}  // namespace omniloc::sim
