// The config layer's reader itself (config_reader.hpp): what nlohmann accepts that the reader must
// not (duplicate keys, NaN/Infinity, 1e400), typed access (a boolean is not a number, a float is
// not an integer, 1 is not a boolean), key tables (unknown and missing keys, table order), error
// messages "<file>:<path>: <why> (got <value>)", and the data-file lookup.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "config_test_util.hpp"
#include "omniloc/config.hpp"
#include "omniloc/detail/config_reader.hpp"

namespace omniloc::config {
namespace {

using test::error_of;

std::string parse_error(const std::string& text) {
  return error_of([&] { (void)parse_json_text(text, "t.json"); });
}

TEST(ConfigParse, DuplicateKeysAreRefusedWithTheirPath) {
  // nlohmann alone keeps one of the two silently: the property the reader adds.
  EXPECT_EQ(nlohmann::ordered_json::parse(R"({"a": 1, "a": 2})").size(), 1u);
  EXPECT_EQ(
      parse_error(R"({"a": 1, "a": 2})"),
      "t.json:a: duplicate key: an object may give a key only once (got \"a\" a second time)");
  EXPECT_EQ(parse_error(R"({"a": {"b": [1, {"c": 1, "c": 1}]}})")
                .rfind("t.json:a.b[1].c: duplicate key", 0),
            0u)
      << parse_error(R"({"a": {"b": [1, {"c": 1, "c": 1}]}})");
  // The same key in two different objects is fine.
  EXPECT_NO_THROW((void)parse_json_text(
      R"({"a": {"x": 1}, "b": {"x": 1}, "c": [{"x": 1}, {"x": 2}]})", "t.json"));
}

TEST(ConfigParse, NanInfinityAndHugeNumbersAreRefusedWithTheField) {
  // JSON has no NaN or Infinity literal: nlohmann reports an invalid literal, with line and column.
  std::string e = parse_error("{\"a\": 1,\n \"b\": NaN}");
  EXPECT_EQ(e.rfind("t.json:b: not valid JSON: parse error at line 2, column", 0), 0u) << e;
  e = parse_error(R"({"a": [1, Infinity]})");
  EXPECT_EQ(e.rfind("t.json:a[1]: not valid JSON", 0), 0u) << e;
  e = parse_error(R"({"a": -Infinity})");
  EXPECT_EQ(e.rfind("t.json:a: not valid JSON", 0), 0u) << e;
  // 1e400 is valid JSON but beyond a double: nlohmann throws out_of_range 406.
  EXPECT_EQ(parse_error(R"({"x": {"y": 1e400}})"),
            "t.json:x.y: number out of range: beyond a double (got 1e400)");
  EXPECT_EQ(parse_error(R"({"y": -1e400})"),
            "t.json:y: number out of range: beyond a double (got -1e400)");
  // A syntax error at the top level names the file and the position.
  e = parse_error(R"({"a" 1})");
  EXPECT_NE(e.find("t.json:a: not valid JSON: parse error at line 1, column 6"), std::string::npos)
      << e;
}

TEST(ConfigParse, MissingFileAndDirectoryAreNamed) {
  EXPECT_EQ(error_of([] { (void)parse_json_file("/nonexistent/x.json"); }),
            "/nonexistent/x.json: no such file");
  const auto dir = test::temp_dir();
  EXPECT_EQ(error_of([&] { (void)parse_json_file(dir); }),
            dir.string() + ": is a directory, not a JSON file");
}

Document doc(const std::string& text) {
  return parse_json_text(text, "t.json");
}

TEST(ConfigNode, TypedAccessRefusesWrongTypes) {
  const Document d = doc(R"({"f": 2.5, "i": 7, "whole": 500.0, "b": true, "s": "x", "neg": -3,
                             "big": 18446744073709551615, "huge": 18446744073709551616})");
  const Node r = d.root();
  EXPECT_EQ((r / "f").number(), 2.5);
  EXPECT_EQ((r / "i").number(), 7.0);  // an integer is a number
  EXPECT_EQ((r / "i").integer(0, 10), 7);
  EXPECT_TRUE((r / "b").boolean());
  EXPECT_EQ((r / "s").text(), "x");
  EXPECT_EQ((r / "big").unsigned_integer(), 18446744073709551615u);
  auto err = [](const std::function<void()>& f) { return error_of(f); };
  EXPECT_EQ(err([&] { (void)(r / "b").number(); }),
            "t.json:b: must be a number, not a boolean (got true)");
  EXPECT_EQ(err([&] { (void)(r / "s").number(); }),
            "t.json:s: must be a number, not a string (got \"x\")");
  EXPECT_EQ(err([&] { (void)(r / "f").integer(0, 10); }),
            "t.json:f: must be an integer (written without a decimal point or exponent) (got 2.5)");
  EXPECT_EQ(err([&] {
              (void)(r / "whole").integer(0, 1000);
            }).rfind("t.json:whole: must be an integer", 0),
            0u);
  EXPECT_EQ(err([&] { (void)(r / "i").boolean(); }),
            "t.json:i: must be true or false, not a number (got 7)");
  EXPECT_EQ(err([&] { (void)(r / "i").text(); }),
            "t.json:i: must be a string, not a number (got 7)");
  EXPECT_EQ(err([&] { (void)(r / "i").integer(0, 5); }),
            "t.json:i: out of range: must be in [0, 5] (got 7)");
  EXPECT_EQ(err([&] { (void)(r / "neg").integer(0, 5); }),
            "t.json:neg: out of range: must be in [0, 5] (got -3)");
  EXPECT_EQ(err([&] { (void)(r / "neg").unsigned_integer(); }),
            "t.json:neg: out of range: must be >= 0 (got -3)");
  EXPECT_EQ(err([&] { (void)(r / "big").integer(0, 1000); }).rfind("t.json:big: out of range", 0),
            0u);
  // Beyond uint64, nlohmann makes a float: still not an integer.
  EXPECT_EQ(err([&] {
              (void)(r / "huge").unsigned_integer();
            }).rfind("t.json:huge: must be an integer", 0),
            0u);
  EXPECT_EQ(err([&] { (void)(r / "nothing"); }), "t.json:nothing: missing (required)");
}

// A small struct and table, to test the table machinery apart from any component.
enum class Colour { kRed, kBlue };
struct Inner {
  double x = 0.0;
  bool operator==(const Inner&) const = default;
};
struct Sample {
  double real = 1.0;
  int count = 2;
  std::uint64_t seed = 3;
  bool flag = false;
  std::string name = "n";
  Colour colour = Colour::kRed;
  std::vector<double> list{1.0};
  Inner inner;
  double grouped = 0.0;
  bool operator==(const Sample&) const = default;
};

const KeyTable<Sample>& sample_keys() {
  static const KeyTable<Sample> table = {
      key("real", &Sample::real, Need::kRequired),
      key("count", &Sample::count),
      key("seed", &Sample::seed),
      key("flag", &Sample::flag),
      key("name", &Sample::name),
      choice<Sample, Colour>("colour", &Sample::colour,
                             {{"red", Colour::kRed}, {"blue", Colour::kBlue}}),
      key("list", &Sample::list),
      nested("inner", &Sample::inner, KeyTable<Inner>{key("x", &Inner::x, Need::kRequired)}),
      group<Sample>("group", {key("grouped", &Sample::grouped)}),
      note<Sample>("description"),
  };
  return table;
}

Sample read_sample(const std::string& text) {
  const Document d = doc(text);
  Sample s;
  read_keys(d.root(), sample_keys(), s);
  return s;
}

TEST(ConfigKeyTable, ReadsEveryKindAndWritesItBack) {
  const Sample s =
      read_sample(R"({"real": 4.5, "count": -7, "seed": 18446744073709551615, "flag": true,
      "name": "a\"b\\c", "colour": "blue", "list": [1, 2.5], "inner": {"x": 9}, "group": {"grouped": 6},
      "description": "not kept"})");
  EXPECT_EQ(s.real, 4.5);
  EXPECT_EQ(s.count, -7);
  EXPECT_EQ(s.seed, 18446744073709551615u);
  EXPECT_TRUE(s.flag);
  EXPECT_EQ(s.name, "a\"b\\c");
  EXPECT_EQ(s.colour, Colour::kBlue);
  EXPECT_EQ(s.list, (std::vector<double>{1.0, 2.5}));
  EXPECT_EQ(s.inner.x, 9.0);
  EXPECT_EQ(s.grouped, 6.0);
  const Json written = write_keys(s, sample_keys());
  EXPECT_EQ(
      written.dump(),
      R"({"real":4.5,"count":-7,"seed":18446744073709551615,"flag":true,"name":"a\"b\\c","colour":"blue",)"
      R"("list":[1.0,2.5],"inner":{"x":9.0},"group":{"grouped":6.0}})");
  EXPECT_EQ(read_sample(written.dump()), s);
  EXPECT_EQ(write_keys(s, sample_keys(), Need::kRequired).dump(), R"({"real":4.5})");
}

