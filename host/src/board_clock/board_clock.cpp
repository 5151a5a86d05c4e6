// Board-to-host clock model (board_clock.hpp): per-bucket minima of (arrival - board), Theil-Sen.
#include "omniloc/detail/board_clock.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace omniloc {
namespace {

double median(std::vector<double>& v) {
  const std::size_t n = v.size();
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2), v.end());
  const double hi = v[n / 2];
  if (n % 2 == 1) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2)));
}

void require(bool ok, const char* field, double value) {
  if (!ok)
    throw std::invalid_argument(std::string("board clock config: ") + field +
                                " out of range (got " + std::to_string(value) + ")");
}

}  // namespace

void BoardClockConfig::validate() const {
  require(std::isfinite(bucket_ms) && bucket_ms >= 10.0 && bucket_ms <= 60'000.0,
          "bucket_ms (10 .. 60000)", bucket_ms);
  require(span_buckets >= 3 && span_buckets <= 10'000, "span_buckets (3 .. 10000)", span_buckets);
  require(min_fit_buckets >= 2 && min_fit_buckets <= span_buckets,
          "min_fit_buckets (2 .. span_buckets)", min_fit_buckets);
  require(converged_buckets >= min_fit_buckets && converged_buckets <= span_buckets,
          "converged_buckets (min_fit_buckets .. span_buckets)", converged_buckets);
  require(std::isfinite(reset_back_ms) && reset_back_ms >= 0.0, "reset_back_ms (>= 0)",
          reset_back_ms);
  require(std::isfinite(jump_ms) && jump_ms > 0.0, "jump_ms (> 0)", jump_ms);
  require(std::isfinite(jump_hold_ms) && jump_hold_ms >= 0.0, "jump_hold_ms (>= 0)", jump_hold_ms);
  require(std::isfinite(max_drift_ppm) && max_drift_ppm > 0.0 && max_drift_ppm <= 1e5,
          "max_drift_ppm (0 .. 1e5]", max_drift_ppm);
  require(std::isfinite(min_uncertainty_ms) && min_uncertainty_ms >= 0.0,
          "min_uncertainty_ms (>= 0)", min_uncertainty_ms);
}

BoardClockModel::BoardClockModel(const BoardClockConfig& config) : config_(config) {
  config_.validate();
}

void BoardClockModel::reanchor(double board_ms) {
  ++epoch_;
  buckets_.clear();
  have_line_ = false;
  slope_ = 0.0;
  scatter_ms_ = slope_sigma_ = 0.0;
  fit_buckets_ = 0;
  off_line_ = false;
  first_board_ms_ = board_ms;
}

void BoardClockModel::refit() {
  // Closed buckets only: the open one's minimum is still falling.
  const std::size_t n = buckets_.size() > 0 ? buckets_.size() - 1 : 0;
  fit_buckets_ = static_cast<int>(n);
  if (fit_buckets_ < config_.min_fit_buckets) return;  // offset-only, kept up by add()
  std::vector<double> slopes;
  slopes.reserve(n * (n - 1) / 2);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      slopes.push_back((buckets_[j].min_d_ms - buckets_[i].min_d_ms) /
                       (buckets_[j].board_ms - buckets_[i].board_ms));
  const double max_slope = config_.max_drift_ppm * 1e-6;
  slope_ = std::clamp(median(slopes), -max_slope, max_slope);
  ref_board_ms_ = buckets_[n - 1].board_ms;
  std::vector<double> icpt(n), mean_b(1, 0.0);
  double sum_b = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    icpt[i] = buckets_[i].min_d_ms - slope_ * (buckets_[i].board_ms - ref_board_ms_);
    sum_b += buckets_[i].board_ms;
  }
  std::vector<double> work = icpt;
  intercept_ms_ = median(work);
  for (double& r : work = icpt) r = std::abs(r - intercept_ms_);
  const double mad = median(work);
  scatter_ms_ = 1.4826 * mad;
  const double mb = sum_b / static_cast<double>(n);
  double var_b = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    var_b += (buckets_[i].board_ms - mb) * (buckets_[i].board_ms - mb);
  var_b /= static_cast<double>(n);
  // Medians are ~1.25 times less efficient than means on normal scatter.
  slope_sigma_ = var_b > 0 ? 1.25 * scatter_ms_ / std::sqrt(static_cast<double>(n) * var_b) : 0.0;
  have_line_ = true;
}

