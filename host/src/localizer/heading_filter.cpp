// The alpha-beta image-heading filter (heading_filter.hpp).
#include "omniloc/heading_filter.hpp"

#include <algorithm>

#include "omniloc/conventions.hpp"

namespace omniloc {

double HeadingFilter::recent_gap_s(double t_ms) const {
  if (!last_fix_ms_) return 0.0;
  const double dt_s = (t_ms - *last_fix_ms_) / 1000.0;
  return dt_s > 0.0 && dt_s <= config_.max_rate_gap_s ? dt_s : 0.0;
}

double HeadingFilter::predict(double t_ms, double gyro_yaw_deg) const {
  const double dt_s = recent_gap_s(t_ms);
  return gyro_yaw_deg + (dt_s > 0.0 ? rate_deg_per_s_ * dt_s : 0.0);
}

double HeadingFilter::correct(double t_ms, double predicted_yaw_deg, double measured_yaw_deg) {
  const double residual = angle_diff_deg(measured_yaw_deg, predicted_yaw_deg);
  if (const double dt_s = recent_gap_s(t_ms); dt_s > 0.0) {
    rate_deg_per_s_ += config_.rate_gain * residual / dt_s;
    rate_deg_per_s_ =
        std::clamp(rate_deg_per_s_, -config_.rate_max_deg_per_s, config_.rate_max_deg_per_s);
  }
  last_fix_ms_ = t_ms;
  return wrap_deg(predicted_yaw_deg + config_.gain * residual);
}

}  // namespace omniloc
