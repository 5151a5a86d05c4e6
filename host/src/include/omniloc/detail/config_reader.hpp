// The typed JSON reader of the config layer, on nlohmann-json (Debian nlohmann-json3-dev).
//
// parse_json_file / parse_json_text read a document and refuse what nlohmann would accept
// silently: a key twice in one object (nlohmann keeps one of them) is an error naming its path.
// A Node is one value with its Origin; its typed accessors refuse wrong types (a boolean is not a
// number, 500.0 is not an integer, 1 is not a boolean), non-finite numbers and integers outside the
// member's type.
//
// A component describes its keys once, in a KeyTable: key name -> struct member (or a custom
// read/write), required or optional, and a help text. read_keys() drives the reading from it
// (unknown keys refused, required keys checked, each value read with the member's Codec) and
// write_keys() the writing back (meta.json, --help defaults). Range checks are not here: each
// component's validate() does them, with the same "<file>:<path>: <why> (got <value>)" messages.
#pragma once

#include <algorithm>
#include <array>
#include <concepts>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "omniloc/config.hpp"

namespace omniloc::config {

/// Keeps the keys in file order, so errors and written files follow the order a person reads.
using Json = nlohmann::ordered_json;

/// One JSON value and where it came from. Refers to the Json it was made from (keep that alive).
class Node {
 public:
  Node(const Json& json, Origin origin) : json_(&json), origin_(std::move(origin)) {}

  [[nodiscard]] const Json& json() const { return *json_; }
  [[nodiscard]] const Origin& origin() const { return origin_; }
  /// The value as the error messages show it (JSON text, shortened when long).
  [[nodiscard]] std::string shown() const;
  /// Throws ConfigError "<origin>: <why> (got <value>)".
  [[noreturn]] void fail(std::string_view why) const;

  void expect_object() const;
  /// Checks the value is an array (of exactly `size` elements when given); returns its size.
  std::size_t expect_array(std::optional<std::size_t> size = std::nullopt) const;
  [[nodiscard]] bool has(std::string_view key) const;
  /// The member `key` of an object (which must have it).
  [[nodiscard]] Node operator/(std::string_view key) const;
  /// Element `index` of an array.
  [[nodiscard]] Node operator[](std::size_t index) const;

  /// A JSON number (integer or not), finite.
  [[nodiscard]] double number() const;
  /// A JSON integer (500, not 500.0) within [lo, hi].
  [[nodiscard]] std::int64_t integer(std::int64_t lo, std::int64_t hi) const;
  [[nodiscard]] std::uint64_t unsigned_integer() const;
  /// true or false (not 0 or 1).
  [[nodiscard]] bool boolean() const;
  [[nodiscard]] std::string text() const;

