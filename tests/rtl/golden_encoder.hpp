// Golden models of the encoder core, written from the specification in docs/RTL.md and
// independent of the RTL's structure: the glitch filter works on whole pin waveforms (segments),
// the decoder on a table of the forward quadrature cycle, the windows on event times.
#pragma once

#include <cstdint>
#include <vector>

namespace omniloc::rtl_golden {

/// A pin level change: `level` is sampled from clock edge `edge` on.
struct Change {
  std::uint64_t edge = 0;
  bool level = false;
};

/// Glitch filter with synchronizer. The pin holds `initial` from `first_edge` (the first edge
/// after reset) until its first change (all changes are at edges > first_edge + 1, in time
/// order, each a real change of level). Returns the output's changes, each stamped with the edge
/// after which out_o shows it: a level held for at least max(len, 1) edges passes, max(len,1)+1
/// edges after it was first sampled; anything shorter never appears.
std::vector<Change> filter(bool initial, const std::vector<Change>& pin, unsigned len);

enum class Mode : unsigned { kX4 = 0, kX2 = 1, kX1 = 2 };

/// Quadrature decoder, one sample at a time: the outputs (visible after the sampling edge) for
/// the levels a, b sampled with valid/en/mode.
class Decoder {
 public:
  struct Out {
    bool up = false;
    bool down = false;
    bool err = false;
    bool dir = false;  // 1 = down; last legal transition while enabled
  };
  Out sample(bool a, bool b, bool valid, bool en, Mode mode);
  /// Start already primed with the given levels (the core after its power-up priming).
  void prime(bool a, bool b);

 private:
  bool a_ = false;
  bool b_ = false;
  bool primed_ = false;
  bool dir_ = false;
};

/// A decoded count or error, at the edge after which the decoder's pulse is visible.
struct Pulse {
  std::uint64_t edge = 0;
  int delta = 0;     // +1, -1, or 0 for a legal transition not counted in this mode
  bool dir = false;  // direction after this event
  bool err = false;  // illegal transition
};

/// One channel through filter and decoder (always enabled): the decoder samples the filtered
/// levels one edge after they appear, so its pulse is visible two edges after the filter output.
std::vector<Pulse> channel_pulses(bool a0, bool b0, const std::vector<Change>& a_pin,
                                  const std::vector<Change>& b_pin, unsigned filter_len, Mode mode);

/// Expected windows: a pulse visible after edge p is in the window of the first tick edge T
/// (tick_o visible after T) with T >= p.
struct Window {
  std::int64_t count = 0;
  std::uint32_t position = 0;
  bool dir = false;
  std::uint64_t errors = 0;
};
std::vector<Window> windows(const std::vector<Pulse>& pulses,
                            const std::vector<std::uint64_t>& ticks);

}  // namespace omniloc::rtl_golden
