// The ICM-42688-P SPI slave model (see sim/include/omniloc_sim/icm42688.hpp and docs/GYRO.md).
#include "omniloc_sim/icm42688.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <utility>

namespace omniloc::sim {
namespace {

constexpr double kResetBusyS = 1e-3;  // no SPI access for 1 ms after a soft reset
constexpr double kModeChangeBusyS =
    200e-6;  // no register write for 200 us after a gyro mode change

// GYRO_FS_SEL 0..7: +-2000, 1000, 500, 250, 125, 62.5, 31.25, 15.625 dps (LSB per dps).
constexpr std::array<double, 8> kSensitivity = {16.4,  32.8,  65.5,   131.0,
                                                262.0, 524.3, 1048.6, 2097.2};
// GYRO_ODR 0..15 in Hz, 0 = reserved.
constexpr std::array<double, 16> kOdrHz = {0,   32000, 16000, 8000, 4000, 2000, 1000, 200,
                                           100, 50,    25,    12.5, 0,    0,    0,    500};

std::string hex2(unsigned v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "0x%02X", v & 0xFFU);
  return buf;
}

}  // namespace

Icm42688::Icm42688(const Icm42688Params& params, RateFn true_rate_dps)
    : params_(params), rate_(std::move(true_rate_dps)), rng_(params.seed) {
  reset_registers();
}

void Icm42688::reset_registers() {
  std::fill(regs_.begin(), regs_.end(), std::uint8_t{0});
  regs_[kGyroConfig0] = 0x06;  // +-2000 dps, 1 kHz
  regs_[0x50] = 0x06;          // ACCEL_CONFIG0
  regs_[kIntStatus] = kResetDoneInt;
  regs_[kGyroDataZ1] = 0x80;  // 0x8000: no valid data yet
  regs_[kGyroDataZ0] = 0x00;
  next_sample_s_ = -1.0;
  sample_pending_ = false;
}

void Icm42688::violation(const std::string& what) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "t=%.6f s: ", time_s());
  violations_.push_back(buf + what);
}

bool Icm42688::gyro_on() const {
  return (regs_[kPwrMgmt0] & 0x0C) >= 0x08;
}  // LP or LN

double Icm42688::sensitivity_lsb_per_dps() const {
  return kSensitivity[regs_[kGyroConfig0] >> 5];
}

double Icm42688::odr_hz() const {
  return kOdrHz[regs_[kGyroConfig0] & 0x0F];
}

std::uint8_t Icm42688::read_reg(std::uint8_t addr) {
  if (addr == kWhoAmI) {
    ++who_am_i_reads_;
    return faults_.who_am_i;
  }
  const std::uint8_t v = regs_[addr];
  if (addr == kIntStatus) regs_[addr] = 0;  // clear on read
  return v;
}

void Icm42688::write_reg(std::uint8_t addr, std::uint8_t value) {
  const double t = time_s();
  if (mode_change_time_s_ >= 0.0 && t - mode_change_time_s_ < kModeChangeBusyS) {
    violation("write of " + hex2(addr) + " within 200 us of a gyro mode change");
  }
  switch (addr) {
    case kDeviceConfig:
      regs_[addr] = value & 0x31;
      if (value & 0x01) reset_pending_ = true;  // applied when CS rises
      break;
    case kPwrMgmt0: {
      const bool was_on = gyro_on();
      const std::uint8_t old_mode = regs_[addr] & 0x0C;
      regs_[addr] = value;
      if ((value & 0x0C) != old_mode) mode_change_time_s_ = t;
      if (gyro_on() && !was_on) next_sample_s_ = t + params_.startup_s;
      if (!gyro_on()) next_sample_s_ = -1.0;
      break;
    }
    case kGyroConfig0:
      regs_[addr] = value;
      if (odr_hz() == 0.0) {
        violation("GYRO_CONFIG0 " + hex2(value) + ": reserved GYRO_ODR code");
        next_sample_s_ = -1.0;
      } else if (gyro_on() && next_sample_s_ >= 0.0 && next_sample_s_ <= t) {
        next_sample_s_ = t + 1.0 / odr_hz();
      }
      break;
    case kWhoAmI:
    case kIntStatus:
    case kGyroDataZ1:
    case kGyroDataZ0:
      break;  // read-only
    default:
      regs_[addr] = value;
      break;
  }
}

