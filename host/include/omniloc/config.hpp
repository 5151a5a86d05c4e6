// The config layer's light half: the error every config reader throws, where a value came from
// ("<file>:<field path>", e.g. "robots/x.json:decoding" or "rec/meta.json:camera.radius_lut[2]"),
// the checks validate() functions are written with, and the lookup of the shared data files
// (common/<kind>/<name>.json). The JSON reader itself (nlohmann-json, key tables) is in
// config_reader.hpp, which only the sources that read files include.
#pragma once

#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <string_view>

namespace omniloc {

/// A configuration that cannot be used; what() is "<file>:<field path>: <why> (got <value>)",
/// e.g. "robots/x.json:decoding: must be 1, 2 or 4 (got 3)".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace config {

// config_reader.hpp
class Node;
template <class T>
struct Key;

/// Where a value came from: a source (a file, "command line") and a field path inside it.
class Origin {
 public:
  Origin(std::string source, std::string path = {})
      : source_(std::move(source)), path_(std::move(path)) {}
  Origin(const char* source) : source_(source) {}

  /// The member `key` of this object ("a" / "b" -> "a.b").
  [[nodiscard]] Origin operator/(std::string_view key) const;
  /// Element `index` of this array ("a" [2] -> "a[2]").
  [[nodiscard]] Origin operator[](std::size_t index) const;

  [[nodiscard]] const std::string& source() const { return source_; }
  [[nodiscard]] const std::string& path() const { return path_; }
  /// "<source>:<path>", or just the source at the top level.
  [[nodiscard]] std::string str() const;

  /// Throws ConfigError "<str()>: <why>".
  [[noreturn]] void fail(std::string_view why) const;
  /// Throws ConfigError "<str()>: <why> (got <got>)".
  [[noreturn]] void fail(std::string_view why, std::string_view got) const;

 private:
  std::string source_;
  std::string path_;
};

/// A number as the error messages show it: the shortest text that reads back to the same double.
[[nodiscard]] std::string show(double value);
/// A string as the error messages show it: in double quotes.
[[nodiscard]] std::string show(std::string_view text);
/// Numbers as a JSON array: "[1, 2.5]".
[[nodiscard]] std::string show(std::initializer_list<double> values);

/// validate() helpers: throw ConfigError "<at>: <why> (got <value>)" unless `ok`.
void require(bool ok, const Origin& at, std::string_view why, double got);
void require(bool ok, const Origin& at, std::string_view why, std::string_view got);

/// Resolves `name_or_path` in the data folder `kind` ("fields", "cameras", "robots", "localizer",
/// "omnilocd"): an existing file path is returned as is; otherwise `<kind>/<name>.json` is looked
/// up in $OMNILOC_DATA_DIR, then in `common/` of the current directory and its parents, then of the
/// executable's directory and its parents. Throws ConfigError naming the places searched when
/// nothing matches, or saying so when the path is a directory.
[[nodiscard]] std::filesystem::path resolve_data_file(const std::string& kind,
                                                      const std::string& name_or_path);

}  // namespace config

using config::resolve_data_file;

}  // namespace omniloc
