// The value axis of the stacked-bar plots: round gridlines that reach the tallest bar.
#include <gtest/gtest.h>

#include <cmath>

#include "experiments/plot.hpp"

namespace deformlab::test {
namespace {

TEST(Plot, TickStepsAreRoundAndReachTheTop) {
  EXPECT_DOUBLE_EQ(plot::tick_step(100), 25);
  EXPECT_DOUBLE_EQ(plot::tick_step(100.026), 25);  // a stack a little over 100%: 5 steps to 125
  EXPECT_DOUBLE_EQ(plot::tick_step(7.3), 1);
  EXPECT_DOUBLE_EQ(plot::tick_step(19.99), 2.5);
  EXPECT_DOUBLE_EQ(plot::tick_step(0.04), 0.01);
  for (double top = 0.013; top < 5000; top *= 1.37) {
    const double step = plot::tick_step(top);
    const double steps = std::ceil(top / step - 1e-9);
    EXPECT_GE(steps, 4) << top;
    EXPECT_LE(steps, 8) << top;
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-12));
    EXPECT_TRUE(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 || std::abs(mantissa - 2.5) < 1e-9 ||
                std::abs(mantissa - 5) < 1e-9)
        << top << " gives " << step;
  }
}

}  // namespace
}  // namespace deformlab::test
