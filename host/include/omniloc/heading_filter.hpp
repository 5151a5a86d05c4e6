// The image-heading filter of the localizer (LocalizerMode::kFull, docs/LOCALIZER.md): an
// alpha-beta filter on the gyro's heading error. A MEMS gyro's bias drifts (tenths of a degree a
// minute, more after a bad start-up calibration); every so often the image gives the heading
// (estimate_yaw), and the filter
//   predicts   the heading as the gyro heading plus the learnt drift rate times the time since
//              the last fix (only when that fix is recent: within max_rate_gap_s),
//   corrects   by `gain` of the residual (image - predicted), and
//   learns     the rate by `rate_gain` of the residual per second since the last fix, clamped
//              to +- rate_max_deg_per_s.
// It knows nothing of images: the caller measures the heading around predict()'s answer and hands
// the measurement to correct(). Time is the board's (ms), angles degrees.
#pragma once

#include <optional>

namespace omniloc {

struct HeadingFilterConfig {
  double gain = 0.05;               ///< alpha: share of the residual applied at a fix, (0, 1]
  double rate_gain = 0.005;         ///< beta: share of residual / dt added to the rate, [0, 1)
  double rate_max_deg_per_s = 2.0;  ///< the learnt rate stays within +- this
  double max_rate_gap_s = 1.0;      ///< the rate is used and learnt only between fixes this close
};

class HeadingFilter {
 public:
  explicit HeadingFilter(const HeadingFilterConfig& config) : config_(config) {}

  /// The heading at t_ms predicted from the gyro's: gyro + rate * (t - last fix) when the last fix
  /// is recent, else the gyro heading itself.
  [[nodiscard]] double predict(double t_ms, double gyro_yaw_deg) const;

  /// A heading measured from the image at t_ms around predicted_yaw_deg (predict()'s answer for
  /// the same t_ms): learns the rate (recent fixes only), records the fix time, and returns the
  /// corrected heading, wrapped into (-180, 180].
  double correct(double t_ms, double predicted_yaw_deg, double measured_yaw_deg);

  /// The drift learnt so far (deg/s added to the gyro heading; 0 until learnt).
  [[nodiscard]] double rate_deg_per_s() const { return rate_deg_per_s_; }

 private:
  /// Seconds since the last fix when it is recent enough to use the rate, else 0 (none yet: 0).
  [[nodiscard]] double recent_gap_s(double t_ms) const;

  HeadingFilterConfig config_;
  double rate_deg_per_s_ = 0.0;
  std::optional<double> last_fix_ms_;
};

}  // namespace omniloc