TEST(ConfigKeyTable, UnknownMissingAndWronglyTypedKeysNameTheirPath) {
  auto err = [](const std::string& text) { return error_of([&] { (void)read_sample(text); }); };
  EXPECT_EQ(err(R"({"real": 1, "reel": 2})"),
            "t.json:reel: unknown key (known keys: real, count, seed, flag, name, colour, list, "
            "inner, group, "
            "description) (got 2)");
  EXPECT_EQ(err(R"({"count": 1})"), "t.json:real: missing (required)");
  EXPECT_EQ(err(R"({"real": 1, "inner": {}})"), "t.json:inner.x: missing (required)");
  EXPECT_EQ(err(R"({"real": 1, "inner": {"x": 1, "y": 2}})")
                .rfind("t.json:inner.y: unknown key (known keys: x)", 0),
            0u);
  EXPECT_EQ(err(R"({"real": 1, "group": {"grouped": false}})"),
            "t.json:group.grouped: must be a number, not a boolean (got false)");
  EXPECT_EQ(err(R"({"real": 1, "list": [1, "2"]})"),
            "t.json:list[1]: must be a number, not a string (got \"2\")");
  EXPECT_EQ(err(R"({"real": 1, "colour": "green"})"),
            "t.json:colour: must be one of \"red\", \"blue\" (got \"green\")");
  EXPECT_EQ(err(R"({"real": 1, "count": 3000000000})"),
            "t.json:count: out of range: must be in [-2147483648, 2147483647] (got 3000000000)");
  EXPECT_EQ(err(R"({"real": 1, "description": 3})"),
            "t.json:description: must be a string, not a number (got 3)");
  EXPECT_EQ(err(R"([1])"), "t.json: must be an object, not an array (got [1])");
}

