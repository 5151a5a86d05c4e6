// The simulator's programs run as a user runs them (child processes): `omnilocd-sim` (the robot's
// daemon on the simulated robot: Verilated board, rendered camera) publishes poses that match the
// simulator's truth and records a run that `omniloc replay` (the robot's tool) replays; `omniloc-sim
// demo` writes errors.csv and exits 0 when it fixed, 1 when it cannot (no camera). Truth comes from
// the simulator's truth.csv, not from the daemon.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <regex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "omniloc/regmap.hpp"

#include "omniloc/recording.hpp"
#include "udp_receiver.hpp"

namespace {

namespace fs = std::filesystem;
using namespace omniloc;

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("omniloc_test_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

/// Runs a command line; returns the exit status, its stdout+stderr in `output`.
int run(const std::string& cmd, const fs::path& log, std::string& output) {
  const int status = std::system((cmd + " >" + log.string() + " 2>&1").c_str());
  std::ifstream in(log);
  std::ostringstream os;
  os << in.rdbuf();
  output = os.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<nlohmann::json> parse_all(const std::vector<std::string>& grams) {
  std::vector<nlohmann::json> out;
  for (const auto& g : grams) out.push_back(nlohmann::json::parse(g));
  return out;
}

std::vector<std::vector<std::string>> read_csv(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

TEST(OmnilocdSim, PublishesPosesThatMatchTruthAndRecordsARunThatReplays) {
  const int seed = 3;
  std::printf("seed %d\n", seed);
  TempDir dir("omnilocd_sim");
  omniloc::test::UdpReceiver rx;
  ASSERT_GT(rx.port(), 0);
  const fs::path rec = dir.path / "rec";
  std::string out;
  const int rc = run(std::string(OMNILOCD_SIM_PATH) + " --trajectory circle --seed=" + std::to_string(seed) +
                         " --duration-s 2 --status-period-s 0 --udp-port " + std::to_string(rx.port()) +
                         " --record-dir " + rec.string(),
                     dir.path / "daemon.log", out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("stopped (duration)"), std::string::npos) << out;

  const auto grams = parse_all(rx.drain());
  ASSERT_GE(grams.size(), 190u) << "2 s of 10 ms windows";
  ASSERT_LE(grams.size(), 201u);
  const Recording recording = load_recording(rec);
  EXPECT_EQ(recording.windows.size(), grams.size()) << "one datagram per window, all recorded";
  EXPECT_EQ(recording.truth.size(), recording.windows.size()) << "truth.csv from the simulator, a row a window";
  EXPECT_GE(recording.frames.size(), 100u) << "60 Hz rendered camera";
  int fixed = 0;
  double max_err_cm = 0.0;
  for (std::size_t i = 0; i < grams.size(); ++i) {
    EXPECT_EQ(grams[i]["seq"].get<std::uint64_t>(), i + 1);
    const std::string status = grams[i]["status"];
    if (status != "ok") continue;
    const auto truth = truth_at(recording.truth, grams[i]["t_ms"].get<double>());
    ASSERT_TRUE(truth.has_value());
    max_err_cm = std::max(max_err_cm, std::hypot(grams[i]["x_cm"].get<double>() - truth->x_cm,
                                                 grams[i]["y_cm"].get<double>() - truth->y_cm));
    ++fixed;
  }
  std::printf("%zu datagrams, %d with status ok, max error %.2f cm against the simulator's truth\n", grams.size(),
              fixed, max_err_cm);
  EXPECT_GE(fixed, 150) << "a fix within the first half second";
  EXPECT_LT(max_err_cm, 10.0);

  // The robot's own replay tool reads what the simulated daemon recorded, and scores it on truth.
  const int replay_rc = run(std::string(OMNILOC_CLI_PATH) + " replay " + rec.string() + " --out " +
                                (dir.path / "poses.csv").string() + " --db " + (dir.path / "features.db").string(),
                            dir.path / "replay.log", out);
  ASSERT_EQ(replay_rc, 0) << out;
  EXPECT_EQ(read_csv(dir.path / "poses.csv").size(), recording.windows.size());
}

TEST(OmnilocdSim, RefusesABadSeedAndAnUnknownOption) {
  TempDir dir("omnilocd_sim_bad");
  std::string out;
  EXPECT_EQ(run(std::string(OMNILOCD_SIM_PATH) + " --seed 1.5", dir.path / "a.log", out), 2) << out;
  EXPECT_NE(out.find("--seed: must be an integer"), std::string::npos) << out;
  EXPECT_EQ(run(std::string(OMNILOCD_SIM_PATH) + " --seed 18446744073709551616", dir.path / "b.log", out), 2) << out;
  EXPECT_NE(run(std::string(OMNILOCD_SIM_PATH) + " --no-such-key 1", dir.path / "c.log", out), 0) << out;
  EXPECT_TRUE(out.find("no-such-key") != std::string::npos || out.find("no_such_key") != std::string::npos) << out;
}

TEST(OmnilocSimDemo, ShortRunFixesAndWritesErrorsCsvNoCameraFails) {
  TempDir dir("demo");
  std::string out;
  const int rc = run(std::string(OMNILOC_SIM_PATH) + " demo --duration 3 --out " + (dir.path / "ok").string(),
                     dir.path / "demo.log", out);
  ASSERT_EQ(rc, 0) << out;
  const auto rows = read_csv(dir.path / "ok" / "errors.csv");
  ASSERT_GE(rows.size(), 290u) << "3 s of 10 ms windows";
  ASSERT_LE(rows.size(), 301u);
  int checked = 0;
  for (const auto& r : rows) {
    ASSERT_EQ(r.size(), 10u);
    const double t_ms = std::stod(r[0]);
    const double err_cm = std::stod(r[8]);  // "nan" before the first fix
    if (t_ms < 1000.0) continue;
    ASSERT_TRUE(std::isfinite(err_cm)) << "no fix at t = " << t_ms;
    // The error column is the distance between the pose and truth columns, recomputed here.
    EXPECT_NEAR(err_cm, std::hypot(std::stod(r[4]) - std::stod(r[1]), std::stod(r[5]) - std::stod(r[2])), 2e-3);
    EXPECT_LT(err_cm, 10.0) << "t = " << t_ms;
    ++checked;
  }
  EXPECT_GE(checked, 190);
  EXPECT_TRUE(fs::exists(dir.path / "ok" / "paths.png"));
  EXPECT_NE(out.find("after the end of this run"), std::string::npos) << "the kidnapping is at 22.6 s\n" << out;

  const int rc_none = run(std::string(OMNILOC_SIM_PATH) + " demo --camera none --duration 1 --out " +
                              (dir.path / "none").string(),
                          dir.path / "none.log", out);
  EXPECT_EQ(rc_none, 1) << out;
  EXPECT_NE(out.find("FAILED: the daemon never had a fix"), std::string::npos) << out;
  EXPECT_EQ(run(std::string(OMNILOC_SIM_PATH) + " demo --seed -1", dir.path / "bad.log", out), 2) << out;
}

// Every program answers --version with its name, the project version CMake was given, the
// register-map version of common/regmap.json (0.1.0 today, read here from the generated header)
// and the tree's git revision, and --key=value works as --key value.
TEST(Programs, VersionAndKeyEqualsValue) {
  TempDir dir("versions");
  const auto v = regmap::kVersionValue;
  const std::string regmap_version = std::to_string(regmap::kVersionMajor.get(v)) + "." +
                                     std::to_string(regmap::kVersionMinor.get(v)) + "." +
                                     std::to_string(regmap::kVersionPatch.get(v));
  const std::regex line("^(omniloc|omniloc-sim|omnilocd-sim|omnilocd) " + std::regex_replace(std::string(OMNILOC_PROJECT_VERSION), std::regex("\\."), "\\.") +
                        " \\(register map " + std::regex_replace(regmap_version, std::regex("\\."), "\\.") +
                        ", board ID 0x4F4D4E4C, git ([0-9a-f]{7,40}(-dirty)?|unknown)\\)\n$");
  for (const auto& [path, name] : std::vector<std::pair<std::string, std::string>>{
           {OMNILOC_CLI_PATH, "omniloc"}, {OMNILOC_SIM_PATH, "omniloc-sim"}, {OMNILOCD_SIM_PATH, "omnilocd-sim"}}) {
    std::string out;
    ASSERT_EQ(run(path + " --version", dir.path / "v.log", out), 0) << out;
    EXPECT_TRUE(std::regex_match(out, line)) << out;
    EXPECT_EQ(out.rfind(name + " ", 0), 0u) << out;
  }
  std::string out;
  EXPECT_EQ(run(std::string(OMNILOCD_SIM_PATH) + " --seed=abc", dir.path / "v.log", out), 2) << out;
  EXPECT_NE(out.find("--seed: must be an integer"), std::string::npos) << out;
  EXPECT_EQ(run(std::string(OMNILOCD_SIM_PATH) + " --udp-port=0", dir.path / "v.log", out), 2) << out;
  EXPECT_NE(out.find("udp_port: must be in [1, 65535] (got 0)"), std::string::npos) << out;
}

}  // namespace
