#include "golden_encoder.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

namespace omniloc::rtl_golden {

std::vector<Change> filter(bool initial, const std::vector<Change>& pin, unsigned len) {
  const std::uint64_t hold = std::max(len, 1u);
  std::vector<Change> out;
  bool level = initial;
  for (std::size_t i = 0; i < pin.size(); ++i) {
    if (i > 0 && pin[i].edge <= pin[i - 1].edge) {
      throw std::invalid_argument("golden filter: pin changes out of order at index " +
                                  std::to_string(i));
    }
    const bool last = (i + 1 == pin.size());
    const std::uint64_t duration = last ? hold : pin[i + 1].edge - pin[i].edge;
    if (pin[i].level != level && duration >= hold) {
      level = pin[i].level;
      // Two synchronizer edges, then the level must be seen `hold` times.
      out.push_back({pin[i].edge + 1 + hold, level});
    }
  }
  return out;
}

namespace {
// The forward cycle (A leads B): AB = 00, 10, 11, 01.
constexpr std::array<unsigned, 4> kForward = {0b00, 0b10, 0b11, 0b01};
unsigned position_in_cycle(bool a, bool b) {
  const unsigned ab = (a ? 2u : 0u) | (b ? 1u : 0u);
  for (unsigned i = 0; i < 4; ++i) {
    if (kForward[i] == ab) return i;
  }
  return 0;
}
}  // namespace

void Decoder::prime(bool a, bool b) {
  a_ = a;
  b_ = b;
  primed_ = true;
}

Decoder::Out Decoder::sample(bool a, bool b, bool valid, bool en, Mode mode) {
  Out o;
  if (primed_ && en) {
    const bool a_changed = a != a_;
    const bool b_changed = b != b_;
    if (a_changed && b_changed) {
      o.err = true;
    } else if (a_changed || b_changed) {
      const bool forward = position_in_cycle(a, b) == (position_in_cycle(a_, b_) + 1) % 4;
      bool counted = true;
      if (mode == Mode::kX2) counted = a_changed;
      if (mode == Mode::kX1) counted = a_changed && !b;
      o.up = counted && forward;
      o.down = counted && !forward;
      dir_ = !forward;
    }
  }
  a_ = a;
  b_ = b;
  primed_ = primed_ || valid;
  o.dir = dir_;
  return o;
}

std::vector<Pulse> channel_pulses(bool a0, bool b0, const std::vector<Change>& a_pin,
                                  const std::vector<Change>& b_pin, unsigned filter_len,
                                  Mode mode) {
  const auto fa = filter(a0, a_pin, filter_len);
  const auto fb = filter(b0, b_pin, filter_len);
  Decoder dec;
  dec.prime(a0, b0);
  bool a = a0;
  bool b = b0;
  std::vector<Pulse> pulses;
  std::size_t ia = 0;
  std::size_t ib = 0;
  while (ia < fa.size() || ib < fb.size()) {
    std::uint64_t t = UINT64_MAX;
    if (ia < fa.size()) t = std::min(t, fa[ia].edge);
    if (ib < fb.size()) t = std::min(t, fb[ib].edge);
    if (ia < fa.size() && fa[ia].edge == t) a = fa[ia++].level;
    if (ib < fb.size() && fb[ib].edge == t) b = fb[ib++].level;
    const auto o = dec.sample(a, b, true, true, mode);
    // Filter output visible after t, sampled by the decoder at t + 1.
    pulses.push_back({t + 1, o.up ? 1 : (o.down ? -1 : 0), o.dir, o.err});
  }
  return pulses;
}

std::vector<Window> windows(const std::vector<Pulse>& pulses,
                            const std::vector<std::uint64_t>& ticks) {
  std::vector<Window> out;
  std::size_t i = 0;
  std::uint32_t position = 0;
  bool dir = false;
  for (const std::uint64_t t : ticks) {
    Window w;
    while (i < pulses.size() && pulses[i].edge <= t) {
      w.count += pulses[i].delta;
      position += static_cast<std::uint32_t>(pulses[i].delta);
      if (!pulses[i].err) dir = pulses[i].dir;
      if (pulses[i].err) ++w.errors;
      ++i;
    }
    w.position = position;
    w.dir = dir;
    out.push_back(w);
  }
  return out;
}

}  // namespace omniloc::rtl_golden