BoardClockEstimate BoardClockModel::map(double board_ms) const {
  BoardClockEstimate e;
  e.epoch = epoch_;
  if (epoch_ == 0) {
    e.host_ms = board_ms;
    return e;
  }
  e.host_ms = board_ms + line_d(board_ms);
  e.offset_ms = line_d(last_board_ms_);
  e.drift_ppm = slope_ * 1e6;
  e.converged = fit_buckets_ >= config_.converged_buckets;
  if (fit_buckets_ >= config_.min_fit_buckets) {
    const double n = static_cast<double>(fit_buckets_);
    const double si = 1.25 * scatter_ms_ / std::sqrt(n);
    const double ss = slope_sigma_ * (board_ms - ref_board_ms_);
    e.uncertainty_ms = std::max(config_.min_uncertainty_ms, std::sqrt(si * si + ss * ss));
  } else {
    // Offset only: a millisecond of jitter, and a drift not yet known (a crystal: up to 100 ppm).
    e.uncertainty_ms = std::max(1.0, std::abs(board_ms - first_board_ms_) * 100e-6);
  }
  return e;
}

BoardClockEstimate BoardClockModel::add(double board_ms, double arrival_host_ms) {
  if (epoch_ == 0 || restart_ || board_ms < last_board_ms_ - config_.reset_back_ms)
    reanchor(board_ms);
  restart_ = false;
  const double d = arrival_host_ms - board_ms;
  if (fit_buckets_ >= config_.min_fit_buckets) {  // before: the minimum is still being found
    const double resid = d - line_d(board_ms);
    if (std::abs(resid) > config_.jump_ms) {
      // Far below the line cannot be latency (it is never negative): the board time jumped ahead.
      // Far above for a while (not a queue read at once): the board restarted its time.
      if (!off_line_) {
        off_line_ = true;
        off_line_since_ms_ = arrival_host_ms;
      }
      if (resid < -config_.jump_ms || arrival_host_ms - off_line_since_ms_ >= config_.jump_hold_ms)
        reanchor(board_ms);
    } else {
      off_line_ = false;
    }
  }
  last_board_ms_ = board_ms;
  const auto index = static_cast<std::int64_t>(std::floor(board_ms / config_.bucket_ms));
  if (buckets_.empty() || index != buckets_.back().index) {
    buckets_.push_back({index, board_ms, d});
    while (buckets_.front().index <= index - config_.span_buckets) buckets_.pop_front();
    refit();
  } else if (d < buckets_.back().min_d_ms) {
    buckets_.back().min_d_ms = d;
    buckets_.back().board_ms = board_ms;
  }
  if (fit_buckets_ < config_.min_fit_buckets) {
    // Offset only: the lowest arrival so far.
    double lo = d;
    for (const Bucket& b : buckets_) lo = std::min(lo, b.min_d_ms);
    intercept_ms_ = lo;
    slope_ = 0.0;
    ref_board_ms_ = board_ms;
  }
  last_ = map(board_ms);
  last_.host_ms =
      std::min(last_.host_ms, arrival_host_ms);  // a window cannot have ended after it arrived
  return last_;
}

std::optional<double> continued_board_ms(const BoardTimeMark& last, std::uint32_t raw_cycles,
                                         double clock_hz, double arrival_ms) {
  if (!(clock_hz > 0.0) || std::abs(clock_hz - last.clock_hz) > 1e-9 * clock_hz)
    return std::nullopt;
  const double wrap_ms = 4294967296.0 / clock_hz * 1000.0;
  const double advance_ms =
      static_cast<double>(static_cast<std::uint32_t>(raw_cycles - last.raw_cycles)) / clock_hz *
      1000.0;
  const double gap_ms = arrival_ms - last.arrival_ms;
  const double wraps = std::max(0.0, std::round((gap_ms - advance_ms) / wrap_ms));
  const double elapsed_ms = advance_ms + wraps * wrap_ms;
  if (std::abs(elapsed_ms - gap_ms) > 100.0 + 2e-3 * std::abs(gap_ms)) return std::nullopt;
  return last.board_ms + elapsed_ms;
}

std::string BoardClockModel::describe() const {
  char buf[96];
  std::snprintf(buf, sizeof buf, "offset %+.3f ms, drift %+.1f ppm, +-%.2f ms%s", last_.offset_ms,
                last_.drift_ppm, last_.uncertainty_ms, last_.converged ? "" : " (settling)");
  return buf;
}

}  // namespace omniloc
