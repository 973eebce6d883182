// Numbers as the summaries print them: significant digits in fixed notation, durations in the
// unit that suits them, counts with their noun.
#include <gtest/gtest.h>

#include <limits>

#include "core/number_text.hpp"

namespace deformlab::test {
namespace {

TEST(NumberText, SignificantDigitsNeverUseAnExponent) {
  EXPECT_EQ(significant(0.003146, 4), "0.003146");
  EXPECT_EQ(significant(4.3e-05, 3), "0.0000430");
  EXPECT_EQ(significant(0.1761, 4), "0.1761");
  EXPECT_EQ(significant(1234.5, 3), "1234");  // no fewer integer digits than the number has
  EXPECT_EQ(significant(-2.5, 2), "-2.5");
  EXPECT_EQ(significant(0, 4), "0");
  // A carry into a new leading digit keeps the count of significant digits.
  EXPECT_EQ(significant(9.9996, 4), "10.00");
  EXPECT_EQ(significant(0.099996, 3), "0.100");
  EXPECT_EQ(significant(std::numeric_limits<double>::quiet_NaN(), 3), "nan");
  EXPECT_EQ(significant(1e300, 3).size(), 301u) << "every digit of a large number";
  EXPECT_EQ(significant(1e-300, 2).substr(0, 4), "0.00");
  // Trimmed, as %g would write them but never with an exponent.
  EXPECT_EQ(significant_trimmed(0.5, 3), "0.5");
  EXPECT_EQ(significant_trimmed(4.3e-05, 3), "0.000043");
  EXPECT_EQ(significant_trimmed(0.39, 2), "0.39");
  EXPECT_EQ(significant_trimmed(100, 3), "100");
  EXPECT_EQ(significant_trimmed(0.999999, 3), "1");
}

// A float as the decimal it was written as: 0.002, not 0.0020000000949949026.
TEST(NumberText, AFloatsShortestDecimal) {
  EXPECT_EQ(shortest_decimal(0.002f), 0.002);
  EXPECT_EQ(shortest_decimal(1e-5f), 1e-5);
  EXPECT_EQ(float(shortest_decimal(0.1f)), 0.1f);
  for (float f : {0.002f, 3e38f, 1.17549435e-38f, 16777217.0f, 0.3f}) EXPECT_EQ(float(shortest_decimal(f)), f) << f;
}

TEST(NumberText, DurationsTakeTheUnitThatSuitsThem) {
  EXPECT_EQ(duration_text(0), "0 s");
  EXPECT_EQ(duration_text(6.9e-08), "69.0 ns");
  EXPECT_EQ(duration_text(9.9996e-07), "1.00 µs");
  EXPECT_EQ(duration_text(4.532e-05), "45.3 µs");
  EXPECT_EQ(duration_text(0.009062), "9.06 ms");
  EXPECT_EQ(duration_text(0.9996), "1.00 s");
  EXPECT_EQ(duration_text(1.5), "1.50 s");
  EXPECT_EQ(duration_text(59.97), "1 min 00 s");
  EXPECT_EQ(duration_text(123), "2 min 03 s");
  EXPECT_EQ(duration_text(3725), "1 h 02 min");
  EXPECT_EQ(duration_text(3599.7), "1 h 00 min");
  EXPECT_EQ(duration_text(7199), "2 h 00 min") << "minutes rounded, as seconds are";
  EXPECT_EQ(duration_text(-0.25), "-250 ms");
  EXPECT_EQ(duration_text(std::numeric_limits<double>::infinity()), "inf s");
  EXPECT_EQ(duration_text(3.6e18), "1000000000000000 h");
}

TEST(NumberText, CountsTakeTheirNounsNumber) {
  EXPECT_EQ(counted(1, "node"), "1 node");
  EXPECT_EQ(counted(0, "spring"), "0 springs");
  EXPECT_EQ(counted(4096, "node"), "4096 nodes");
  EXPECT_EQ(counted(1, "tetrahedron", "tetrahedra"), "1 tetrahedron");
  EXPECT_EQ(counted(2, "tetrahedron", "tetrahedra"), "2 tetrahedra");
}

}  // namespace
}  // namespace deformlab::test
