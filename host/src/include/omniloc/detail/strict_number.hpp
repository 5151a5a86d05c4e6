// One strict parser for every number a user types or a file holds: the whole text, finite, in
// range, integers exact. Every command line and configuration reader goes through it, so that
// "12x", "nan", "1e30" for an int, "1.7" for a count or "-1" for an unsigned value are refused
// with the same message shape everywhere:
//   "<what>: must be an integer in [0, 65535] (got '56066666666660')".
#pragma once

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>

namespace omniloc {

/// A number that is not one, or out of its range; what() names the setting and quotes the text.
class NumberError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A whole decimal integer in [min, max] ("42", "-3"; not "4.0", "0x10", " 1", "1e3").
[[nodiscard]] std::int64_t parse_int(std::string_view text, std::string_view what,
                                     std::int64_t min = std::numeric_limits<std::int64_t>::min(),
                                     std::int64_t max = std::numeric_limits<std::int64_t>::max());

/// A whole decimal integer in [min, max] over the full unsigned 64-bit range; "-1" is refused,
/// never wrapped.
[[nodiscard]] std::uint64_t parse_uint(
    std::string_view text, std::string_view what, std::uint64_t min = 0,
    std::uint64_t max = std::numeric_limits<std::uint64_t>::max());

/// A whole finite decimal number in [min, max] ("12", "-3.5", "1e2"; not "inf", "nan", "1,5").
[[nodiscard]] double parse_double(std::string_view text, std::string_view what,
                                  double min = -std::numeric_limits<double>::max(),
                                  double max = std::numeric_limits<double>::max());

/// A value already read as a double (a JSON number) that must be an exact integer in [min, max]:
/// 3.0 is 3, 3.5, 1e300 and NaN are refused. The range must be representable exactly (|x| < 2^53).
[[nodiscard]] std::int64_t exact_int(double value, std::string_view what, std::int64_t min,
                                     std::int64_t max);

/// A double that must be finite and in [min, max].
[[nodiscard]] double checked_double(double value, std::string_view what, double min, double max);

}  // namespace omniloc
