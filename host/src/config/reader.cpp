// The JSON reader: parsing with duplicate-key detection and typed access to values.
#include <cmath>
#include <set>

#include "omniloc/detail/config_reader.hpp"
#include "omniloc/detail/file_read.hpp"

namespace omniloc::config {

namespace {

// nlohmann's what() starts with "[json.exception.parse_error.101] ": the bracket says nothing to a
// user.
std::string without_prefix(const std::string& what) {
  const auto close = what.find("] ");
  return what.rfind("[json.exception.", 0) == 0 && close != std::string::npos
             ? what.substr(close + 2)
             : what;
}

// The token nlohmann quotes in "number overflow parsing '1e400'".
std::string quoted_token(const std::string& what) {
  const auto a = what.find('\'');
  const auto b = what.rfind('\'');
  return a != std::string::npos && b > a ? what.substr(a + 1, b - a - 1) : std::string("?");
}

// Follows the parser's position (object keys, array indices) so that errors, including the
// parser's own, name the field, and refuses a key seen twice in one object: nlohmann would keep
// one of the two values silently.
class PathTracker {
 public:
  explicit PathTracker(const std::string& source) : root_(source) {}

  bool on_event(Json::parse_event_t event, const Json& parsed) {
    using E = Json::parse_event_t;
    switch (event) {
      case E::object_start:
        stack_.push_back({false, 0, {}, {}, child(true)});
        break;
      case E::array_start:
        stack_.push_back({true, 0, {}, {}, child(true)});
        break;
      case E::object_end:
      case E::array_end:
        stack_.pop_back();
        done_with_member();
        break;
      case E::key: {
        Frame& f = stack_.back();
        std::string k = parsed.get<std::string>();
        if (!f.keys.insert(k).second)
          (f.at / k).fail("duplicate key: an object may give a key only once",
                          show(k) + " a second time");
        f.key = std::move(k);
        break;
      }
      case E::value:
        (void)child(true);
        done_with_member();
        break;
    }
    return true;
  }

  /// Where the parser is (the value being read when it failed).
  [[nodiscard]] Origin here() { return child(false); }

 private:
  struct Frame {
    bool array;
    std::size_t next;
    std::set<std::string> keys;
    std::string key;
    Origin at;
  };
  // The element being read: the current key of an object (the object itself between two
  // members), the next index of an array.
  Origin child(bool consume) {
    if (stack_.empty()) return root_;
    Frame& f = stack_.back();
    if (f.array) return f.at[consume ? f.next++ : f.next];
    return f.key.empty() ? f.at : f.at / f.key;
  }
  // After a member's value an error (a missing comma) is the object's, not that member's.
  void done_with_member() {
    if (!stack_.empty() && !stack_.back().array) stack_.back().key.clear();
  }
  Origin root_;
  std::vector<Frame> stack_;
};

}  // namespace

Document parse_json_text(std::string_view text, const std::string& source) {
  PathTracker tracker(source);
  Document doc;
  doc.source = source;
  try {
    doc.json =
        Json::parse(text.begin(), text.end(), [&](int, Json::parse_event_t event, Json& parsed) {
          return tracker.on_event(event, parsed);
        });
  } catch (const Json::out_of_range& e) {
    // 1e400 and the like: JSON has no infinity, and nlohmann refuses what a double cannot hold.
    tracker.here().fail("number out of range: beyond a double", quoted_token(e.what()));
  } catch (const Json::exception& e) {
    // NaN and Infinity are not JSON either: they end up here as "invalid literal".
    const Origin at = tracker.here();
    throw ConfigError(at.str() + ": not valid JSON: " + without_prefix(e.what()));
  }
  return doc;
}

Document parse_json_file(const std::filesystem::path& path) {
  std::string text;
  try {
    text = read_file_bounded(path, kMaxJsonFileBytes, "JSON file");
  } catch (const FileReadError& e) {
    throw ConfigError(e.what());
  }
  return parse_json_text(text, path.string());
}

// --- Node
// -----------------------------------------------------------------------------------------

std::string Node::shown() const {
  std::string s = json_->dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

void Node::fail(std::string_view why) const {
  origin_.fail(why, shown());
}

namespace {
const char* type_phrase(const Json& j) {
  if (j.is_boolean()) return "a boolean";
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return "null";
}
}  // namespace

void Node::expect_object() const {
  if (!json_->is_object()) fail(std::string("must be an object, not ") + type_phrase(*json_));
}

std::size_t Node::expect_array(std::optional<std::size_t> size) const {
  if (!json_->is_array()) fail(std::string("must be an array, not ") + type_phrase(*json_));
  if (size && json_->size() != *size)
    fail("must be an array of " + std::to_string(*size) + " elements");
  return json_->size();
}

bool Node::has(std::string_view key) const {
  return json_->is_object() && json_->contains(key);
}

Node Node::operator/(std::string_view key) const {
  expect_object();
  if (!has(key)) (origin_ / key).fail("missing (required)");
  return Node(json_->at(std::string(key)), origin_ / key);
}

Node Node::operator[](std::size_t index) const {
  expect_array();
  if (index >= json_->size()) (origin_[index]).fail("missing (the array is too short)");
  return Node((*json_)[index], origin_[index]);
}

double Node::number() const {
  // nlohmann's is_number() is false for booleans, true for integers and floats.
  if (!json_->is_number()) fail(std::string("must be a number, not ") + type_phrase(*json_));
  const double v = json_->get<double>();
  if (!std::isfinite(v)) fail("must be a finite number");
  return v;
}

std::int64_t Node::integer(std::int64_t lo, std::int64_t hi) const {
  if (json_->is_number_float())
    fail("must be an integer (written without a decimal point or exponent)");
  if (!json_->is_number_integer())
    fail(std::string("must be an integer, not ") + type_phrase(*json_));
  if (json_->is_number_unsigned() && json_->get<std::uint64_t>() > static_cast<std::uint64_t>(hi))
    fail("out of range: must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  const std::int64_t v = json_->get<std::int64_t>();
  if (v < lo || v > hi)
    fail("out of range: must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

std::uint64_t Node::unsigned_integer() const {
  if (json_->is_number_float())
    fail("must be an integer (written without a decimal point or exponent)");
  if (!json_->is_number_integer())
    fail(std::string("must be an integer, not ") + type_phrase(*json_));
  if (!json_->is_number_unsigned()) fail("out of range: must be >= 0");
  return json_->get<std::uint64_t>();
}

bool Node::boolean() const {
  if (!json_->is_boolean()) fail(std::string("must be true or false, not ") + type_phrase(*json_));
  return json_->get<bool>();
}

std::string Node::text() const {
  if (!json_->is_string()) fail(std::string("must be a string, not ") + type_phrase(*json_));
  return json_->get<std::string>();
}

}  // namespace omniloc::config
