// The profiler's span model, summary and writers; and the run loop's spans.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unistd.h>

#include "core/cpu_backend.hpp"
#include "core/profiler.hpp"
#include "core/run.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

TEST(Profiler, SummarySumsSpansPerStepThenTakesTheMedian) {
  Profiler p;
  // Two force passes per step (as midpoint): 1 + 2, 5 + 6, 9 + 10 ms -> per step 3, 11, 19.
  for (int step = 1; step <= 3; ++step) {
    p.add({span::force, step, 0.0, 4.0 * step - 3.0, "CUDA events"});
    p.add({span::force, step, 0.0, 4.0 * step - 2.0, "CUDA events"});
    p.add({span::update, step, 0.0, 0.5, "GL timer queries"});
  }
  const auto s = p.summary();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].name, "force");
  EXPECT_EQ(s[0].steps, 3);
  EXPECT_EQ(s[0].spans, 6);
  EXPECT_DOUBLE_EQ(s[0].median_ms, 11.0);
  EXPECT_DOUBLE_EQ(s[0].total_ms, 33.0);
  EXPECT_EQ(s[0].clock, "CUDA events");
  EXPECT_EQ(s[1].name, "update");
  EXPECT_DOUBLE_EQ(s[1].median_ms, 0.5);
}

// Sampling: every step by default; else windows of 8 steps from step 1, one in `every`.
TEST(Profiler, SamplesWindowsOfStepsFromTheFirst) {
  Profiler p;
  EXPECT_EQ(p.sampled_steps(), "every step");
  p.sample_every(3);
  EXPECT_EQ(p.sampled_steps(), "steps 1-8 of every 24");
  std::vector<int> sampled;
  for (int step = 0; step <= 60; ++step) {
    p.set_step(step);
    if (p.sampled()) sampled.push_back(step);
    EXPECT_EQ(sampling(&p), p.sampled() ? &p : nullptr);
  }
  EXPECT_EQ(sampled, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 25, 26, 27, 28, 29, 30, 31, 32, 49, 50, 51, 52,
                                       53, 54, 55, 56}));
  for (int n = 0; n <= 60; ++n)  // steps 1..n among those sampled
    EXPECT_EQ(p.sampled_count(n), std::count_if(sampled.begin(), sampled.end(), [n](int s) { return s >= 1 && s <= n; }))
        << n;
  EXPECT_EQ(sampling(nullptr), nullptr);
  p.sample_every(1);
  p.set_step(13);
  EXPECT_TRUE(p.sampled());
  EXPECT_EQ(p.sampled_count(13), 13);
}

// Streamed spans: the file is the same whether the spans are kept or not, the summary is the
// same, and without keeping them the profiler holds no spans (a long run's memory stays flat).
TEST(Profiler, StreamsSpansWithTheSameSummary) {
  const auto dir = std::filesystem::temp_directory_path() / ("deformlab_stream_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  Profiler kept, streamed;
  kept.stream_csv((dir / "kept.csv").string(), true);
  streamed.stream_csv((dir / "streamed.csv").string(), false);
  for (Profiler* p : {&kept, &streamed})
    for (int step = 1; step <= 50; ++step) {
      p->add({span::force, step, 0.0, 0.01 * step, "CUDA events"});
      p->add({span::force, step, 0.0, 0.02, "CUDA events"});
      p->add({span::reductions, step, 0.0, 1.0 / step, "host clock"});
    }
  streamed.end_stream();
  kept.end_stream();
  auto slurp = [](const std::filesystem::path& f) {
    std::ifstream in(f);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  EXPECT_EQ(slurp(dir / "streamed.csv"), slurp(dir / "kept.csv"));
  EXPECT_TRUE(streamed.spans().empty());
  EXPECT_EQ(kept.spans().size(), 150u);
  const auto a = kept.summary(), b = streamed.summary();
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(b.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(a[k].name, b[k].name);
    EXPECT_EQ(a[k].steps, 50);
    EXPECT_EQ(a[k].spans, b[k].spans);
    EXPECT_DOUBLE_EQ(a[k].median_ms, b[k].median_ms);
  }
  EXPECT_DOUBLE_EQ(a[0].median_ms, 0.01 * 26 + 0.02);  // the upper median of 50 step sums
  std::filesystem::remove_all(dir);
}

TEST(Profiler, WritesCsvAndAChromeTrace) {
  const auto dir = std::filesystem::temp_directory_path() / ("deformlab_profiler_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  Profiler p;
  p.stream_csv((dir / "spans.csv").string(), true);
  p.set_step(1);
  { HostSpan h(&p, span::step); }
  p.add({span::force, 1, 0.25, 0.125, "CUDA events"});
  p.end_stream();
  p.write_trace((dir / "trace.json").string());
  std::ifstream csv(dir / "spans.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header, "name,step,start_ms,ms,clock");
  int lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 2);
  std::ifstream tf(dir / "trace.json");
  const auto j = nlohmann::json::parse(tf);
  int complete = 0;
  for (const auto& e : j["traceEvents"]) {
    if (e["ph"] != "X") continue;
    ++complete;
    if (e["name"] == "force") {
      EXPECT_DOUBLE_EQ(e["ts"].get<double>(), 250.0);  // microseconds
      EXPECT_DOUBLE_EQ(e["dur"].get<double>(), 125.0);
    }
  }
  EXPECT_EQ(complete, 2);
  std::filesystem::remove_all(dir);
}

TEST(Profiler, RunRecordsStepAndReductionSpans) {
  const Model m = small_cloth(6, 6);
  Params p = small_params();
  p.max_steps = 5;
  p.check_every = 1;
  auto pipe = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, false);
  Profiler prof;
  RunOptions opt;
  opt.profiler = &prof;
  run(*pipe, m, p, opt);
  int steps = 0, reductions = 0;
  for (const Span& s : prof.spans()) {
    steps += s.name == span::step;
    reductions += s.name == span::reductions;
    EXPECT_EQ(s.clock, "host clock");
    EXPECT_GE(s.step, 1);
  }
  EXPECT_EQ(steps, 5);
  EXPECT_EQ(reductions, 5);
}

}  // namespace
}  // namespace deformlab::test
