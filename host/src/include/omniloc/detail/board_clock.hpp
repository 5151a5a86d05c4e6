// The board's clock against the host's: each encoder window carries the board's time (its cycle
// counter over clock_hz, unwrapped by BoardSession) and arrives on the host some time after it
// ended. The arrival is the window's host time plus the USB and driver latency, which is never
// negative, jitters by a fraction of a millisecond and now and then grows by tens of milliseconds
// (a late burst: the host or the bridge stalled). So the host time of board time b is the LOWER
// ENVELOPE of the arrivals: host(b) = b + offset + drift * (b - b_ref). The model keeps the minimum
// of (arrival - board) per bucket of board time (1 s), over a sliding span (60 s), and fits a line
// through those minima robustly (Theil-Sen: the median of the pairwise slopes, then the median
// intercept), so a burst that spoils a few buckets does not move it. A board reset (board time goes
// back, or every window for 0.5 s of host time arrives far off the line) starts a new epoch; a
// reconnect does not (the board's time runs on, and the line with it). Behaviour and figures:
// docs/DAEMON.md "Board clock". A value type: no threads, no global state.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>

namespace omniloc {

struct BoardClockConfig {
  double bucket_ms = 1000.0;      ///< board time per bucket (one minimum each)
  int span_buckets = 60;          ///< buckets the fit spans (sliding)
  int min_fit_buckets = 3;        ///< fewer: offset only (drift 0), flagged not converged
  int converged_buckets = 5;      ///< this many: converged
  double reset_back_ms = 1.0;     ///< board time going back by more than this: a reset
  double jump_ms = 100.0;         ///< every arrival this far off the line ...
  double jump_hold_ms = 500.0;    ///< ... for this long (host time): re-anchor (new epoch). A queue
                                  ///< of stale windows read at once after a reconnect is far above
                                  ///< the line too, but arrives within milliseconds
  double max_drift_ppm = 1000.0;  ///< a fitted drift beyond this is clamped (a crystal is < 100)
  double min_uncertainty_ms = 0.05;  ///< floor of the stated uncertainty once converged
  /// Throws std::invalid_argument naming the field and the value.
  void validate() const;
};

/// What the model says about one board time.
struct BoardClockEstimate {
  double host_ms = 0.0;         ///< host-clock time of the board time
  double uncertainty_ms = 0.0;  ///< one sigma, from the fit's scatter and the extrapolation
  double offset_ms = 0.0;       ///< host - board at the newest board time seen
  double drift_ppm = 0.0;       ///< (host rate / board rate - 1) * 1e6
  std::uint32_t epoch = 0;      ///< 0 before the first window, +1 at each (re-)anchoring
  bool converged = false;       ///< converged_buckets buckets in the fit
};

class BoardClockModel {
 public:
  explicit BoardClockModel(const BoardClockConfig& config = {});

  /// One window: its board time and the host time it arrived. Returns the estimate for it (the
  /// host time is never later than its arrival). Windows must come in board-time order within an
  /// epoch; a board time going back is a board reset.
  BoardClockEstimate add(double board_ms, double arrival_host_ms);
  /// The estimate for any board time of the current epoch (after add() of the windows known).
  [[nodiscard]] BoardClockEstimate map(double board_ms) const;
  /// The newest add()'s estimate (epoch 0 and zeros before the first).
  [[nodiscard]] const BoardClockEstimate& last() const { return last_; }
  [[nodiscard]] std::uint64_t resets() const { return epoch_ > 0 ? epoch_ - 1 : 0; }
  /// The caller knows the board restarted (continued_board_ms said so): the next add() starts a
  /// new epoch.
  void restart() { restart_ = true; }
  /// "offset +12.345 ms, drift +50.1 ppm, +-0.02 ms" for status lines.
  [[nodiscard]] std::string describe() const;

 private:
  struct Bucket {
    std::int64_t index = 0;  // floor(board_ms / bucket_ms)
    double board_ms = 0.0;   // of the minimum
    double min_d_ms = 0.0;   // min(arrival - board)
  };
  void reanchor(double board_ms);
  void refit();
  [[nodiscard]] double line_d(double board_ms) const {
    return intercept_ms_ + slope_ * (board_ms - ref_board_ms_);
  }

  BoardClockConfig config_;
  std::deque<Bucket> buckets_;  // closed and the open one (last)
  std::uint32_t epoch_ = 0;
  double last_board_ms_ = 0.0;
  bool have_line_ = false;
  double ref_board_ms_ = 0.0, intercept_ms_ = 0.0, slope_ = 0.0;
  double scatter_ms_ = 0.0, slope_sigma_ = 0.0;
  int fit_buckets_ = 0;
  bool restart_ = false;
  bool off_line_ = false;
  double off_line_since_ms_ = 0.0;
  double first_board_ms_ = 0.0;
  BoardClockEstimate last_;
};

/// Where a board's time stood at a window: its raw 32-bit cycle counter, the same instant on a
/// scale that runs on across sessions (ms), and when the window arrived (host ms).
struct BoardTimeMark {
  std::uint32_t raw_cycles = 0;
  double board_ms = 0.0;
  double arrival_ms = 0.0;
  double clock_hz = 0.0;
};

/// A new session's window on the previous session's board-time scale: the counter's advance since
/// `last` (its wraps counted from the host time between the arrivals), or nullopt when that
/// advance disagrees with the host time by more than 100 ms + 0.2 % (the board restarted its
/// counter while the link was down) or the clock differs (another board). A session's own board
/// times (BoardSession) start at 0, so the daemon keeps one scale with this.
[[nodiscard]] std::optional<double> continued_board_ms(const BoardTimeMark& last,
                                                       std::uint32_t raw_cycles, double clock_hz,
                                                       double arrival_ms);

}  // namespace omniloc
