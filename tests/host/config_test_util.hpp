// Helpers shared by the config tests: temporary JSON files, the message of the error a loader
// throws, and a check that it names the file and the field path ("<file>:<path>: <why>").
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace omniloc::test {

/// A fresh directory for this test (removed by the caller if it cares; /tmp is cleaned anyway).
inline std::filesystem::path temp_dir() {
  const auto* info = testing::UnitTest::GetInstance()->current_test_info();
  const auto dir =
      std::filesystem::temp_directory_path() / ("omniloc_cfg_" + std::to_string(::getpid()) + "_" +
                                                info->test_suite_name() + "_" + info->name());
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::filesystem::path write_file(const std::string& name, const std::string& text) {
  const auto p = temp_dir() / name;
  std::ofstream(p) << text;
  return p;
}

/// The what() of the std::exception `f` throws ("(no error)" when it does not throw).
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

/// Replaces the first `from` in `s` (which must be there).
inline std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << "'" << from << "' not in the text";
  if (p == std::string::npos) return s;
  return s.replace(p, from.size(), to);
}

/// One bad variant of a valid file, and what its error must say.
struct BadCase {
  std::string json;
  std::string path;  ///< field path the message must name after "<file>:" ("" = the file only)
  std::string why;   ///< a part of the message after it
};

/// Writes each case to a file, loads it with `load(path)` and checks the message is
/// "<file>:<path>: ..." (or "<file>: ..." for an empty path) and contains `why`.
inline void expect_errors(const std::function<void(const std::string&)>& load,
                          const std::vector<BadCase>& cases) {
  int i = 0;
  for (const BadCase& c : cases) {
    const std::string file = write_file("bad" + std::to_string(i++) + ".json", c.json).string();
    const std::string msg = error_of([&] { load(file); });
    const std::string where = file + (c.path.empty() ? "" : ":" + c.path) + ": ";
    EXPECT_EQ(msg.rfind(where, 0), 0u) << "want the message to start with '" << where
                                       << "'\n  json: " << c.json << "\n  got:  " << msg;
    EXPECT_NE(msg.find(c.why), std::string::npos)
        << "want '" << c.why << "'\n  json: " << c.json << "\n  got:  " << msg;
  }
}

/// The keys of a JSON object in a file, in file order (read with nlohmann directly, not with the
/// reader under test).
inline std::vector<std::string> keys_of(const nlohmann::ordered_json& object) {
  std::vector<std::string> out;
  for (auto it = object.begin(); it != object.end(); ++it) out.push_back(it.key());
  return out;
}

inline nlohmann::ordered_json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::ordered_json::parse(in);
}

}  // namespace omniloc::test
