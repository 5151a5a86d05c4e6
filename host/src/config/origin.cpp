// Where a config value came from, and the messages that name it.
#include <charconv>
#include <cmath>

#include "omniloc/config.hpp"

namespace omniloc::config {

Origin Origin::operator/(std::string_view key) const {
  return Origin(source_, path_.empty() ? std::string(key) : path_ + "." + std::string(key));
}

Origin Origin::operator[](std::size_t index) const {
  return Origin(source_, path_ + "[" + std::to_string(index) + "]");
}

std::string Origin::str() const {
  return path_.empty() ? source_ : source_ + ":" + path_;
}

void Origin::fail(std::string_view why) const {
  throw ConfigError(str() + ": " + std::string(why));
}

void Origin::fail(std::string_view why, std::string_view got) const {
  throw ConfigError(str() + ": " + std::string(why) + " (got " + std::string(got) + ")");
}

std::string show(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buf[32];
  // Whole numbers in full (40000000, not 4e+07: clock rates and counts read as written).
  const bool whole = value == std::floor(value) && std::abs(value) < 1e15;
  const auto [end, ec] = whole
                             ? std::to_chars(buf, buf + sizeof buf, value, std::chars_format::fixed)
                             : std::to_chars(buf, buf + sizeof buf, value);
  return ec == std::errc() ? std::string(buf, end) : std::string("?");
}

std::string show(std::string_view text) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "literal" + string.
  std::string s(1, '"');
  s.append(text);
  s.push_back('"');
  return s;
}

std::string show(std::initializer_list<double> values) {
  std::string s(1, '[');
  for (const double v : values) {
    if (s.size() > 1) s.append(", ");
    s.append(show(v));
  }
  s.push_back(']');
  return s;
}

void require(bool ok, const Origin& at, std::string_view why, double got) {
  if (!ok) at.fail(why, show(got));
}

void require(bool ok, const Origin& at, std::string_view why, std::string_view got) {
  if (!ok) at.fail(why, got);
}

}  // namespace omniloc::config
