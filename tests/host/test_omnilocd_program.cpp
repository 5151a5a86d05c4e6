// The production `omnilocd` run as a program, without hardware: with no board on the bus it keeps
// trying to reconnect and stops cleanly at --duration-s; a camera it cannot open and a bad flag
// are refused with the name of what was wrong and the documented exit codes (1 and 2).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

int run(const std::string& args, std::string& output) {
  const fs::path log = fs::temp_directory_path() / ("omniloc_test_omnilocd_" + std::to_string(::getpid()) + ".log");
  const int status = std::system((std::string(OMNILOCD_PATH) + " " + args + " >" + log.string() + " 2>&1").c_str());
  std::ifstream in(log);
  std::ostringstream os;
  os << in.rdbuf();
  output = os.str();
  fs::remove(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(OmnilocdProgram, WithoutABoardItKeepsTryingAndStopsCleanly) {
  std::string out;
  const int rc = run("--camera none --duration-s 1 --udp-port 9", out);
  if (out.find("board open") != std::string::npos) GTEST_SKIP() << "a real omniloc board is plugged in";
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("board not available"), std::string::npos) << out;
  EXPECT_NE(out.find("stopped (duration) after 1.0 s: 0 windows"), std::string::npos) << out;
}

TEST(OmnilocdProgram, RefusesACameraItCannotOpenAndABadFlag) {
  std::string out;
  EXPECT_EQ(run("--camera /nonexistent/run.avi --duration-s 1", out), 1) << out;
  EXPECT_NE(out.find("camera '/nonexistent/run.avi'"), std::string::npos) << out;
  EXPECT_EQ(run("--udp-port 70000", out), 2) << out;
  EXPECT_NE(out.find("udp_port"), std::string::npos) << out;
  EXPECT_EQ(run("--help", out), 0) << out;
  EXPECT_NE(out.find("--udp-port"), std::string::npos) << out;
}

}  // namespace
