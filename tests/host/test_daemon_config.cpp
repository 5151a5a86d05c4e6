// omnilocd's config file and flags: the shipped default file, every kind of bad input named by file
// and field, flags over the file, and the help text listing every key.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <fstream>
#include <string>
#include <vector>

#include "omniloc/daemon_config.hpp"
#include "omniloc/data_files.hpp"

namespace {

using omniloc::ConfigError;
using omniloc::daemon::DaemonConfig;
using omniloc::daemon::load_daemon_config;
using omniloc::daemon::parse_daemon_args;

std::filesystem::path write_file(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / ("omniloc_test_daemon_config_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto p = dir / name;
  std::ofstream(p) << text;
  return p;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(DaemonConfig, ShippedDefaultFileLoadsWithItsValues) {
  const std::string path = omniloc::resolve_data_file("omnilocd", "default").string();
  const DaemonConfig c = load_daemon_config(path);
  EXPECT_EQ(c.board, "usb");
  EXPECT_EQ(c.camera, "0");
  EXPECT_EQ(c.udp_address, "127.0.0.1");
  EXPECT_EQ(c.udp_port, 5600);
  EXPECT_EQ(c.publish_hz, 100.0);
  EXPECT_EQ(c.camera_timeout_ms, 500.0);
  EXPECT_EQ(c.reconnect_period_ms, 500.0);
  EXPECT_EQ(c.database, "");
  EXPECT_EQ(c.sim_seed, 1u);
}

TEST(DaemonConfig, FileValuesOverrideDefaultsAndOthersKeepThem) {
  const auto p = write_file("partial.json", R"({"board": "sim", "udp_port": 6001, "camera_fps": 30.5})");
  const DaemonConfig c = load_daemon_config(p.string());
  EXPECT_EQ(c.board, "sim");
  EXPECT_EQ(c.udp_port, 6001);
  EXPECT_EQ(c.camera_fps, 30.5);
  EXPECT_EQ(c.camera, DaemonConfig{}.camera);
  EXPECT_EQ(c.status_period_s, DaemonConfig{}.status_period_s);
}

TEST(DaemonConfig, ErrorsNameTheFileAndTheField) {
  struct Case {
    std::string json;
    std::string field;
    std::string why;
  };
  const std::vector<Case> cases = {
      {R"({"udp_prot": 5600})", "udp_prot", "unknown key"},
      {R"({"udp_port": "5600"})", "udp_port", "must be a number"},
      {R"({"udp_port": 70000})", "udp_port", "(got 70000)"},
      {R"({"udp_port": 56.5})", "udp_port", "integer"},
      {R"({"board": "serial"})", "board", "\"usb\" or \"sim\""},
      {R"({"board": 3})", "board", "must be a string"},
      {R"({"udp_address": "localhost"})", "udp_address", "dotted IPv4"},
      {R"({"publish_hz": 50})", "publish_hz", "must be 100"},
      {R"({"camera_timeout_ms": 0})", "camera_timeout_ms", "[10, 60000]"},
      {R"({"duration_s": -1})", "duration_s", ">= 0"},
      {R"({"grid_step_cm": 1})", "grid_step_cm", "[2, 50]"},
  };
  int i = 0;
  for (const auto& c : cases) {
    const auto p = write_file("bad" + std::to_string(i++) + ".json", c.json);
    const std::string msg = error_of([&] { (void)load_daemon_config(p.string()); });
    EXPECT_NE(msg.find(p.string()), std::string::npos) << c.json << " -> " << msg;
    EXPECT_NE(msg.find("field '" + c.field + "'"), std::string::npos) << c.json << " -> " << msg;
    EXPECT_NE(msg.find(c.why), std::string::npos) << c.json << " -> " << msg;
  }
}

TEST(DaemonConfig, MissingAndMalformedFilesAreNamed) {
  const std::string missing = "/nonexistent/omnilocd.json";
  std::string msg = error_of([&] { (void)load_daemon_config(missing); });
  EXPECT_NE(msg.find(missing), std::string::npos) << msg;
  const auto bad = write_file("malformed.json", "{\"board\" \"sim\"}");
  msg = error_of([&] { (void)load_daemon_config(bad.string()); });
  EXPECT_NE(msg.find(bad.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("JSON"), std::string::npos) << msg;
  const auto arr = write_file("array.json", "[1, 2]");
  msg = error_of([&] { (void)load_daemon_config(arr.string()); });
  EXPECT_NE(msg.find(arr.string()), std::string::npos) << msg;
}

TEST(DaemonConfig, FlagsOverrideTheFileWhateverTheirOrder) {
  const auto p = write_file("flags.json", R"({"udp_port": 6001, "board": "sim", "duration_s": 3})");
  const std::string ps = p.string();
  const std::vector<std::string_view> args = {"--udp-port", "6002", "--config", ps, "--camera_fps", "15"};
  const auto a = parse_daemon_args(args);
  EXPECT_FALSE(a.help);
  EXPECT_EQ(a.config_path, ps);
  EXPECT_EQ(a.config.udp_port, 6002);       // flag beats file
  EXPECT_EQ(a.config.board, "sim");         // file beats default
  EXPECT_EQ(a.config.duration_s, 3.0);
  EXPECT_EQ(a.config.camera_fps, 15.0);
}

TEST(DaemonConfig, BadFlagsAreRefusedWithTheFlagNamed) {
  auto err = [](std::vector<std::string_view> args) {
    return error_of([&] { (void)parse_daemon_args(args); });
  };
  EXPECT_NE(err({"--udp-port", "abc"}).find("field 'udp_port': must be a number (got \"abc\")"), std::string::npos)
      << err({"--udp-port", "abc"});
  EXPECT_NE(err({"--no-such-key", "1"}).find("field 'no_such_key': unknown key"), std::string::npos);
  EXPECT_NE(err({"--udp-port"}).find("--udp-port needs a value"), std::string::npos);
  EXPECT_NE(err({"stray"}).find("unexpected argument 'stray'"), std::string::npos);
  EXPECT_NE(err({"--udp-port", "0"}).find("command line: field 'udp_port'"), std::string::npos);
  EXPECT_TRUE(parse_daemon_args(std::vector<std::string_view>{"--help"}).help);
}

TEST(DaemonConfig, HelpListsEveryKeyAsAFlagWithItsDefault) {
  const std::string help = omniloc::daemon::daemon_usage();
  for (const char* flag : {"--board ", "--board-serial", "--reconnect-period-ms", "--camera ", "--camera-fps",
                           "--camera-timeout-ms", "--field", "--camera-model", "--robot", "--localizer", "--database",
                           "--grid-step-cm", "--udp-address", "--udp-port", "--publish-hz", "--record-dir",
                           "--status-period-s", "--duration-s", "--sim-trajectory", "--sim-seed"}) {
    EXPECT_NE(help.find(flag), std::string::npos) << flag;
  }
  EXPECT_NE(help.find("(5600)"), std::string::npos);
}

}  // namespace
