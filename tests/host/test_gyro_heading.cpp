// GyroHeading (gyro_heading.hpp): the board's raw gyro windows turned into the heading, against
// hand-computed values from the ICM-42688-P's sensitivity (16.4 LSB per deg/s at +-2000 dps,
// 1 kHz) and the default robot's wheel geometry; heading.csv in recordings.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "omniloc/gyro_heading.hpp"
#include "omniloc/recording.hpp"
#include "omniloc/regmap.hpp"
#include "temp_dir.hpp"

namespace omniloc {
namespace {

constexpr double kLsbPerDps = 16.4;
constexpr double kOdrHz = 1000.0;

class GyroHeadingTest : public ::testing::Test {
 protected:
  GyroHeadingTest()
      : robot_(load_named_robot_config("default")), heading_(robot_, {kLsbPerDps, kOdrHz}) {}

  /// The next 10 ms window: the gyro's sum over 10 samples, flags, and every wheel's count.
  EncoderWindow window(std::int64_t sum_lsb, std::int32_t counts, std::uint8_t flags = 0,
                       std::uint32_t samples = 10) {
    EncoderWindow w;
    w.seq = seq_++;
    w.t_end_ms = 10.0 * seq_;
    w.counts = {counts, counts, counts, counts};
    w.gyro = {true, sum_lsb, samples, flags};
    return w;
  }
  double feed(const EncoderWindow& w) { return heading_.gyro_yaw_deg(w); }

