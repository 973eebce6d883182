// ClockWatch: the GPU's SM clock over timed work, read through NVML where the NVIDIA driver is
// there (the GPU machine), and nothing where it is not (CI); the summaries' text and JSON.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/clock_watch.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

ClockSummary summary(unsigned lo, unsigned median, unsigned hi, double slowed, std::uint64_t reasons) {
  ClockSummary s;
  s.device = "NVIDIA H100 80GB HBM3, 00000000:1B:00.0";
  s.samples = 40;
  s.sm_mhz_min = lo;
  s.sm_mhz_median = median;
  s.sm_mhz_max = hi;
  s.sm_mhz_top = 1980;
  s.slowed = slowed;
  s.reasons = reasons;
  return s;
}

TEST(ClockWatch, NamesOnlyTheReasonsThatLowerTheClockUnderLoad) {
  EXPECT_EQ(slowdown_names(0x1 | 0x2 | 0x10 | 0x100), "");  // idle, application clocks, sync boost, display
  EXPECT_EQ(slowdown_names(0x4), "power cap");
  EXPECT_EQ(slowdown_names(0x4 | 0x40 | 0x1), "power cap, thermal slowdown (hardware)");
  EXPECT_EQ(slowdown_names(0x8 | 0x20 | 0x80), "hardware slowdown, thermal slowdown (software), power brake");
}

TEST(ClockWatch, SummaryRoundTripsThroughJson) {
  const ClockSummary s = summary(1485, 1980, 1980, 0.25, 0x4);
  const nlohmann::json j = to_json(s);
  EXPECT_EQ(j["slowdowns"], "power cap");
  const ClockSummary back = clock_summary(j);
  EXPECT_EQ(back.device, s.device);
  EXPECT_EQ(back.samples, 40);
  EXPECT_EQ(back.sm_mhz_min, 1485u);
  EXPECT_EQ(back.sm_mhz_median, 1980u);
  EXPECT_EQ(back.sm_mhz_max, 1980u);
  EXPECT_EQ(back.sm_mhz_top, 1980u);
  EXPECT_DOUBLE_EQ(back.slowed, 0.25);
  EXPECT_EQ(back.reasons, 0x4u);
  EXPECT_TRUE(to_json(ClockSummary{}).is_null());
  EXPECT_FALSE(clock_summary(nullptr).watched());
}

TEST(ClockWatch, DescribesTheRangeAndTheSlowdowns) {
  EXPECT_EQ(describe(summary(1485, 1980, 1980, 0.25, 0x4)),
            "SM clock 1485-1980 MHz (median 1980, top 1980); power cap in 25% of 40 samples (NVML, every 5 ms, "
            "NVIDIA H100 80GB HBM3, 00000000:1B:00.0)");
  EXPECT_NE(describe(summary(1980, 1980, 1980, 0, 0)).find("no slowdown in any of 40 samples"), std::string::npos);
  EXPECT_NE(describe(ClockSummary{}).find("not read"), std::string::npos);
}

TEST(ClockWatch, TallyNamesTheSlowedCasesAndTheRangeOfTheirMedians) {
  ClockTally t;
  EXPECT_TRUE(t.empty());
  EXPECT_EQ(t.describe("case"), "");
  t.add("unwatched", ClockSummary{});
  EXPECT_TRUE(t.empty());
  t.add("a", summary(1980, 1980, 1980, 0, 0));
  t.add("b", summary(1410, 1485, 1980, 0.4, 0x4));
  t.add("c", summary(1965, 1980, 1980, 0, 0));
  EXPECT_EQ(t.describe("case"),
            "the cases' median SM clocks 1485-1980 MHz; 1 of 3 cases timed while a slowdown held the clock down: "
            "b (power cap in 40% of samples, 1410-1980 MHz)");
  EXPECT_NE(t.describe("case", true).find("held the clock down:\n  b (power cap"), std::string::npos);
  ClockTally calm;
  calm.add("a", summary(1980, 1980, 1980, 0, 0));
  calm.add("b", summary(1965, 1965, 1980, 0, 0));
  EXPECT_EQ(calm.describe("cell"), "the cells' median SM clocks 1965-1980 MHz; no slowdown while any of the 2 cells "
                                   "was timed");
}

// With the NVIDIA driver: samples every few ms, each a clock the device can run at. Without
// it: no samples, and the summary says the clock was not read.
TEST(ClockWatch, SamplesTheGpuWhereTheDriverIsThere) {
  ClockWatch w;
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const ClockSummary s = w.stop();
  if (!ClockWatch::available()) {
    EXPECT_FALSE(s.watched());
    EXPECT_TRUE(w.samples().empty());
    EXPECT_FALSE(test::gpu_required()) << "a GPU machine has the NVIDIA driver's NVML";
    return;
  }
  ASSERT_TRUE(s.watched());
  EXPECT_GE(s.samples, 100 / ClockWatch::kPeriodMs / 4);
  EXPECT_FALSE(s.device.empty());
  EXPECT_GT(s.sm_mhz_min, 0u);
  EXPECT_LE(s.sm_mhz_min, s.sm_mhz_median);
  EXPECT_LE(s.sm_mhz_median, s.sm_mhz_max);
  EXPECT_LE(s.sm_mhz_max, s.sm_mhz_top);
  const auto all = w.samples();
  ASSERT_EQ(int(all.size()), s.samples);
  for (std::size_t k = 1; k < all.size(); ++k) EXPECT_GE(all[k].t_ms, all[k - 1].t_ms);
  EXPECT_GE(all.back().t_ms, 90.0);
}

}  // namespace
}  // namespace deformlab::test
