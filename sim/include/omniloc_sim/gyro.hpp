// A MEMS yaw gyroscope that integrates its own rate and reports the yaw angle, as the robot's IMU
// does: white rate noise (angle random walk), a residual bias left after start-up calibration that
// drifts as a random walk, a scale-factor error, and quantisation of the reported angle.
#pragma once

#include <random>

namespace omniloc::sim {

struct GyroModel {
  double arw_deg_per_sqrt_s = 0.005;               ///< white rate noise (0.3 deg/sqrt(h))
  double bias_sigma_deg_per_s = 0.01;              ///< residual bias after calibration, drawn once
  double bias_walk_deg_per_s_per_sqrt_s = 0.0005;  ///< bias drift (random walk of the bias)
  double scale_error_sigma = 0.002;                ///< scale-factor error, drawn once (0.2 %)
  double quantum_deg = 0.01;                       ///< resolution of the reported angle
  double bias_offset_deg_per_s = 0.0;              ///< a known extra bias (e.g. a bad calibration)

  /// Only the quantisation of the reported angle.
  [[nodiscard]] static GyroModel noise_free() { return {0.0, 0.0, 0.0, 0.0, 0.01}; }
};

class Gyro {
 public:
  /// The gyro is aligned with the field at start-up: it reads `initial_yaw_deg`.
  Gyro(const GyroModel& model, double initial_yaw_deg, std::mt19937_64& rng);
  /// Integrates a true yaw change over dt_s.
  void step(double true_dyaw_deg, double dt_s, std::mt19937_64& rng);
  /// Internal, unquantised, unwrapped integrated yaw.
  [[nodiscard]] double raw_yaw_deg() const { return yaw_deg_; }
  /// What the gyro reports for an internal value: quantised and wrapped into (-180, 180].
  [[nodiscard]] double report(double raw_yaw_deg) const;
  [[nodiscard]] double bias_deg_per_s() const { return bias_; }
  [[nodiscard]] double scale_error() const { return scale_; }

 private:
  GyroModel model_;
  double yaw_deg_;
  double bias_;
  double scale_;
};

}  // namespace omniloc::sim
