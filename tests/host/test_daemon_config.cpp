// omnilocd's config file and flags: the shipped default file is the struct's defaults (every key),
// a file setting every key to a non-default value lands in every member (expected values by hand),
// every kind of bad input is named by file and field, flags (CLI11, as omnilocd parses them)
// override the file, and --help lists every key.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "config_test_util.hpp"
#include "daemon_cli.hpp"
#include "omniloc/config.hpp"
#include "omniloc/daemon_config.hpp"

namespace omniloc::daemon {
namespace {

using test::error_of;

// Every key of DaemonConfig, written down here by hand (not taken from the reader's table).
const std::vector<std::string> kEveryKey = {"board_serial",
                                            "reconnect_period_ms",
                                            "camera",
                                            "camera_fps",
                                            "camera_timeout_ms",
                                            "camera_latency_ms",
                                            "field",
                                            "camera_model",
                                            "robot",
                                            "localizer",
                                            "database",
                                            "grid_step_cm",
                                            "side",
                                            "udp_address",
                                            "udp_port",
                                            "control_port",
                                            "publish_hz",
                                            "record_dir",
                                            "record_overwrite",
                                            "record_format",
                                            "status_period_s",
                                            "log_level",
                                            "duration_s",
                                            "ros2_domain_id",
                                            "ros2_namespace",
                                            "ros2_frame_id",
                                            "http_port",
                                            "http_address"};

// Every key set to a value that differs from its default (publish_hz has only one valid value).
const std::string kEveryKeyJson = R"({
  "board_serial": "OL-0042",
  "reconnect_period_ms": 750,
  "camera": "/dev/video2",
  "camera_fps": 30.5,
  "camera_timeout_ms": 250,
  "camera_latency_ms": 12.5,
  "field": "robocup-msl",
  "camera_model": "cams/c.json",
  "robot": "robots/r.json",
  "localizer": "loc/l.json",
  "database": "/var/db.bin",
  "grid_step_cm": 20,
  "side": "yellow",
  "udp_address": "192.168.1.20",
  "udp_port": 6001,
  "control_port": 6101,
  "publish_hz": 100,
  "record_dir": "/data/run1",
  "record_overwrite": true,
  "record_format": "png",
  "status_period_s": 2.5,
  "log_level": "debug",
  "duration_s": 12,
  "ros2_domain_id": 7,
  "ros2_namespace": "/robot2/omniloc",
  "ros2_frame_id": "field",
  "http_port": 8080,
  "http_address": "0.0.0.0"
})";

TEST(DaemonConfig, ShippedDefaultFileIsTheStructDefaultsEveryKey) {
  const auto path = resolve_data_file("omnilocd", "default");
  // The file names every key (so none of them falls back to a C++ default) ...
  EXPECT_EQ(test::keys_of(test::read_json(path)), kEveryKey);
  // ... and loading it gives exactly the struct's defaults: one set of defaults, not two.
  const DaemonConfig loaded = load_daemon_config(path.string());
  EXPECT_TRUE(loaded == DaemonConfig{});
  EXPECT_EQ(loaded.camera, "0");
  EXPECT_EQ(loaded.udp_port, 5600);
}

TEST(DaemonConfig, EveryKeyReachesItsMember) {
  const auto p = test::write_file("every.json", kEveryKeyJson);
  EXPECT_EQ(test::keys_of(test::read_json(p)), kEveryKey);
  const DaemonConfig c = load_daemon_config(p.string());
  EXPECT_EQ(c.board_serial, "OL-0042");
  EXPECT_EQ(c.reconnect_period_ms, 750.0);
  EXPECT_EQ(c.camera, "/dev/video2");
  EXPECT_EQ(c.camera_fps, 30.5);
  EXPECT_EQ(c.camera_timeout_ms, 250.0);
  EXPECT_EQ(c.camera_latency_ms, 12.5);
  EXPECT_EQ(c.field, "robocup-msl");
  EXPECT_EQ(c.camera_model, "cams/c.json");
  EXPECT_EQ(c.robot, "robots/r.json");
  EXPECT_EQ(c.localizer, "loc/l.json");
  EXPECT_EQ(c.database, "/var/db.bin");
  EXPECT_EQ(c.grid_step_cm, 20.0);
  EXPECT_EQ(c.udp_address, "192.168.1.20");
  EXPECT_EQ(c.udp_port, 6001);
  EXPECT_EQ(c.publish_hz, 100.0);
  EXPECT_EQ(c.record_dir, "/data/run1");
  EXPECT_TRUE(c.record_overwrite);
  EXPECT_EQ(c.record_format, "png");
  EXPECT_EQ(c.side, "yellow");
  EXPECT_EQ(c.status_period_s, 2.5);
  EXPECT_EQ(c.duration_s, 12.0);
  EXPECT_EQ(c.control_port, 6101);
  EXPECT_EQ(c.ros2_domain_id, 7);
  EXPECT_EQ(c.ros2_namespace, "/robot2/omniloc");
  EXPECT_EQ(c.ros2_frame_id, "field");
  EXPECT_EQ(c.http_port, 8080);
  EXPECT_EQ(c.http_address, "0.0.0.0");
}

