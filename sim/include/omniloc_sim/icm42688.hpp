// A cycle-accurate model of the SPI slave side of a TDK InvenSense ICM-42688-P 6-axis IMU, as far
// as the gyro reader (rtl/gyro/gyro_ctrl.v) uses it: bank-0 registers DEVICE_CONFIG (soft reset),
// INT_STATUS (DATA_RDY_INT, RESET_DONE_INT, clear on read), GYRO_DATA_Z1/Z0 (big-endian signed 16
// bit), PWR_MGMT0 (GYRO_MODE), GYRO_CONFIG0 (GYRO_FS_SEL, GYRO_ODR), WHO_AM_I (0x47); SPI mode 0
// (MOSI sampled on the rising SCLK edge, MISO changed after the falling edge), bit 7 of the first
// byte = read, the address auto-increments over a burst. Values from the datasheet DS-000347 as
// docs/GYRO.md lists them.
//
// It is stepped once per clock cycle of the design that drives it, with the pins as that cycle's
// edge left them (CS, SCLK, MOSI), and returns MISO for the next edge. The gyro samples the true
// yaw rate (a function of time, deg/s) at the output data rate, adds a bias and white noise, scales
// by the configured range and rounds. The data registers never change while CS is low (an update
// falling into a transaction is applied when CS rises), so a burst reads one sample.
//
// Checks of the master (recorded in violations(), never thrown): an SPI access within 1 ms of the
// soft reset, a register write within 200 us of a gyro mode change, MOSI changing in the cycle of
// a rising SCLK edge (no setup time), a reserved GYRO_ODR code.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace omniloc::sim {

struct Icm42688Params {
  double clk_hz = 12e6;        ///< step() calls per second (the driving design's clock)
  double bias_dps = 0.0;       ///< constant rate bias
  double noise_dps_rms = 0.0;  ///< white noise added to each sample
  double startup_s = 0.030;    ///< gyro start-up: PWR_MGMT0 on to the first data-ready
  std::uint64_t seed = 1;      ///< of the noise
  bool keep_logs = true;       ///< false: produced() and reads() hold only the latest (long runs)
};

/// Fault injection; may be changed between steps.
struct Icm42688Faults {
  std::uint8_t who_am_i = 0x47;  ///< what WHO_AM_I reads (0x47 = the genuine part)
  bool no_data_ready = false;    ///< no new samples, DATA_RDY_INT never set
  bool stuck = false;            ///< new samples repeat the last value (data-ready goes on)
  bool invalid = false;          ///< new samples read 0x8000 (the part's "no data" value)
};

class Icm42688 {
 public:
  static constexpr std::uint8_t kDeviceConfig = 0x11;
  static constexpr std::uint8_t kIntStatus = 0x2D;
  static constexpr std::uint8_t kGyroDataZ1 = 0x29;
  static constexpr std::uint8_t kGyroDataZ0 = 0x2A;
  static constexpr std::uint8_t kPwrMgmt0 = 0x4E;
  static constexpr std::uint8_t kGyroConfig0 = 0x4F;
  static constexpr std::uint8_t kWhoAmI = 0x75;
  static constexpr std::uint8_t kDataRdyInt = 0x08;    ///< INT_STATUS bit 3
  static constexpr std::uint8_t kResetDoneInt = 0x10;  ///< INT_STATUS bit 4

  using RateFn = std::function<double(double t_s)>;  ///< true yaw rate in deg/s at time t_s

  struct Sample {
    std::int16_t value;
    std::uint64_t cycle;  ///< produced: the ODR instant; read: the burst's last rising SCLK edge
  };

  Icm42688(const Icm42688Params& params, RateFn true_rate_dps);

  /// One clock cycle: the pins after the driving design's edge. Returns MISO for the next edge.
  bool step(bool cs_n, bool sclk, bool mosi);

  [[nodiscard]] std::uint8_t reg(std::uint8_t addr) const { return regs_.at(addr & 0x7F); }
  [[nodiscard]] Icm42688Faults& faults() { return faults_; }
  [[nodiscard]] std::uint64_t cycle() const { return cycle_; }
  [[nodiscard]] double time_s() const { return static_cast<double>(cycle_) / params_.clk_hz; }

  /// Every sample put into GYRO_DATA_Z (in order; only the latest without keep_logs).
  [[nodiscard]] const std::vector<Sample>& produced() const { return produced_; }
  /// Every burst that read GYRO_DATA_Z1 then GYRO_DATA_Z0: the 16-bit value the master got.
  [[nodiscard]] const std::vector<Sample>& reads() const { return reads_; }
  [[nodiscard]] const std::vector<std::string>& violations() const { return violations_; }
  [[nodiscard]] int soft_resets() const { return soft_resets_; }
  [[nodiscard]] int who_am_i_reads() const { return who_am_i_reads_; }
  [[nodiscard]] bool gyro_on() const;
  /// LSB per deg/s of the configured GYRO_FS_SEL (16.4 at +-2000 dps).
  [[nodiscard]] double sensitivity_lsb_per_dps() const;
  /// The configured GYRO_ODR in Hz (0 for a reserved code).
  [[nodiscard]] double odr_hz() const;

 private:
  void reset_registers();
  void violation(const std::string& what);
  std::uint8_t read_reg(std::uint8_t addr);
  void write_reg(std::uint8_t addr, std::uint8_t value);
  void produce_sample();
  void begin_transaction(double t);  // step()'s stages: CS falls, CS rises, a byte in
  void end_transaction(double t);
  void byte_boundary();
  void schedule_from(double t_s);

  Icm42688Params params_;
  RateFn rate_;
  Icm42688Faults faults_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  std::vector<std::uint8_t> regs_ = std::vector<std::uint8_t>(128, 0);

  std::uint64_t cycle_ = 0;
  bool prev_cs_n_ = true, prev_sclk_ = false, prev_mosi_ = false;
  bool miso_ = false;
  // The transaction.
  int bits_ = 0;          ///< rising edges since CS fell
  std::uint8_t in_ = 0;   ///< MOSI bits of the current byte
  std::uint8_t out_ = 0;  ///< MISO bits still to send
  bool read_ = false;
  std::uint8_t addr_ = 0;
  std::vector<std::uint8_t> read_addrs_;  ///< registers loaded for MISO in this transaction
  std::vector<std::uint8_t> read_values_;
  bool reset_pending_ = false;
  bool sample_pending_ = false;  ///< an ODR instant fell into a transaction
  // Timing.
  double reset_time_s_ = -1.0;
  double mode_change_time_s_ = -1.0;
  double next_sample_s_ = -1.0;  ///< < 0: no sampling
  std::int16_t last_value_ = 0;

  std::vector<Sample> produced_, reads_;
  std::vector<std::string> violations_;
  int soft_resets_ = 0;
  int who_am_i_reads_ = 0;
};

}  // namespace omniloc::sim
