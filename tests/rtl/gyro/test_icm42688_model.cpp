// The ICM-42688-P model (sim/gyro/) on its own, driven by a bit-banged SPI mode-0 master written
// here (not the RTL): register access, the range and rate tables, clear-on-read, noise and bias
// statistics, and the timing checks it makes of a master.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "omniloc_sim/icm42688.hpp"

namespace {

using omniloc::sim::Icm42688;

constexpr double kClkHz = 12e6;
constexpr std::uint64_t kMs = 12000;

/// A mode-0 master: 2 cycles a half period, CS set up and held one half period.
class Master {
 public:
  explicit Master(Icm42688& m) : m_(m) {}
  void idle(std::uint64_t cycles) {
    for (std::uint64_t i = 0; i < cycles; ++i) miso_ = m_.step(true, false, false);
  }
  std::vector<std::uint8_t> xfer(const std::vector<std::uint8_t>& tx) {
    std::vector<std::uint8_t> rx;
    pins(false, false, tx[0] & 0x80, 2);
    for (std::uint8_t byte : tx) {
      std::uint8_t in = 0;
      for (int bit = 7; bit >= 0; --bit) {
        const bool mosi = (byte >> bit) & 1;
        pins(false, false, mosi, 2);
        pins(false, true, mosi, 2);
        in = static_cast<std::uint8_t>((in << 1) | (miso_ ? 1 : 0));
      }
      rx.push_back(in);
    }
    pins(false, false, false, 2);
    pins(true, false, false, 2);
    return rx;
  }
  void write(std::uint8_t addr, std::uint8_t v) { xfer({addr, v}); }
  std::uint8_t read(std::uint8_t addr) {
    return xfer({static_cast<std::uint8_t>(0x80 | addr), 0})[1];
  }
  std::int16_t read_z() {
    const auto rx = xfer({0x80 | Icm42688::kGyroDataZ1, 0, 0});
    return static_cast<std::int16_t>(static_cast<std::uint16_t>((rx[1] << 8) | rx[2]));
  }

 private:
  void pins(bool cs_n, bool sclk, bool mosi, int cycles) {
    for (int i = 0; i < cycles; ++i) miso_ = m_.step(cs_n, sclk, mosi);
  }
  Icm42688& m_;
  bool miso_ = false;
};

TEST(Icm42688Model, ReadsIdAndResetValues) {
  Icm42688 m({kClkHz, 0, 0, 0.030, 1}, [](double) { return 0.0; });
  Master spi(m);
  spi.idle(10);
  EXPECT_EQ(spi.read(Icm42688::kWhoAmI), 0x47);
  EXPECT_EQ(spi.read(Icm42688::kGyroConfig0), 0x06);
  EXPECT_EQ(spi.read(Icm42688::kIntStatus), 0x10);  // RESET_DONE_INT
  EXPECT_EQ(spi.read(Icm42688::kIntStatus), 0x00);  // cleared by the read
  EXPECT_EQ(spi.read_z(), INT16_MIN);               // no data yet
  m.faults().who_am_i = 0x12;
  EXPECT_EQ(spi.read(Icm42688::kWhoAmI), 0x12);
  EXPECT_TRUE(m.violations().empty());
}

TEST(Icm42688Model, ScaleFollowsTheRangeAndOdrTheRate) {
  // +-500 dps (GYRO_FS_SEL 2: 65.5 LSB/(deg/s)), 2 kHz (GYRO_ODR 5); 10 deg/s read 655.
  Icm42688 m({kClkHz, 0, 0, 0.030, 1}, [](double) { return 10.0; });
  Master spi(m);
  spi.idle(10);
  spi.write(Icm42688::kPwrMgmt0, 0x0C);
  spi.idle(3 * kMs);
  spi.write(Icm42688::kGyroConfig0, (2 << 5) | 5);
  EXPECT_DOUBLE_EQ(m.sensitivity_lsb_per_dps(), 65.5);
  EXPECT_DOUBLE_EQ(m.odr_hz(), 2000.0);
  spi.idle(26 * kMs);  // 29 ms after PWR_MGMT0
  EXPECT_TRUE(m.produced().empty()) << "data before the 30 ms start-up";
  spi.idle(2 * kMs);
  EXPECT_EQ(spi.read(Icm42688::kIntStatus) & Icm42688::kDataRdyInt, Icm42688::kDataRdyInt);
  EXPECT_EQ(spi.read_z(), 655);
  const std::size_t before = m.produced().size();
  spi.idle(100 * kMs);
  EXPECT_EQ(m.produced().size() - before, 200U);
  EXPECT_TRUE(m.violations().empty()) << m.violations().front();
}

TEST(Icm42688Model, NoiseAndBiasHaveTheirStatistics) {
  // 2 deg/s bias, 1 deg/s rms noise at 16.4 LSB/(deg/s): mean 32.8 LSB, sigma 16.4 LSB.
  Icm42688 m({kClkHz, 2.0, 1.0, 0.0, 99}, [](double) { return 0.0; });
  Master spi(m);
  spi.write(Icm42688::kPwrMgmt0, 0x0C);
  spi.idle(2000 * kMs);  // 2 s at 1 kHz: 2000 samples
  double s = 0, s2 = 0;
  const auto& p = m.produced();
  ASSERT_GE(p.size(), 1999U);
  for (const auto& x : p) {
    s += x.value;
    s2 += static_cast<double>(x.value) * x.value;
  }
  const double n = static_cast<double>(p.size());
  const double mean = s / n, sd = std::sqrt(s2 / n - mean * mean);
  EXPECT_NEAR(mean, 32.8, 1.5);  // 4 sigma of the mean (0.37 LSB)
  EXPECT_NEAR(sd, 16.4, 1.0);    // 4 sigma of the sd (0.26 LSB)
}

TEST(Icm42688Model, FlagsAMasterThatDoesNotWait) {
  Icm42688 m({kClkHz, 0, 0, 0.030, 1}, [](double) { return 0.0; });
  Master spi(m);
  spi.write(Icm42688::kDeviceConfig, 0x01);
  EXPECT_EQ(m.soft_resets(), 1);
  spi.idle(100);
  spi.read(Icm42688::kWhoAmI);  // within 1 ms of the reset
  ASSERT_EQ(m.violations().size(), 1U);
  EXPECT_NE(m.violations()[0].find("1 ms of the soft reset"), std::string::npos);
  spi.idle(2 * kMs);
  spi.write(Icm42688::kPwrMgmt0, 0x0C);
  spi.write(Icm42688::kGyroConfig0, 0x06);  // within 200 us of the mode change
  ASSERT_EQ(m.violations().size(), 2U);
  EXPECT_NE(m.violations()[1].find("200 us"), std::string::npos);
  spi.idle(kMs);
  spi.write(Icm42688::kGyroConfig0, 0x0C);  // GYRO_ODR 12: reserved
  ASSERT_EQ(m.violations().size(), 3U);
  EXPECT_NE(m.violations()[2].find("reserved"), std::string::npos);
}

}  // namespace