TEST(DaemonConfig, EachKeyOfTheFullFileMatters) {
  // Dropping any one key from the full file changes the result: each key is read into a member of
  // its own (a table entry pointing at the wrong member, or at none, fails here).
  const DaemonConfig full =
      load_daemon_config(test::write_file("every.json", kEveryKeyJson).string());
  const auto json = test::read_json(test::write_file("every.json", kEveryKeyJson));
  for (const std::string& k : kEveryKey) {
    if (k == "publish_hz") continue;  // its only valid value is the default
    auto without = json;
    without.erase(k);
    const DaemonConfig c =
        load_daemon_config(test::write_file("without.json", without.dump()).string());
    EXPECT_FALSE(c == full) << k << " made no difference";
  }
}

TEST(DaemonConfig, FileValuesOverrideTheBaseAndOthersKeepIt) {
  const auto p = test::write_file("partial.json", R"({"udp_port": 6001, "camera_fps": 30.5})");
  DaemonConfig base;
  base.camera = "none";
  const DaemonConfig c = load_daemon_config(p.string(), base);
  EXPECT_EQ(c.udp_port, 6001);
  EXPECT_EQ(c.camera_fps, 30.5);
  EXPECT_EQ(c.camera, "none");
  EXPECT_EQ(c.status_period_s, DaemonConfig{}.status_period_s);
}