void Icm42688::produce_sample() {
  if (faults_.no_data_ready) return;
  std::int16_t value;
  if (faults_.invalid) {
    value = INT16_MIN;
  } else if (faults_.stuck) {
    value = last_value_;
  } else {
    const double t = time_s();
    const double dps = rate_(t) + params_.bias_dps + params_.noise_dps_rms * noise_(rng_);
    const double lsb = std::round(dps * sensitivity_lsb_per_dps());
    value = static_cast<std::int16_t>(std::clamp(lsb, -32767.0, 32767.0));
    last_value_ = value;
  }
  if (!params_.keep_logs) produced_.clear();  // the last one is still needed (a sample pending)
  produced_.push_back({value, cycle_});
  if (prev_cs_n_) {
    const auto u = static_cast<std::uint16_t>(value);
    regs_[kGyroDataZ1] = static_cast<std::uint8_t>(u >> 8);
    regs_[kGyroDataZ0] = static_cast<std::uint8_t>(u & 0xFF);
    regs_[kIntStatus] |= kDataRdyInt;
  } else {
    sample_pending_ = true;
  }
}

// CS falls: a transaction starts (refused within 1 ms of the soft reset).
void Icm42688::begin_transaction(double t) {
  if (reset_time_s_ >= 0.0 && t - reset_time_s_ < kResetBusyS) {
    violation("SPI access within 1 ms of the soft reset");
  }
  bits_ = 0;
  in_ = 0;
  read_ = false;
  read_addrs_.clear();
  read_values_.clear();
  miso_ = false;
}

// CS rises: the transaction ends; a soft reset written during it takes effect, and a sample
// taken during it reaches the registers.
void Icm42688::end_transaction(double t) {
  if (reset_pending_) {
    reset_pending_ = false;
    reset_registers();
    reset_time_s_ = t;
    mode_change_time_s_ = -1.0;
    ++soft_resets_;
  }
  if (sample_pending_) {
    sample_pending_ = false;
    const auto u = static_cast<std::uint16_t>(produced_.back().value);
    regs_[kGyroDataZ1] = static_cast<std::uint8_t>(u >> 8);
    regs_[kGyroDataZ0] = static_cast<std::uint8_t>(u & 0xFF);
    regs_[kIntStatus] |= kDataRdyInt;
  }
}

// A whole byte clocked in: the address byte, a written byte, or (reading) the next register
// loaded, a completed GYRO_DATA_Z1/Z0 pair logged.
void Icm42688::byte_boundary() {
  if (bits_ == 8) {
    read_ = (in_ & 0x80) != 0;
    addr_ = in_ & 0x7F;
  } else if (!read_) {
    write_reg(addr_, in_);
    addr_ = (addr_ + 1) & 0x7F;
  } else {
    // The byte loaded at the previous byte boundary has been clocked out completely.
    const std::size_t n = read_addrs_.size();
    if (n >= 2 && read_addrs_[n - 2] == kGyroDataZ1 && read_addrs_[n - 1] == kGyroDataZ0) {
      const auto v = static_cast<std::int16_t>(
          static_cast<std::uint16_t>((read_values_[n - 2] << 8) | read_values_[n - 1]));
      if (!params_.keep_logs) reads_.clear();
      reads_.push_back({v, cycle_});
    }
  }
  if (read_) {
    out_ = read_reg(addr_);
    read_addrs_.push_back(addr_);
    read_values_.push_back(out_);
    addr_ = (addr_ + 1) & 0x7F;
  }
}

bool Icm42688::step(bool cs_n, bool sclk, bool mosi) {
  const double t = time_s();
  // ODR instants: the sample is taken now; it reaches the registers now or when CS rises.
  if (next_sample_s_ >= 0.0 && t >= next_sample_s_) {
    produce_sample();
    next_sample_s_ += 1.0 / odr_hz();
  }
  if (prev_cs_n_ && !cs_n) begin_transaction(t);
  if (!prev_cs_n_ && cs_n) end_transaction(t);
  if (!cs_n && !prev_cs_n_) {
    if (sclk && !prev_sclk_) {  // rising edge: MOSI sampled
      if (mosi != prev_mosi_) violation("MOSI changed with the rising SCLK edge (no setup time)");
      in_ = static_cast<std::uint8_t>((in_ << 1) | (mosi ? 1 : 0));
      ++bits_;
      if (bits_ % 8 == 0) byte_boundary();
    } else if (!sclk && prev_sclk_ && read_ && bits_ >= 8) {  // falling edge: next MISO bit
      miso_ = (out_ & 0x80) != 0;
      out_ = static_cast<std::uint8_t>(out_ << 1);
    }
  }
  prev_cs_n_ = cs_n;
  prev_sclk_ = sclk;
  prev_mosi_ = mosi;
  ++cycle_;
  return miso_;
}

}  // namespace omniloc::sim
