// Harness: the one strict number parser of every command line and config reader
// (strict_number.hpp). Input: byte 0 picks the function and its range, the rest is the text (or,
// for exact_int / checked_double, 8 bytes of a double). Each result is compared with an
// independent reading: integers digit by digit in 128 bits, decimals by strtod over the grammar
// -?(digits[.digits] | .digits)([eE][+-]?digits)? ; accepted exactly when the reference says the
// text is a number of the kind asked for, in range, with the same value; refused with NumberError.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "fuzz_common.hpp"
#include "omniloc/detail/strict_number.hpp"

namespace {

using omniloc::NumberError;
using omniloc::fuzz::fuzz_check;

constexpr std::int64_t kI64Min = std::numeric_limits<std::int64_t>::min();
constexpr std::int64_t kI64Max = std::numeric_limits<std::int64_t>::max();
constexpr std::uint64_t kU64Max = std::numeric_limits<std::uint64_t>::max();

struct IntRange {
  std::int64_t min, max;
};
constexpr IntRange kIntRanges[] = {{kI64Min, kI64Max},
                                   {0, 65535},
                                   {1, 65535},
                                   {-1, 1},
                                   {-(std::int64_t{1} << 53), std::int64_t{1} << 53},
                                   {7, 7}};
struct UintRange {
  std::uint64_t min, max;
};
constexpr UintRange kUintRanges[] = {
    {0, kU64Max}, {0, 65535}, {1, std::uint64_t{1} << 53}, {kU64Max, kU64Max}};
struct DoubleRange {
  double min, max;
};
constexpr DoubleRange kDoubleRanges[] = {
    {-std::numeric_limits<double>::max(), std::numeric_limits<double>::max()},
    {0.0, 1e4},
    {-360.0, 360.0},
    {1e-300, 1e300},
    {0.5, 0.5}};

/// The integer `text` spells (optional '-' for signed, then one or more digits), or nullopt.
std::optional<__int128> reference_integer(std::string_view text, bool allow_minus) {
  std::size_t i = 0;
  bool neg = false;
  if (allow_minus && i < text.size() && text[i] == '-') {
    neg = true;
    ++i;
  }
  if (i == text.size()) return std::nullopt;
  __int128 v = 0;
  for (; i < text.size(); ++i) {
    if (text[i] < '0' || text[i] > '9') return std::nullopt;
    v = v * 10 + (text[i] - '0');
    if (v > (static_cast<__int128>(1) << 70))
      v = static_cast<__int128>(1) << 70;  // beyond any range: saturate
  }
  return neg ? -v : v;
}

bool digits(std::string_view t, std::size_t& i) {
  const std::size_t start = i;
  while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
  return i > start;
}

/// True if `text` is in the decimal grammar of parse_double.
bool decimal_grammar(std::string_view t) {
  std::size_t i = 0;
  if (i < t.size() && t[i] == '-') ++i;
  const bool int_part = digits(t, i);
  bool frac_part = false;
  if (i < t.size() && t[i] == '.') {
    ++i;
    frac_part = digits(t, i);
  }
  if (!int_part && !frac_part) return false;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    if (!digits(t, i)) return false;
  }
  return i == t.size();
}

template <class F>
bool refused(F&& f) {
  try {
    f();
    return false;
  } catch (const NumberError& e) {
    fuzz_check(std::strstr(e.what(), "fuzz-setting: must be ") == e.what(),
               "a NumberError does not name the setting");
    return true;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const unsigned mode = data[0] % 5;
  const unsigned pick = data[0] / 5;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  const char* what = "fuzz-setting";

  if (mode == 0) {
    const IntRange r = kIntRanges[pick % std::size(kIntRanges)];
    const auto ref = reference_integer(text, true);
    const bool ok = ref && *ref >= r.min && *ref <= r.max;
    std::int64_t got = 0;
    const bool no = refused([&] { got = omniloc::parse_int(text, what, r.min, r.max); });
    fuzz_check(no == !ok, "parse_int accepts or refuses differently from the reference");
    if (ok) fuzz_check(got == *ref, "parse_int returned another value");
  } else if (mode == 1) {
    const UintRange r = kUintRanges[pick % std::size(kUintRanges)];
    const auto ref = reference_integer(text, false);
    const bool ok = ref && *ref >= r.min && *ref <= r.max;
    std::uint64_t got = 0;
    const bool no = refused([&] { got = omniloc::parse_uint(text, what, r.min, r.max); });
    fuzz_check(no == !ok, "parse_uint accepts or refuses differently from the reference");
    if (ok)
      fuzz_check(got == static_cast<std::uint64_t>(*ref), "parse_uint returned another value");
  } else if (mode == 2) {
    const DoubleRange r = kDoubleRanges[pick % std::size(kDoubleRanges)];
    double got = 0.0;
    const bool no = refused([&] { got = omniloc::parse_double(text, what, r.min, r.max); });
    if (!decimal_grammar(text)) {
      fuzz_check(no, "parse_double accepted a text outside the decimal grammar");
      return 0;
    }
    const std::string z(text);
    errno = 0;
    const double ref = std::strtod(z.c_str(), nullptr);
    if (errno == ERANGE)
      return 0;  // overflow (refused as not finite) or underflow: either answer is fine
    const bool ok = std::isfinite(ref) && ref >= r.min && ref <= r.max;
    fuzz_check(no == !ok, "parse_double accepts or refuses differently from strtod");
    if (ok) fuzz_check(got == ref, "parse_double returned another value than strtod");
  } else {
    double v = 0.0;
    std::memcpy(&v, text.data(), std::min(text.size(), sizeof v));
    if (mode == 3) {
      const IntRange r = kIntRanges[3 + pick % 3];  // the ranges representable exactly in a double
      const bool ok = std::isfinite(v) && v == std::trunc(v) && v >= static_cast<double>(r.min) &&
                      v <= static_cast<double>(r.max);
      std::int64_t got = 0;
      const bool no = refused([&] { got = omniloc::exact_int(v, what, r.min, r.max); });
      fuzz_check(no == !ok, "exact_int accepts or refuses wrongly");
      if (ok) fuzz_check(static_cast<double>(got) == v, "exact_int returned another value");
    } else {
      const DoubleRange r = kDoubleRanges[pick % std::size(kDoubleRanges)];
      const bool ok = std::isfinite(v) && v >= r.min && v <= r.max;
      const bool no = refused([&] { (void)omniloc::checked_double(v, what, r.min, r.max); });
      fuzz_check(no == !ok, "checked_double accepts or refuses wrongly");
    }
  }
  return 0;
}