 private:
  const Json* json_;
  Origin origin_;
};

/// A parsed file: the JSON and its source name.
struct Document {
  Json json;
  std::string source;
  [[nodiscard]] Node root() const { return Node(json, Origin(source)); }
};

/// Reads and parses a JSON file. Throws ConfigError "<path>: ..." when it is missing, a directory,
/// unreadable, not JSON (with line and column, and the field being read), has a number beyond a
/// double (1e400), or a key twice in one object.
[[nodiscard]] Document parse_json_file(const std::filesystem::path& path);
/// The same for text in memory; `source` names it in errors.
[[nodiscard]] Document parse_json_text(std::string_view text, const std::string& source);

// --- Codecs: how a member type is read from and written to JSON ---------------------------------

/// What a key's value looks like, for reading it from a command-line flag.
enum class Kind { kText, kNumber, kBoolean, kOther };

template <class M>
struct Codec;

template <>
struct Codec<double> {
  static constexpr Kind kKind = Kind::kNumber;
  static double read(const Node& n) { return n.number(); }
  static Json write(double v) { return v; }
};

template <class I>
requires(std::is_integral_v<I> && !std::is_same_v<I, bool>) struct Codec<I> {
  static constexpr Kind kKind = Kind::kNumber;
  static I read(const Node& n) {
    if constexpr (std::is_unsigned_v<I> && sizeof(I) == 8) {
      return n.unsigned_integer();
    } else {
      return static_cast<I>(n.integer(std::numeric_limits<I>::min(),
                                      static_cast<std::int64_t>(std::numeric_limits<I>::max())));
    }
  }
  static Json write(I v) { return v; }
};

template <>
struct Codec<bool> {
  static constexpr Kind kKind = Kind::kBoolean;
  static bool read(const Node& n) { return n.boolean(); }
  static Json write(bool v) { return v; }
};

template <>
struct Codec<std::string> {
  static constexpr Kind kKind = Kind::kText;
  static std::string read(const Node& n) { return n.text(); }
  static Json write(const std::string& v) { return v; }
};

/// [x, y].
template <>
struct Codec<Eigen::Vector2d> {
  static constexpr Kind kKind = Kind::kOther;
  static Eigen::Vector2d read(const Node& n) {
    n.expect_array(2);
    return {n[0].number(), n[1].number()};
  }
  static Json write(const Eigen::Vector2d& v) { return Json::array({v.x(), v.y()}); }
};

template <class V>
struct Codec<std::vector<V>> {
  static constexpr Kind kKind = Kind::kOther;
  static std::vector<V> read(const Node& n) {
    const std::size_t size = n.expect_array();
    std::vector<V> out;
    out.reserve(size);
    for (std::size_t i = 0; i < size; ++i) out.push_back(Codec<V>::read(n[i]));
    return out;
  }
  static Json write(const std::vector<V>& v) {
    Json out = Json::array();
    for (const auto& e : v) out.push_back(Codec<V>::write(e));
    return out;
  }
};

template <class V, std::size_t N>
struct Codec<std::array<V, N>> {
  static constexpr Kind kKind = Kind::kOther;
  static std::array<V, N> read(const Node& n) {
    n.expect_array(N);
    std::array<V, N> out{};
    for (std::size_t i = 0; i < N; ++i) out[i] = Codec<V>::read(n[i]);
    return out;
  }
  static Json write(const std::array<V, N>& v) {
    Json out = Json::array();
    for (const auto& e : v) out.push_back(Codec<V>::write(e));
    return out;
  }
};

/// A fixed set of names for the values of M (an enum, or a string restricted to a few words).
template <class M>
using Choices = std::vector<std::pair<std::string, M>>;

template <class M>
M read_choice(const Node& n, const Choices<M>& choices) {
  const std::string s = n.text();
  for (const auto& [name, value] : choices)
    if (name == s) return value;
  std::string list;
  for (const auto& [name, value] : choices) list += (list.empty() ? "\"" : ", \"") + name + "\"";
  n.fail("must be one of " + list);
}

template <class M>
std::string choice_name(const M& value, const Choices<M>& choices) {
  for (const auto& [name, v] : choices)
    if (v == value) return name;
  return "?";
}

// --- Key tables ---------------------------------------------------------------------------------

enum class Need { kOptional, kRequired };

/// One key of a JSON object and the member of T it reads into and writes from.
template <class T>
struct Key {
  std::string name;
  Need need = Need::kOptional;
  Kind kind = Kind::kOther;
  std::function<void(const Node&, T&)> read;
  /// nullopt: nothing to write (a note key).
  std::function<std::optional<Json>(const T&)> write;
  std::string help;
};

template <class T>
using KeyTable = std::vector<Key<T>>;

/// A key read into `member` with its type's Codec.
template <class T, class M>
Key<T> key(std::string name, M T::*member, Need need = Need::kOptional, std::string help = {}) {
  return Key<T>{
      std::move(name),
      need,
      Codec<M>::kKind,
      [member](const Node& n, T& out) { out.*member = Codec<M>::read(n); },
      [member](const T& in) -> std::optional<Json> { return Codec<M>::write(in.*member); },
      std::move(help)};
}

/// An integer key with its own range [lo, hi]: a value outside it (also one beyond the member's
/// type) is refused as "out of range: must be in [lo, hi]", not with the type's limits.
template <class T, class M>
requires(std::is_integral_v<M> &&
         !std::is_same_v<M, bool>) Key<T> ranged(std::string name, M T::*member, std::int64_t lo,
                                                 std::int64_t hi, Need need = Need::kOptional,
                                                 std::string help = {}) {
  return Key<T>{
      std::move(name),
      need,
      Kind::kNumber,
      [member, lo, hi](const Node& n, T& out) { out.*member = static_cast<M>(n.integer(lo, hi)); },
      [member](const T& in) -> std::optional<Json> { return Codec<M>::write(in.*member); },
      std::move(help)};
}

/// A key whose value is one of a few names (an enum member, or a restricted string).
template <class T, class M>
Key<T> choice(std::string name, M T::*member, Choices<M> choices, Need need = Need::kOptional,
              std::string help = {}) {
  return Key<T>{std::move(name),
                need,
                Kind::kText,
                [member, choices](const Node& n, T& out) { out.*member = read_choice(n, choices); },
                [member, choices](const T& in) -> std::optional<Json> {
                  return choice_name(in.*member, choices);
                },
                std::move(help)};
}

/// A key with its own reading and writing (a shape the codecs do not cover).
template <class T>
Key<T> custom(std::string name, Need need, std::function<void(const Node&, T&)> read,
              std::function<Json(const T&)> write) {
  return Key<T>{
      std::move(name),
      need,
      Kind::kOther,
      std::move(read),
      [write = std::move(write)](const T& in) -> std::optional<Json> { return write(in); },
      {}};
}

/// A free-text note for people reading the file ("description"): must be a string, is not kept.
template <class T>
Key<T> note(std::string name) {
  return Key<T>{std::move(name),
                Need::kOptional,
                Kind::kText,
                [](const Node& n, T&) { (void)n.text(); },
                [](const T&) -> std::optional<Json> { return std::nullopt; },
                {}};
}

/// An optional object kept for the record and not read into the struct (e.g. how a camera file was
/// made: `omniloc calibrate`'s fit report). It must be an object; what is inside is not checked.
template <class T>
Key<T> record(std::string name) {
  return Key<T>{std::move(name),
                Need::kOptional,
                Kind::kOther,
                [](const Node& n, T&) { n.expect_object(); },
                [](const T&) -> std::optional<Json> { return std::nullopt; },
                {}};
}

template <class T>
const Key<T>* find_key(const KeyTable<T>& table, std::string_view name) {
  for (const auto& k : table)
    if (k.name == name) return &k;
  return nullptr;
}

template <class T>
std::string key_names(const KeyTable<T>& table) {
  std::string s;
  for (const auto& k : table) s += (s.empty() ? "" : ", ") + k.name;
  return s;
}

/// Reads the object `object` into `out` by the table: an unknown key is refused, a missing
/// required key too; keys are read in the table's order (so a key may set up later ones), keys
/// not in the file keep out's values.
template <class T>
void read_keys(const Node& object, const KeyTable<T>& table, T& out) {
  object.expect_object();
  for (auto it = object.json().begin(); it != object.json().end(); ++it) {
    if (!find_key(table, it.key()))
      (object / it.key()).fail("unknown key (known keys: " + key_names(table) + ")");
  }
  for (const auto& k : table) {
    if (object.has(k.name))
      k.read(object / k.name, out);
    else if (k.need == Need::kRequired)
      (object.origin() / k.name).fail("missing (required)");
  }
}

/// The object the table describes, in table order; only the required keys with kRequired.
template <class T>
Json write_keys(const T& in, const KeyTable<T>& table, Need which = Need::kOptional) {
  Json out = Json::object();
  for (const auto& k : table) {
    if (which == Need::kRequired && k.need != Need::kRequired) continue;
    if (auto v = k.write(in)) out[k.name] = std::move(*v);
  }
  return out;
}

/// A key holding a nested object whose keys (`sub`) are members of T itself (e.g. a camera's
/// "mask" {body_radius_px, masts}).
template <class T>
Key<T> group(std::string name, KeyTable<T> sub, Need need = Need::kOptional) {
  return Key<T>{std::move(name),
                need,
                Kind::kOther,
                [sub](const Node& n, T& out) { read_keys(n, sub, out); },
                [sub](const T& in) -> std::optional<Json> { return write_keys(in, sub); },
                {}};
}

/// A key holding a nested struct S with its own table.
template <class T, class S>
Key<T> nested(std::string name, S T::*member, KeyTable<S> sub, Need need = Need::kOptional) {
  return Key<T>{
      std::move(name),
      need,
      Kind::kOther,
      [member, sub](const Node& n, T& out) { read_keys(n, sub, out.*member); },
      [member, sub](const T& in) -> std::optional<Json> { return write_keys(in.*member, sub); },
      {}};
}

/// A Codec for a struct described by a table (an array element such as a camera's mast sector).
template <class S, const KeyTable<S>& (*Table)()>
struct TableCodec {
  static constexpr Kind kKind = Kind::kOther;
  static S read(const Node& n) {
    S out{};
    read_keys(n, Table(), out);
    return out;
  }
  static Json write(const S& v) { return write_keys(v, Table()); }
};

}  // namespace omniloc::config
