#include "omniloc/robot_config.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <stdexcept>

#include "omniloc/conventions.hpp"
#include "omniloc/detail/config_reader.hpp"

namespace omniloc {

using config::Need;

namespace {

using Jacobian = Eigen::Matrix<double, Eigen::Dynamic, 3>;

// The shorthand's geometry keys: written only when there is no "wheels" list, and refused beside
// one.
constexpr const char* kShorthandKeys[] = {"wheel_radius_cm", "center_to_wheel_cm",
                                          "motor_angle_deg", "gear_ratio", "counts_per_rev"};

bool is_shorthand_key(const std::string& name) {
  for (const char* k : kShorthandKeys)
    if (name == k) return true;
  return false;
}

template <class M>
config::Key<RobotConfig> shorthand(std::string name, M RobotConfig::*member) {
  config::Key<RobotConfig> k = config::key(std::move(name), member, Need::kRequired);
  k.write = [write = k.write](const RobotConfig& c) -> std::optional<config::Json> {
    if (!c.wheels.empty()) return std::nullopt;
    return write(c);
  };
  return k;
}

const config::KeyTable<WheelConfig>& wheel_keys() {
  using config::key;
  static const config::KeyTable<WheelConfig> table = {
      key("mount_angle_deg", &WheelConfig::mount_angle_deg, Need::kRequired),
      key("distance_cm", &WheelConfig::distance_cm, Need::kRequired),
      key("drive_angle_deg", &WheelConfig::drive_angle_deg, Need::kRequired),
      key("wheel_radius_cm", &WheelConfig::wheel_radius_cm, Need::kRequired),
      key("gear_ratio", &WheelConfig::gear_ratio, Need::kRequired),
      key("counts_per_rev", &WheelConfig::counts_per_rev, Need::kRequired),
  };
  return table;
}

config::Key<RobotConfig> wheels_key() {
  config::Key<RobotConfig> k;
  k.name = "wheels";
  k.need = Need::kRequired;
  k.read = [](const config::Node& n, RobotConfig& out) {
    const std::size_t size = n.expect_array();
    if (size == 0) n.fail("must list 3 or 4 wheels");  // an empty list would read as the shorthand
    out.wheels.assign(size, WheelConfig{});
    for (std::size_t i = 0; i < size; ++i) config::read_keys(n[i], wheel_keys(), out.wheels[i]);
  };
  k.write = [](const RobotConfig& c) -> std::optional<config::Json> {
    if (c.wheels.empty()) return std::nullopt;
    config::Json out = config::Json::array();
    for (const WheelConfig& w : c.wheels) out.push_back(config::write_keys(w, wheel_keys()));
    return out;
  };
  k.help = "the wheels one by one (3 or 4), instead of the symmetric shorthand";
  return k;
}

// Upper bounds far beyond any robot, so that a typo (1e9) or garbage (1e-300) is refused before it
// turns into a divided-by-nearly-zero window or an overflowing count.
constexpr double kMaxRobotCm = 1000.0;
constexpr double kMaxWheelRadiusCm = 100.0;
constexpr double kMaxGearRatio = 10000.0;
constexpr int kMaxCountsPerRev = 1000000;

void validate_wheel(const WheelConfig& w, const config::Origin& at) {
  using config::require;
  const auto angle = [&](double v, const char* field) {
    require(std::isfinite(v) && std::abs(v) <= 360.0, at / field,
            "must be an angle within [-360, 360] degrees", v);
  };
  angle(w.mount_angle_deg, "mount_angle_deg");
  require(std::isfinite(w.distance_cm) && w.distance_cm >= 0.0, at / "distance_cm", "must be >= 0",
          w.distance_cm);
  require(w.distance_cm <= kMaxRobotCm, at / "distance_cm",
          "must be at most 1000 cm (a robot, not a field)", w.distance_cm);
  angle(w.drive_angle_deg, "drive_angle_deg");
  require(std::isfinite(w.wheel_radius_cm) && w.wheel_radius_cm > 0.0, at / "wheel_radius_cm",
          "must be > 0", w.wheel_radius_cm);
  require(w.wheel_radius_cm <= kMaxWheelRadiusCm, at / "wheel_radius_cm", "must be at most 100 cm",
          w.wheel_radius_cm);
  require(std::isfinite(w.gear_ratio) && w.gear_ratio > 0.0, at / "gear_ratio", "must be > 0",
          w.gear_ratio);
  require(w.gear_ratio <= kMaxGearRatio, at / "gear_ratio", "must be at most 10000", w.gear_ratio);
  require(w.counts_per_rev > 0, at / "counts_per_rev",
          "must be a positive number of encoder cycles per motor turn", w.counts_per_rev);
  require(w.counts_per_rev <= kMaxCountsPerRev, at / "counts_per_rev", "must be at most 1000000",
          w.counts_per_rev);
}

// Full column rank 3: every body motion (dx, dy, dtheta) moves some wheel. The columns are cm and
// cm per radian; a smallest singular value below 1e-6 of the largest is rounding, not geometry.
void validate_rank(const RobotConfig& c, const config::Origin& at) {
  const Jacobian j = wheel_jacobian(c);
  const Eigen::JacobiSVD<Jacobian> svd(j);
  const Eigen::Vector3d sv = svd.singularValues();
  const int rank = (sv.array() > 1e-6 * sv(0)).count();
  if (rank < 3)
    at.fail("degenerate wheel layout: the wheel Jacobian has rank " + std::to_string(rank) +
                ", not 3, so some motion of the robot moves no wheel (e.g. every drive direction "
                "parallel, "
                "or every wheel driving along its own radius)",
            "singular values " + config::show({sv(0), sv(1), sv(2)}));
}

}  // namespace

const config::KeyTable<RobotConfig>& robot_config_keys() {
  using config::key;
  static const config::KeyTable<RobotConfig> table = {
      // --- required: the recording contract's robot block (the shorthand), or "wheels" ---
      shorthand("wheel_radius_cm", &RobotConfig::wheel_radius_cm),
      shorthand("center_to_wheel_cm", &RobotConfig::center_to_wheel_cm),
      shorthand("motor_angle_deg", &RobotConfig::motor_angle_deg),
      shorthand("gear_ratio", &RobotConfig::gear_ratio),
      shorthand("counts_per_rev", &RobotConfig::counts_per_rev),
      key("decoding", &RobotConfig::decoding, Need::kRequired),
      // --- optional ---
      key("slip_threshold_cm_per_s", &RobotConfig::slip_threshold_cm_per_s),
      key("wheel_noise_cm_per_sqrt_cm", &RobotConfig::wheel_noise_cm_per_sqrt_cm),
      key("max_accel_cm_per_s2", &RobotConfig::max_accel_cm_per_s2),
      key("max_yaw_rate_deg_per_s", &RobotConfig::max_yaw_rate_deg_per_s),
      key("odometry_noise_fraction", &RobotConfig::odometry_noise_fraction),
      key("gyro_arw_deg_per_sqrt_s", &RobotConfig::gyro_arw_deg_per_sqrt_s),
      wheels_key(),
  };
  return table;
}

int wheel_count(const RobotConfig& c) {
  return c.wheels.empty() ? 4 : static_cast<int>(c.wheels.size());
}

std::vector<WheelConfig> wheel_layout(const RobotConfig& c) {
  if (!c.wheels.empty()) return c.wheels;
  const Eigen::Matrix<double, 4, 3> j = wheel_jacobian(c.motor_angle_deg, c.center_to_wheel_cm);
  const std::vector<Eigen::Vector2d> p = wheel_positions_cm(c);
  std::vector<WheelConfig> out(4);
  for (int i = 0; i < 4; ++i) {
    WheelConfig& w = out[static_cast<std::size_t>(i)];
    w.mount_angle_deg = rad_to_deg(
        std::atan2(p[static_cast<std::size_t>(i)].y(), p[static_cast<std::size_t>(i)].x()));
    w.distance_cm = c.center_to_wheel_cm;
    w.drive_angle_deg = rad_to_deg(std::atan2(j(i, 1), j(i, 0)));
    w.wheel_radius_cm = c.wheel_radius_cm;
    w.gear_ratio = c.gear_ratio;
    w.counts_per_rev = c.counts_per_rev;
  }
  return out;
}

std::vector<Eigen::Vector2d> wheel_positions_cm(const RobotConfig& c) {
  std::vector<Eigen::Vector2d> out;
  if (c.wheels.empty()) {
    // Row i of eq. (9) is the wheel's drive direction u and R: the contact point p satisfies
    // (omega x p) . u = omega R, i.e. p = R (u_y, -u_x).
    const Eigen::Matrix<double, 4, 3> j = wheel_jacobian(c.motor_angle_deg, c.center_to_wheel_cm);
    for (int i = 0; i < 4; ++i)
      out.push_back(c.center_to_wheel_cm * Eigen::Vector2d(j(i, 1), -j(i, 0)));
    return out;
  }
  for (const WheelConfig& w : c.wheels) {
    const double a = deg_to_rad(w.mount_angle_deg);
    out.push_back(w.distance_cm * Eigen::Vector2d(std::cos(a), std::sin(a)));
  }
  return out;
}

Eigen::Matrix<double, Eigen::Dynamic, 3> wheel_jacobian(const RobotConfig& c) {
  if (c.wheels.empty()) return wheel_jacobian(c.motor_angle_deg, c.center_to_wheel_cm);
  Jacobian j(static_cast<Eigen::Index>(c.wheels.size()), 3);
  for (std::size_t i = 0; i < c.wheels.size(); ++i) {
    const WheelConfig& w = c.wheels[i];
    const double drive = deg_to_rad(w.drive_angle_deg);
    const double mount = deg_to_rad(w.mount_angle_deg);
    const auto r = static_cast<Eigen::Index>(i);
    j(r, 0) = std::cos(drive);
    j(r, 1) = std::sin(drive);
    j(r, 2) = w.distance_cm * std::sin(drive - mount);
  }
  return j;
}

double counts_per_wheel_turn(const RobotConfig& c, int wheel) {
  if (wheel < 0 || wheel >= wheel_count(c))
    throw std::out_of_range("counts_per_wheel_turn: wheel index " + std::to_string(wheel) +
                            " of a robot with " + std::to_string(wheel_count(c)) + " wheels");
  if (c.wheels.empty()) return static_cast<double>(c.counts_per_rev) * c.decoding * c.gear_ratio;
  const WheelConfig& w = c.wheels[static_cast<std::size_t>(wheel)];
  return static_cast<double>(w.counts_per_rev) * c.decoding * w.gear_ratio;
}

double cm_per_count(const RobotConfig& c, int wheel) {
  const double r = c.wheels.empty() ? c.wheel_radius_cm
                                    : c.wheels.at(static_cast<std::size_t>(wheel)).wheel_radius_cm;
  return 2.0 * kPi * r / counts_per_wheel_turn(c, wheel);
}

namespace {
template <class F>
double shared_value(const RobotConfig& c, F per_wheel, const char* what) {
  const double first = per_wheel(c, 0);
  for (int i = 1; i < wheel_count(c); ++i)
    if (per_wheel(c, i) != first)
      throw std::logic_error(std::string(what) +
                             ": the wheels differ; ask for one wheel (index 0.." +
                             std::to_string(wheel_count(c) - 1) + ")");
  return first;
}
}  // namespace

double counts_per_wheel_turn(const RobotConfig& c) {
  return shared_value(
      c, [](const RobotConfig& r, int i) { return counts_per_wheel_turn(r, i); },
      "counts_per_wheel_turn");
}

double cm_per_count(const RobotConfig& c) {
  return shared_value(
      c, [](const RobotConfig& r, int i) { return cm_per_count(r, i); }, "cm_per_count");
}

std::optional<std::string> board_channel_mismatch(int board_channels, int n) {
  if (board_channels == n) return std::nullopt;
  return "the board counts " + std::to_string(board_channels) +
         " encoder channels but the robot config has " + std::to_string(n) +
         " wheels: load the bitstream built for " + std::to_string(n) +
         " channels (make bitstream CHANNELS=" + std::to_string(n) +
         "), or the robot file of this robot";
}

void RobotConfig::validate(const config::Origin& at) const {
  using config::require;
  const auto positive = [&](double v, const char* field) {
    require(std::isfinite(v) && v > 0.0, at / field, "must be > 0", v);
  };
  if (wheels.empty()) {
    positive(wheel_radius_cm, "wheel_radius_cm");
    positive(center_to_wheel_cm, "center_to_wheel_cm");
    // Equation (9) needs both sin and cos of theta_m non-zero, or the 4x3 matrix loses rank.
    require(std::isfinite(motor_angle_deg) && motor_angle_deg > 0.0 && motor_angle_deg < 90.0,
            at / "motor_angle_deg",
            "must be strictly between 0 and 90 degrees, or equation (9) loses rank",
            motor_angle_deg);
    positive(gear_ratio, "gear_ratio");
    require(counts_per_rev > 0, at / "counts_per_rev",
            "must be a positive number of encoder cycles per motor turn", counts_per_rev);
    require(wheel_radius_cm <= kMaxWheelRadiusCm, at / "wheel_radius_cm", "must be at most 100 cm",
            wheel_radius_cm);
    require(center_to_wheel_cm <= kMaxRobotCm, at / "center_to_wheel_cm",
            "must be at most 1000 cm (a robot, not a field)", center_to_wheel_cm);
    require(gear_ratio <= kMaxGearRatio, at / "gear_ratio", "must be at most 10000", gear_ratio);
    require(counts_per_rev <= kMaxCountsPerRev, at / "counts_per_rev", "must be at most 1000000",
            counts_per_rev);
  } else {
    const config::Origin list = at / "wheels";
    require(wheels.size() >= static_cast<std::size_t>(kMinWheels) &&
                wheels.size() <= static_cast<std::size_t>(kMaxWheels),
            list, "must list 3 or 4 wheels (the board counts 3 or 4 encoder channels)",
            static_cast<double>(wheels.size()));
    for (std::size_t i = 0; i < wheels.size(); ++i) validate_wheel(wheels[i], list[i]);
    validate_rank(*this, list);
  }
  require(decoding == 1 || decoding == 2 || decoding == 4, at / "decoding",
          "unknown quadrature decoding mode: must be 1, 2 or 4", decoding);
  const auto in_range = [&](double v, const char* field, double lo, double hi, const char* why) {
    require(std::isfinite(v) && v >= lo && v <= hi, at / field, why, v);
  };
  positive(slip_threshold_cm_per_s, "slip_threshold_cm_per_s");
  in_range(slip_threshold_cm_per_s, "slip_threshold_cm_per_s", 0.0, 10000.0,
           "must be at most 10000 cm/s");
  in_range(wheel_noise_cm_per_sqrt_cm, "wheel_noise_cm_per_sqrt_cm", 0.0, 10.0,
           "must be in [0, 10]");
  positive(max_accel_cm_per_s2, "max_accel_cm_per_s2");
  in_range(max_accel_cm_per_s2, "max_accel_cm_per_s2", 0.0, 1e5,
           "must be at most 1e5 cm/s^2 (10 g)");
  in_range(odometry_noise_fraction, "odometry_noise_fraction", 0.0, 1.0, "must be in [0, 1]");
  in_range(gyro_arw_deg_per_sqrt_s, "gyro_arw_deg_per_sqrt_s", 0.0, 100.0, "must be in [0, 100]");
  // Bounded both ways: it sizes the largest gyro jump a window may show (times 10 ms); below
  // 10 deg/s a robot's ordinary turns would be dropped, above the gyro's full scale nothing would.
  in_range(max_yaw_rate_deg_per_s, "max_yaw_rate_deg_per_s", 10.0, 36000.0,
           "must be in [10, 36000] deg/s");
}

void validate_robot_config(const RobotConfig& c, const std::string& source) {
  c.validate(source);
}

RobotConfig parse_robot_config(const config::Node& node) {
  node.expect_object();
  // The shorthand's geometry keys are required without "wheels" and refused beside it.
  const bool listed = node.has("wheels");
  config::KeyTable<RobotConfig> table = robot_config_keys();
  for (auto& k : table) {
    if (k.name == "wheels") k.need = Need::kOptional;
    if (listed && is_shorthand_key(k.name)) {
      if (node.has(k.name))
        (node / k.name).fail("not allowed beside \"wheels\": give it for each wheel");
      k.need = Need::kOptional;
    }
  }
  RobotConfig c;
  config::read_keys(node, table, c);
  c.validate(node.origin());
  return c;
}

RobotConfig load_robot_config(const std::filesystem::path& path) {
  return parse_robot_config(config::parse_json_file(path).root());
}

RobotConfig load_named_robot_config(const std::string& name_or_path) {
  return load_robot_config(resolve_data_file("robots", name_or_path));
}

}  // namespace omniloc
