// The shared strict number parser: every case from issue 16 item 7 and the file-side ones of item
// 6, with the expected value or refusal written by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "omniloc/detail/strict_number.hpp"

namespace omniloc {
namespace {

std::string refusal(auto&& call) {
  try {
    call();
  } catch (const NumberError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(StrictNumber, IntegersAreWholeDecimalAndInRange) {
  EXPECT_EQ(parse_int("42", "--port", 0, 65535), 42);
  EXPECT_EQ(parse_int("-3", "x"), -3);
  EXPECT_EQ(parse_int("0", "x", 0, 0), 0);
  for (const char* bad : {"", "4.0", "0x10", " 1", "1 ", "1e3", "+1", "12x", "nan", "inf"}) {
    EXPECT_NE(refusal([&] { (void)parse_int(bad, "x"); }), "(accepted)") << bad;
  }
}

TEST(StrictNumber, AnOverflowingPortNamesTheTextNotAWrappedValue) {
  EXPECT_EQ(refusal([] { (void)parse_int("56066666666660", "--udp-port", 1, 65535); }),
            "--udp-port: must be an integer in [1, 65535] (got '56066666666660')");
  EXPECT_EQ(refusal([] { (void)parse_int("99999999999999999999999", "n"); }),
            "n: must be an integer in [-9223372036854775808, 9223372036854775807] "
            "(got '99999999999999999999999')");
}

TEST(StrictNumber, UnsignedValuesCoverTheWholeRangeAndNeverWrap) {
  EXPECT_EQ(parse_uint("18446744073709551615", "--seed"),
            std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(parse_uint("9007199254740993", "--sim-seed"), 9007199254740993ULL);  // above 2^53
  EXPECT_EQ(refusal([] { (void)parse_uint("-1", "--seed"); }),
            "--seed: must be an integer in [0, 18446744073709551615] (got '-1')");
  EXPECT_NE(refusal([] { (void)parse_uint("abc", "--seed"); }), "(accepted)");
  EXPECT_NE(refusal([] { (void)parse_uint("1.7", "--seed"); }), "(accepted)");
}

TEST(StrictNumber, DoublesAreFiniteWholeAndInRange) {
  EXPECT_DOUBLE_EQ(parse_double("-3.5", "x"), -3.5);
  EXPECT_DOUBLE_EQ(parse_double("1e2", "x"), 100.0);
  EXPECT_DOUBLE_EQ(parse_double("12", "x", 0.0, 20.0), 12.0);
  for (const char* bad : {"", "inf", "-inf", "nan", "1,5", "1e999", "12x", " 1", "0x1p3"}) {
    EXPECT_NE(refusal([&] { (void)parse_double(bad, "x"); }), "(accepted)") << bad;
  }
  EXPECT_EQ(refusal([] { (void)parse_double("25", "--speed-cm-s", 0.0, 20.0); }),
            "--speed-cm-s: must be a finite number in [0, 20] (got '25')");
}

TEST(StrictNumber, JsonNumbersMustBeExactIntegersWhereACountIsMeant) {
  EXPECT_EQ(exact_int(3.0, "decoding", 1, 4), 3);
  EXPECT_NE(refusal([] { (void)exact_int(3.5, "decoding", 1, 4); }), "(accepted)");
  EXPECT_NE(refusal([] { (void)exact_int(1e300, "n", 0, 100); }), "(accepted)");
  EXPECT_NE(refusal([] { (void)exact_int(std::nan(""), "n", 0, 100); }), "(accepted)");
  EXPECT_EQ(refusal([] { (void)exact_int(7.0, "mirrored", 0, 1); }),
            "mirrored: must be an integer in [0, 1] (got '7')");
}

TEST(StrictNumber, CheckedDoublesRefuseNonFiniteAndOutOfRange) {
  EXPECT_DOUBLE_EQ(checked_double(5.0, "x", 0.0, 10.0), 5.0);
  EXPECT_NE(refusal([] { (void)checked_double(1e-300, "window_period_ms", 1.0, 1000.0); }),
            "(accepted)");
  EXPECT_NE(refusal([] { (void)checked_double(INFINITY, "x", 0.0, 10.0); }), "(accepted)");
}

}  // namespace
}  // namespace omniloc