TEST(DaemonConfig, BadFilesNameTheFileAndTheField) {
  test::expect_errors(
      [](const std::string& f) { (void)load_daemon_config(f); },
      {
          {R"({"udp_prot": 5600})", "udp_prot", "unknown key (known keys: board_serial, "},
          {R"({"board": "usb"})", "board", "unknown key"},  // the simulator keys are gone
          {R"({"sim_seed": 1})", "sim_seed", "unknown key"},
          {R"({"udp_port": 5600, "udp_port": 5601})", "udp_port", "duplicate key"},
          {R"({"udp_port": "5600"})", "udp_port",
           "must be an integer, not a string (got \"5600\")"},
          {R"({"udp_port": 56.5})", "udp_port", "must be an integer"},
          {R"({"udp_port": 5600.0})", "udp_port", "must be an integer"},
          {R"({"camera_fps": true})", "camera_fps", "must be a number, not a boolean (got true)"},
          {R"({"camera": 7})", "camera", "must be a string, not a number (got 7)"},
          {R"({"camera_fps": NaN})", "camera_fps", "not valid JSON"},
          {R"({"duration_s": Infinity})", "duration_s", "not valid JSON"},
          {R"({"duration_s": 1e400})", "duration_s",
           "number out of range: beyond a double (got 1e400)"},
          {R"({"udp_port": 70000})", "udp_port", "out of range: must be in [1, 65535] (got 70000)"},
          {R"({"udp_port": 1e10})", "udp_port", "must be an integer"},
          {R"({"udp_port": 99999999999})", "udp_port",
           "out of range: must be in [1, 65535] (got 99999999999)"},
          {R"({"udp_address": "localhost"})", "udp_address",
           "dotted IPv4 address (got \"localhost\")"},
          {R"({"publish_hz": 50})", "publish_hz", "must be 100"},
          {R"({"camera_timeout_ms": 0})", "camera_timeout_ms", "[10, 60000] (got 0)"},
          {R"({"camera_latency_ms": -1})", "camera_latency_ms", "[0, 1000] (got -1)"},
          {R"({"duration_s": -1})", "duration_s", ">= 0 (got -1)"},
          {R"({"control_port": 70000})", "control_port",
           "must be 0 (off) or in [1, 65535] (got 70000)"},
          {R"({"ros2_domain_id": 233})", "ros2_domain_id",
           "must be -1 (off) or in [0, 232] (got 233)"},
          {R"({"ros2_namespace": "omniloc"})", "ros2_namespace", "absolute ROS 2 name"},
          {R"({"ros2_namespace": "/a//b"})", "ros2_namespace", "absolute ROS 2 name"},
          {R"({"grid_step_cm": 1})", "grid_step_cm", "[2, 50] (got 1)"},
          {R"({"http_port": -1})", "http_port", "must be 0 (off) or in [1, 65535] (got -1)"},
          {R"({"http_port": 65536})", "http_port", "must be 0 (off) or in [1, 65535] (got 65536)"},
          {R"({"http_address": "localhost"})", "http_address",
           "dotted IPv4 address (got \"localhost\")"},
          {R"({"camera": ""})", "camera", "must not be empty"},
          {"{\"udp_port\" 5600}", "udp_port", "not valid JSON: parse error at line 1"},
          {"{\"udp_port\": 5600 \"camera\": \"0\"}", "", "not valid JSON: parse error at line 1"},
          {"[1, 2]", "", "must be an object"},
      });
}

TEST(DaemonConfig, MissingFileAndDirectoryAreNamed) {
  EXPECT_EQ(error_of([] { (void)load_daemon_config("/nonexistent/omnilocd.json"); }),
            "/nonexistent/omnilocd.json: no such file");
  const std::string dir = test::temp_dir().string();
  EXPECT_EQ(error_of([&] { (void)load_daemon_config(dir); }),
            dir + ": is a directory, not a JSON file");
  EXPECT_THROW((void)load_daemon_config(dir), ConfigError);
}

// The command line as omnilocd and omnilocd-sim parse it (CLI11, host/apps/common/daemon_cli.hpp).
struct CommandLine {
  CLI::App app{"test", "omnilocd"};
  cli::DaemonCommandLine cl;
  CommandLine() { cli::add_daemon_options(app, cl); }
  DaemonConfig parse(std::vector<std::string> args) {
    std::vector<char*> argv{const_cast<char*>("omnilocd")};
    for (auto& a : args) argv.push_back(a.data());
    app.parse(static_cast<int>(argv.size()), argv.data());
    return cli::daemon_config_from(cl);
  }
};

DaemonConfig parse_flags(std::vector<std::string> args) {
  return CommandLine().parse(std::move(args));
}

std::string flag_error(std::vector<std::string> args) {
  try {
    (void)parse_flags(std::move(args));
  } catch (const CLI::ParseError& e) {
    return std::string("usage: ") + e.what();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(DaemonConfig, FlagsOverrideTheFileWhateverTheirOrder) {
  const auto p =
      test::write_file("flags.json", R"({"udp_port": 6001, "camera": "none", "duration_s": 3})");
  const std::string ps = p.string();
  CommandLine c;
  const DaemonConfig a = c.parse({"--udp-port", "6002", "--config", ps, "--camera-fps=15"});
  EXPECT_EQ(c.cl.config_path, ps);
  EXPECT_EQ(a.udp_port, 6002);  // flag beats file
  EXPECT_EQ(a.camera, "none");  // file beats default
  EXPECT_EQ(a.duration_s, 3.0);
  EXPECT_EQ(a.camera_fps, 15.0);  // --key=value as well as --key value
  // A text key takes the flag's text as it is (a camera index is the string "1").
  EXPECT_EQ(parse_flags({"--camera", "1"}).camera, "1");
  // --http is the short form of --http-port (the live view).
  EXPECT_EQ(parse_flags({"--http", "8081"}).http_port, 8081);
  EXPECT_EQ(parse_flags({"--http-port=8082"}).http_port, 8082);
  // No flag at all: the defaults, valid on their own.
  EXPECT_TRUE(parse_flags({}) == DaemonConfig{});
}

TEST(DaemonConfig, BadFlagsAreRefusedWithTheFlagNamed) {
  EXPECT_EQ(flag_error({"--udp-port", "abc"}),
            "command line:udp_port: must be a number (got \"abc\")");
  EXPECT_EQ(flag_error({"--udp-port=5600.5"}).rfind("command line:udp_port: must be an integer", 0),
            0u);
  EXPECT_EQ(flag_error({"--camera-fps", "nan"}),
            "command line:camera_fps: must be a number (got \"nan\")");
  EXPECT_EQ(flag_error({"--udp-port", "0"}),
            "command line:udp_port: out of range: must be in [1, 65535] (got 0)");
  // What is not an option of the table is refused by the parser, naming it.
  for (const auto& [args, named] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--no-such-key", "1"}, "--no-such-key"},
           {{"--board", "sim"}, "--board"},
           {{"stray"}, "stray"},
           {{"--udp-port"}, "--udp-port"}}) {
    const std::string e = flag_error(args);
    EXPECT_EQ(e.rfind("usage: ", 0), 0u) << e;
    EXPECT_NE(e.find(named), std::string::npos) << e;
  }
}

TEST(DaemonConfig, HelpListsEveryKeyAsAFlagWithItsDefault) {
  CommandLine c;
  const std::string help = c.app.help();
  for (std::string flag : kEveryKey) {
    for (char& ch : flag)
      if (ch == '_') ch = '-';
    // "--udp-port NUMBER", or a switch's "--record-overwrite, --no-record-overwrite".
    const bool listed = help.find("--" + flag + " ") != std::string::npos ||
                        help.find("--" + flag + ",") != std::string::npos;
    EXPECT_TRUE(listed) << flag << "\n" << help;
  }
  EXPECT_NE(help.find("--config"), std::string::npos);
  EXPECT_NE(help.find("UDP port the poses are sent to"), std::string::npos);
  EXPECT_NE(help.find("5600"), std::string::npos);
  EXPECT_NE(help.find("\"fira-robosot\""), std::string::npos);
  EXPECT_NE(help.find("\"\""), std::string::npos);  // an empty default is shown as ""
  for (const char* gone : {"--board ", "--sim-", "sim |"})
    EXPECT_EQ(help.find(gone), std::string::npos) << gone;
}

// A switch (a boolean key) is a flag: --record-overwrite sets it, --no-record-overwrite undoes a
// config file's true, and --help shows no value for it (it once read "NUMBER=false").
TEST(DaemonConfig, SwitchesAreFlags) {
  EXPECT_FALSE(parse_flags({}).record_overwrite);
  EXPECT_TRUE(parse_flags({"--record-overwrite"}).record_overwrite);
  const auto p = test::write_file("overwrite.json", R"({"record_overwrite": true})");
  EXPECT_TRUE(parse_flags({"--config", p.string()}).record_overwrite);
  EXPECT_FALSE(parse_flags({"--config", p.string(), "--no-record-overwrite"}).record_overwrite);
  EXPECT_FALSE(parse_flags({"--no-record-overwrite", "--config", p.string()}).record_overwrite);
  // A value after the flag is a stray argument, refused by the parser.
  EXPECT_EQ(flag_error({"--record-overwrite", "true"}).rfind("usage: ", 0), 0u);
  const std::string help = CommandLine().app.help();
  for (const char* shown : {"NUMBER=false", "NUMBER=true", "=false", "=true"})
    EXPECT_EQ(help.find(shown), std::string::npos) << shown << "\n" << help;
  EXPECT_NE(help.find("--no-record-overwrite"), std::string::npos) << help;
}

// Issue 17.3: log levels from the key table (--log-level, the config file) and -v / -q on top.
TEST(DaemonCommandLine, LogLevelFromTheKeyAndVerboseQuietFlags) {
  const auto level = [](std::vector<std::string> args) {
    CommandLine c;
    const DaemonConfig cfg = c.parse(std::move(args));
    return cli::daemon_logger(cfg, c.cl, "omnilocd").threshold();
  };
  EXPECT_EQ(level({}), LogLevel::kInfo);
  EXPECT_EQ(level({"--log-level", "warning"}), LogLevel::kWarning);
  EXPECT_EQ(level({"-v"}), LogLevel::kDebug);
  EXPECT_EQ(level({"-q"}), LogLevel::kWarning);
  EXPECT_EQ(level({"-qq"}), LogLevel::kError);
  EXPECT_EQ(level({"--log-level=error", "-v"}), LogLevel::kWarning);
  EXPECT_NE(flag_error({"--log-level", "loud"}).find("log_level"), std::string::npos);
}

}  // namespace
}  // namespace omniloc::daemon