TEST(ConfigOrigin, PathsAndNumbers) {
  const Origin o("f.json");
  EXPECT_EQ(o.str(), "f.json");
  EXPECT_EQ(((o / "robot" / "wheels")[2]).str(), "f.json:robot.wheels[2]");
  EXPECT_EQ(((o / "fuzzy" / "snap_ranges_cm")[1]).str(), "f.json:fuzzy.snap_ranges_cm[1]");
  EXPECT_EQ(show(0.1), "0.1");
  EXPECT_EQ(show(40e6), "40000000");
  EXPECT_EQ(show(3.0), "3");
  EXPECT_EQ(error_of([] { require(false, Origin("f.json") / "k", "must be > 0", -5.0); }),
            "f.json:k: must be > 0 (got -5)");
}

TEST(ConfigDataFiles, NamesPathsAndDirectories) {
  EXPECT_EQ(resolve_data_file("robots", "default").filename(), "default.json");
  const auto dir = test::temp_dir();
  EXPECT_EQ(error_of([&] { (void)resolve_data_file("robots", dir.string()); }),
            dir.string() + ": is a directory, not a JSON file");
  EXPECT_EQ(error_of([] { (void)resolve_data_file("robots", "/nonexistent/r.json"); }),
            "/nonexistent/r.json: no such file");
  const std::string e = error_of([] { (void)resolve_data_file("robots", "no_such_robot"); });
  EXPECT_EQ(e.rfind("no robots file named 'no_such_robot' (searched ", 0), 0u) << e;
  EXPECT_THROW((void)resolve_data_file("robots", "no_such_robot"), ConfigError);
}

}  // namespace
}  // namespace omniloc::config
