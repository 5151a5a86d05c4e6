#include "omniloc_sim/gyro.hpp"

#include <cmath>

#include "omniloc/conventions.hpp"

namespace omniloc::sim {

Gyro::Gyro(const GyroModel& model, double initial_yaw_deg, std::mt19937_64& rng)
    : model_(model), yaw_deg_(initial_yaw_deg) {
  std::normal_distribution<double> n(0.0, 1.0);
  bias_ = model.bias_offset_deg_per_s + model.bias_sigma_deg_per_s * n(rng);
  scale_ = model.scale_error_sigma * n(rng);
}

void Gyro::step(double true_dyaw_deg, double dt_s, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  // Angle random walk: integrated white rate noise has sigma ARW * sqrt(dt) per step.
  const double noise_deg =
      model_.arw_deg_per_sqrt_s > 0.0 ? model_.arw_deg_per_sqrt_s * std::sqrt(dt_s) * n(rng) : 0.0;
  yaw_deg_ += true_dyaw_deg * (1.0 + scale_) + bias_ * dt_s + noise_deg;
  if (model_.bias_walk_deg_per_s_per_sqrt_s > 0.0)
    bias_ += model_.bias_walk_deg_per_s_per_sqrt_s * std::sqrt(dt_s) * n(rng);
}

double Gyro::report(double raw_yaw_deg) const {
  const double q = model_.quantum_deg;
  const double quantised = q > 0.0 ? std::round(raw_yaw_deg / q) * q : raw_yaw_deg;
  return wrap_deg(quantised);
}

}  // namespace omniloc::sim
