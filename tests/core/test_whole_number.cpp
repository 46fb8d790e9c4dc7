// The command line's one whole-number reader (app/whole_number.hpp): what it takes and refuses.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "app/whole_number.hpp"

namespace {

using rig::cli::whole_number;
constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();

TEST(WholeNumber, TakesTheWholeTextAsDecimalDigits) {
  EXPECT_EQ(whole_number("0", 0), 0u);
  EXPECT_EQ(whole_number("7", 1), 7u);
  EXPECT_EQ(whole_number("18446744073709551615", 0), kMax);
}

TEST(WholeNumber, RefusesEmptySignBlankHexAndTrailingText) {
  for (const char* bad : {"", "+5", "-5", "-0", " 5", "5 ", "\t5", "0x10", "1e3", "5.0", "5,", "x"})
    EXPECT_EQ(whole_number(bad, 0), std::nullopt) << "'" << bad << "'";
}

// As every whole number on the command line (README): "010" is a typo, not 10 (nor octal 8).
TEST(WholeNumber, RefusesALeadingZero) {
  for (const char* bad : {"00", "05", "007", "0170000"}) EXPECT_EQ(whole_number(bad, 0), std::nullopt) << "'" << bad << "'";
}

TEST(WholeNumber, RefusesOverflowRatherThanWrapping) {
  EXPECT_EQ(whole_number("18446744073709551616", 0), std::nullopt);  // max uint64 + 1
  EXPECT_EQ(whole_number("99999999999999999999", 0), std::nullopt);  // 20 digits
  EXPECT_EQ(whole_number("123456789012345678901234567890", 0), std::nullopt);
}

TEST(WholeNumber, HoldsTheBounds) {
  EXPECT_EQ(whole_number("0", 1), std::nullopt);
  EXPECT_EQ(whole_number("1", 1), 1u);
  EXPECT_EQ(whole_number("4", 5), std::nullopt);
  EXPECT_EQ(whole_number("4294967295", 0, 4294967295u), 4294967295u);
  EXPECT_EQ(whole_number("4294967296", 0, 4294967295u), std::nullopt);
  EXPECT_EQ(whole_number(std::string_view("12345").substr(0, 2), 0), 12u);  // a view, not a C string
}

}  // namespace