  RobotConfig robot_;
  GyroHeading heading_;
  std::uint32_t seq_ = 0;
};

// The default robot (eq. (9), R = 20 cm, wheel radius 5 cm, 500 CPR x4, gear 19): one count is
// 2 pi 5 / 38000 cm; equal counts on all four wheels are a pure rotation of travel / R.
constexpr double kCmPerCount = 2.0 * 3.14159265358979323846 * 5.0 / 38000.0;
double wheel_rotation_deg(int counts) {
  return counts * kCmPerCount / 20.0 * 180.0 / 3.14159265358979323846;
}

TEST_F(GyroHeadingTest, OneDegreeIsTheDatasheetSensitivityTimesTheRate) {
  // 100 deg/s for 10 ms = 1 deg: ten samples of 1640 LSB.
  EXPECT_NEAR(feed(window(16400, 500)), 1.0, 1e-12);
  EXPECT_NEAR(feed(window(-32800, 500)), -1.0, 1e-12);
  EXPECT_EQ(heading_.state(), GyroState::kLearningBias);
  EXPECT_EQ(heading_.trust(), HeadingTrust::kRelative);
  EXPECT_EQ(heading_.status_token(), "gyro");
}

TEST_F(GyroHeadingTest, TheBiasIsLearntWhileTheWheelsStandStillAndTheHeadingHolds) {
  // A bias of 41 LSB per sample (2.5 deg/s). The first 0.2 s of still wheels are not yet a
  // standstill (a slow robot may show zero counts for a window or two): summed as they come.
  double yaw = 0.0;
  for (int i = 0; i < 50; ++i) yaw = feed(window(410, 0));
  EXPECT_NEAR(yaw, 20 * 410 / (kLsbPerDps * kOdrHz), 1e-9);  // 20 windows before the standstill
  EXPECT_NEAR(heading_.bias_deg_per_s(), 2.5, 1e-9);
  EXPECT_EQ(heading_.state(), GyroState::kRunning);
  // Moving again at 100 deg/s: the bias is taken off.
  EXPECT_NEAR(feed(window(410 + 16400, 300)), yaw + 1.0, 1e-9);
}

TEST_F(GyroHeadingTest, AFlaggedWindowIsNeverSummedTheWheelsStandIn) {
  (void)feed(window(16400, 0));
  const double before = feed(window(0, 1000, 0x04));  // stuck value: the sum is not used
  EXPECT_NEAR(before, 1.0 + wheel_rotation_deg(1000), 1e-6);
  EXPECT_EQ(heading_.trust(), HeadingTrust::kNone);
  EXPECT_EQ(heading_.status_token(), "wheels-gyro-fault");
  EXPECT_NE(heading_.describe().find("0x04"), std::string::npos) << heading_.describe();
  // No sample at all (a missing data-ready) is a fault too.
  EXPECT_NEAR(feed(window(0, 1000, 0, 0)), before + wheel_rotation_deg(1000), 1e-6);
  EXPECT_EQ(heading_.fault_windows(), 2u);
  // Trusted again after ten clean windows in a row.
  for (int i = 0; i < 9; ++i) (void)feed(window(0, 100));
  EXPECT_EQ(heading_.trust(), HeadingTrust::kNone);
  (void)feed(window(0, 100));
  EXPECT_EQ(heading_.trust(), HeadingTrust::kRelative);
}

TEST_F(GyroHeadingTest, ABoardWithoutAGyroGivesTheWheelsRotation) {
  EncoderWindow w = window(0, 2000);
  w.gyro = {};
  EXPECT_NEAR(feed(w), wheel_rotation_deg(2000), 1e-6);
  EXPECT_EQ(heading_.state(), GyroState::kNoGyro);
  EXPECT_EQ(heading_.trust(), HeadingTrust::kNone);
  EXPECT_EQ(heading_.status_token(), "wheels-no-gyro");
}

TEST_F(GyroHeadingTest, AGyroThatDoesNotAnswerIsMissingNotAFault) {
  // A v0.2 board with nothing on its gyro PMOD: flags ABSENT | NOT_RUNNING, no sample.
  const std::uint8_t absent = (1u << regmap::kGyroFlagAbsent) | (1u << regmap::kGyroFlagNotRunning);
  EXPECT_NEAR(feed(window(0, 2000, absent, 0)), wheel_rotation_deg(2000), 1e-6);
  EXPECT_EQ(heading_.state(), GyroState::kMissing);
  EXPECT_EQ(heading_.trust(), HeadingTrust::kNone);
  EXPECT_EQ(heading_.status_token(), "wheels-no-gyro");
  EXPECT_NE(heading_.describe().find("gyro missing"), std::string::npos) << heading_.describe();
  // The part answers after all (plugged in): trusted after ten clean windows.
  for (int i = 0; i < 10; ++i) (void)feed(window(0, 100));
  EXPECT_EQ(heading_.state(), GyroState::kLearningBias);
  EXPECT_EQ(gyro_flag_names(0x28), "invalid value, not running");
  EXPECT_EQ(gyro_flag_names(0), "none");
}

TEST_F(GyroHeadingTest, TheStartUpIsBridgedByTheWheelsWithoutAFault) {
  // The part's 31 ms start-up after the board's reset: NOT_RUNNING and no sample. The wheels give
  // the rotation, the trust stays relative (an aligned heading is not forgotten), no fault counted.
  const std::uint8_t not_running = 1u << regmap::kGyroFlagNotRunning;
  EXPECT_NEAR(feed(window(0, 500, not_running, 0)), wheel_rotation_deg(500), 1e-6);
  EXPECT_EQ(heading_.state(), GyroState::kStarting);
  EXPECT_EQ(heading_.trust(), HeadingTrust::kRelative);
  EXPECT_EQ(heading_.status_token(), "gyro");
  EXPECT_EQ(heading_.fault_windows(), 0u);
  // Its first samples: the gyro from the next window on, at once (nothing to recover from).
  EXPECT_NEAR(feed(window(16400, 500)), wheel_rotation_deg(500) + 1.0, 1e-6);
  EXPECT_EQ(heading_.state(), GyroState::kLearningBias);
  // NOT_RUNNING after it once ran is a restart (a timeout): a fault.
  (void)feed(window(0, 500, not_running, 0));
  EXPECT_EQ(heading_.state(), GyroState::kFault);
  EXPECT_EQ(heading_.trust(), HeadingTrust::kNone);
}

TEST_F(GyroHeadingTest, TheBoardsScaleIsTheRegisterMapsPart) {
  EXPECT_DOUBLE_EQ(GyroScale::of_board().lsb_per_dps, kLsbPerDps);
  EXPECT_DOUBLE_EQ(GyroScale::of_board().odr_hz, kOdrHz);
}

TEST_F(GyroHeadingTest, ABadScaleIsRefused) {
  EXPECT_THROW(GyroHeading(robot_, {0.0, 1000.0}), std::invalid_argument);
  EXPECT_THROW(GyroHeading(robot_, {16.4, -1.0}), std::invalid_argument);
}

TEST(HeadingTrust, NamesRoundTrip) {
  for (HeadingTrust t : {HeadingTrust::kAbsolute, HeadingTrust::kRelative, HeadingTrust::kNone})
    EXPECT_EQ(parse_heading_trust(heading_trust_name(t)), t);
  EXPECT_FALSE(parse_heading_trust("Relative").has_value());
}

TEST(HeadingCsv, ARecordingKeepsEachWindowsHeadingAndRawGyro) {
  test::TempDir tmp("heading_csv");
  RecordingMeta meta;
  meta.camera = load_camera("default");
  meta.robot = load_named_robot_config("default");
  {
    RecordingWriter rec(tmp.path / "rec", meta, false);
    EncoderWindow w;
    w.t_end_ms = 10.0;
    rec.add_window(w);  // the simulator's aligned gyro: no heading.csv row yet
    w.t_end_ms = 20.0;
    w.seq = 1;
    w.heading_trust = HeadingTrust::kRelative;
    w.gyro = {true, -123456, 10, 0};
    rec.add_window(w);
    w.t_end_ms = 30.0;
    w.seq = 2;
    w.heading_trust = HeadingTrust::kNone;
    w.gyro = {true, 7, 9, 0x10};
    rec.add_window(w);
    rec.close();
  }
  const Recording r = load_recording(tmp.path / "rec");
  ASSERT_EQ(r.windows.size(), 3u);
  EXPECT_EQ(r.windows[0].heading_trust, HeadingTrust::kAbsolute);
  EXPECT_FALSE(r.windows[0].gyro.present);
  EXPECT_EQ(r.windows[1].heading_trust, HeadingTrust::kRelative);
  EXPECT_EQ(r.windows[1].gyro.sum_lsb, -123456);
  EXPECT_EQ(r.windows[1].gyro.samples, 10u);
  EXPECT_EQ(r.windows[2].heading_trust, HeadingTrust::kNone);
  EXPECT_EQ(r.windows[2].gyro.flags, 0x10);
  // A bad trust names the file, the line and the column.
  {
    std::ofstream f(tmp.path / "rec" / "heading.csv");
    f << "t_ms,trust,gyro_sum_lsb,gyro_samples,gyro_flags\n30.000000,aligned,0,10,0\n";
  }
  try {
    (void)load_recording(tmp.path / "rec");
    ADD_FAILURE() << "a bad trust was read";
  } catch (const RecordingError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("heading.csv:2"), std::string::npos) << what;
    EXPECT_NE(what.find("'trust'"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace omniloc
