// The logging facility (log.hpp): level names, -v / -q arithmetic, the threshold, the line format.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "omniloc/log.hpp"

using namespace omniloc;

TEST(Log, LevelNamesReadBackAndABadOneIsNamed) {
  for (const LogLevel l : {LogLevel::kError, LogLevel::kWarning, LogLevel::kInfo, LogLevel::kDebug})
    EXPECT_EQ(parse_log_level(to_string(l), "log_level"), l);
  try {
    (void)parse_log_level("verbose", "cfg.json: log_level");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "cfg.json: log_level: must be one of error, warning, info, debug (got 'verbose')");
  }
  EXPECT_THROW((void)parse_log_level("INFO", "x"), std::invalid_argument);
  EXPECT_THROW((void)parse_log_level("", "x"), std::invalid_argument);
}

TEST(Log, VerboseAndQuietMoveOneStepEachAndStopAtTheEnds) {
  EXPECT_EQ(adjust_log_level(LogLevel::kInfo, 1, 0), LogLevel::kDebug);
  EXPECT_EQ(adjust_log_level(LogLevel::kInfo, 0, 1), LogLevel::kWarning);
  EXPECT_EQ(adjust_log_level(LogLevel::kInfo, 0, 2), LogLevel::kError);
  EXPECT_EQ(adjust_log_level(LogLevel::kInfo, 0, 9), LogLevel::kError);
  EXPECT_EQ(adjust_log_level(LogLevel::kWarning, 5, 0), LogLevel::kDebug);
  EXPECT_EQ(adjust_log_level(LogLevel::kInfo, 1, 1), LogLevel::kInfo);
}

TEST(Log, OnlyMessagesAtOrAboveTheThresholdReachTheSink) {
  std::vector<std::string> got;
  const Logger log(LogLevel::kWarning, [&](LogLevel l, std::string_view m) {
    got.push_back(format_log_line("omnilocd", l, m));
  });
  log.debug("d");
  log.info("i");
  log.warning("board lost");
  log.error("recording stopped");
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], "omnilocd: warning: board lost");
  EXPECT_EQ(got[1], "omnilocd: error: recording stopped");
  EXPECT_FALSE(log.enabled(LogLevel::kInfo));
  EXPECT_TRUE(log.enabled(LogLevel::kError));
  EXPECT_EQ(format_log_line("omniloc", LogLevel::kInfo, "t=1.0s ok"), "omniloc: t=1.0s ok");
  EXPECT_EQ(format_log_line("omniloc", LogLevel::kDebug, "frame"), "omniloc: debug: frame");
  EXPECT_THROW(Logger(LogLevel::kInfo, nullptr), std::invalid_argument);
}
