#include "omniloc/detail/strict_number.hpp"

#include <charconv>
#include <cmath>
#include <sstream>
#include <system_error>

namespace omniloc {
namespace {

[[noreturn]] void refuse(std::string_view what, const std::string& rule, std::string_view got) {
  std::ostringstream os;
  os << what << ": must be " << rule << " (got '" << got << "')";
  throw NumberError(os.str());
}

template <class T>
std::string range_text(const char* kind, T min, T max) {
  std::ostringstream os;
  os.precision(17);
  os << kind << " in [" << min << ", " << max << "]";
  return os.str();
}

template <class T>
T parse_integer(std::string_view text, std::string_view what, T min, T max) {
  const std::string rule = range_text("an integer", min, max);
  T value{};
  const char* first = text.data();
  const char* last = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(first, last, value, 10);
  if (text.empty() || ec == std::errc::invalid_argument || ptr != last) refuse(what, rule, text);
  if (ec == std::errc::result_out_of_range || value < min || value > max) refuse(what, rule, text);
  return value;
}

}  // namespace

std::int64_t parse_int(std::string_view text, std::string_view what, std::int64_t min,
                       std::int64_t max) {
  return parse_integer<std::int64_t>(text, what, min, max);
}

std::uint64_t parse_uint(std::string_view text, std::string_view what, std::uint64_t min,
                         std::uint64_t max) {
  // from_chars for an unsigned type refuses a leading '-' already; say so in the same words.
  return parse_integer<std::uint64_t>(text, what, min, max);
}

double parse_double(std::string_view text, std::string_view what, double min, double max) {
  const std::string rule = range_text("a finite number", min, max);
  double value = 0.0;
  const char* last = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), last, value, std::chars_format::general);
  if (text.empty() || ec != std::errc{} || ptr != last || !std::isfinite(value)) {
    refuse(what, rule, text);
  }
  if (value < min || value > max) refuse(what, rule, text);
  return value;
}

std::int64_t exact_int(double value, std::string_view what, std::int64_t min, std::int64_t max) {
  const std::string rule = range_text("an integer", min, max);
  std::ostringstream got;
  got.precision(17);
  got << value;
  if (!std::isfinite(value) || value != std::trunc(value) || value < static_cast<double>(min) ||
      value > static_cast<double>(max)) {
    refuse(what, rule, got.str());
  }
  return static_cast<std::int64_t>(value);
}

double checked_double(double value, std::string_view what, double min, double max) {
  std::ostringstream got;
  got.precision(17);
  got << value;
  if (!std::isfinite(value) || value < min || value > max) {
    refuse(what, range_text("a finite number", min, max), got.str());
  }
  return value;
}

}  // namespace omniloc
