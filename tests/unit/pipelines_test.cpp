// The registry's traits: every pipeline name carries the same traits and options in every
// build, whether its backend is built or stands in as unavailable; the untimed warm-up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <fstream>
#include <numeric>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/integrator.hpp"
#include "core/timed_work.hpp"
#include "experiments/pipelines.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab {
namespace {

TEST(Pipelines, TraitsAreTheSameInEveryBuild) {
  const PipelineRegistry& r = pipelines();
  for (const char* n : {"cpu", "omp", "cuda-naive", "cuda-tiled", "cuda-fused", "cuda-temporal"})
    EXPECT_EQ(r.find(n)->traits.cpu_match, CpuMatch::bitwise) << n;
  for (const char* n : {"reference", "cuda-scatter", "glsl-tf", "glsl-compute", "hybrid", "hybrid-compute"})
    EXPECT_EQ(r.find(n)->traits.cpu_match, CpuMatch::rounding) << n;
  for (const auto& e : r.all()) EXPECT_EQ(e.traits.deterministic, e.name != "cuda-scatter") << e.name;
  for (const auto& e : r.all()) EXPECT_EQ(e.traits.hands_off(), e.name.starts_with("hybrid")) << e.name;
  EXPECT_EQ(r.find("hybrid")->traits.update, Engine::gl_transform_feedback);
  EXPECT_EQ(r.find("hybrid-compute")->traits.update, Engine::gl_compute);
  EXPECT_EQ(r.find("cpu")->traits.force, Engine::cpu);
  EXPECT_EQ(r.find("cuda-tiled")->options, (std::vector<std::string>{"tile", "math"}));
  EXPECT_EQ(r.find("cuda-temporal")->options, (std::vector<std::string>{"tile", "steps_per_launch", "math"}));
  EXPECT_EQ(r.find("hybrid")->options, (std::vector<std::string>{"interop", "force", "tile", "math"}));
  EXPECT_EQ(r.find("glsl-tf")->options, (std::vector<std::string>{"link_view", "math", "memory"}));
  for (const auto& e : r.all()) EXPECT_EQ(e.traits.grids_only, e.name == "cuda-temporal") << e.name;
  // Fast math compares by rounding; exact keeps the trait.
  EXPECT_EQ(cpu_match(*r.find("cuda-fused"), {{"math", "fast"}}), CpuMatch::rounding);
  EXPECT_EQ(cpu_match(*r.find("cuda-fused"), {{"math", "exact"}}), CpuMatch::bitwise);
  EXPECT_THROW(math_option({{"math", "quick"}}), std::invalid_argument);
}

// A count in an option's value has one spelling: two option sets that read differently differ
// in value (a sweep runs each set once).
TEST(Pipelines, OptionCountsHaveOneSpelling) {
  EXPECT_EQ(option_count("8", 8), 8);
  EXPECT_EQ(option_count("1", 1), 1);
  EXPECT_EQ(option_count("9223372036854775807", INT64_MAX), INT64_MAX);
  for (const char* bad : {"", "0", "9", "08", "+8", " 8", "8 ", "-1", "8x", "0x8", "1e1", "99999999999999999999"})
    EXPECT_EQ(option_count(bad, 8), std::nullopt) << bad;
}

// `best` is the first pipeline of the list that runs here, runs the integrator and does not run
// on a software rasteriser (on a machine with llvmpipe only, a CPU pipeline).
TEST(Pipelines, BestIsTheFirstThatRunsHereOffSoftwareGl) {
  for (const auto& i : integrators()) {
    const PipelineEntry& best = best_pipeline(i.id);
    EXPECT_TRUE(best.unavailable().empty() && best.unsupported(i.id).empty()) << best.name;
    EXPECT_FALSE(on_software_gl(best)) << best.name;
    for (const auto& e : pipelines().all()) {
      if (e.name == best.name) break;
      EXPECT_TRUE(!e.unavailable().empty() || !e.unsupported(i.id).empty() || on_software_gl(e))
          << e.name << " comes before " << best.name << " and runs " << i.name << " here";
    }
  }
}

TEST(Pipelines, WarmUpEndsWithinAboutAStepOfItsTime) {
  // 4 ms steps for 140 ms: batches doubling without a bound would stop after 1 + 2 + ... + 32 = 63 steps
  // (252 ms); at the mean step the warm-up takes about 35.
  int steps = 0;
  std::vector<int> batches;  // steps between drains
  const WarmUp w = warm_up([&] { ++steps, std::this_thread::sleep_for(std::chrono::milliseconds(4)); },
                           [&] { batches.push_back(steps - std::accumulate(batches.begin(), batches.end(), 0)); }, 140);
  EXPECT_EQ(w.steps, steps);
  EXPECT_GE(w.ms, 140);
  EXPECT_LT(w.ms, 180) << "in " << w.steps << " steps";
  // The first 15 steps take 60 ms: the batches still start at one step and double.
  ASSERT_GE(batches.size(), 4u);
  EXPECT_EQ(std::vector<int>(batches.begin(), batches.begin() + 4), (std::vector<int>{1, 2, 4, 8}));
}

// The timed steps of a GPU case span about kGpuTimedMs: 0.106 ms steps 1887 of them, rounded up
// to whole launches of 8; slow steps at least the count asked for; no step time, a bounded count.
TEST(Pipelines, TimedStepsSpanTheirTime) {
  EXPECT_EQ(steps_spanning(200, 0.106, 8, 8), 1888);
  EXPECT_EQ(steps_spanning(200, 0.1, 8), 2000);
  EXPECT_EQ(steps_spanning(200, 50, 20), 20);
  EXPECT_EQ(steps_spanning(200, 50, 20, 8), 24);
  EXPECT_EQ(steps_spanning(200, 300, 0), 1);
  EXPECT_EQ(steps_spanning(200, 0, 1), 1000000);
}

// Work timed as the steps are: the warm-up's mean (4 ms a call) sets how many calls span
// kGpuTimedMs (50, rounded up to 56, a multiple of 8); `prepare` runs before each call, outside
// its timer; the clock is watched where NVML is.
TEST(Pipelines, WorkTimedBackToBackSpansItsTime) {
  // A timer that gives each call 4 ms and logs the order of events.
  struct FixedTimer final : StepTimer {
    std::string log;
    int ended = 0;
    void begin() override { log += 'b'; }
    void end() override { log += 'e', ++ended; }
    std::vector<double> take() override { return std::vector<double>(std::exchange(ended, 0), 4.0); }
    std::string clock() const override { return "fixed"; }
  } t;
  const TimedWork w = time_back_to_back(
      t, [&] { t.log += 'w'; }, 3, 5, {}, 8, [&] { t.log += 'p'; });
  EXPECT_EQ(w.ms.size(), 56u);
  EXPECT_EQ(w.median_ms(), 4.0);
  std::string expected;
  for (int c = 0; c < 3 + 56; ++c) expected += "pbwe";
  EXPECT_EQ(t.log, expected);
  EXPECT_EQ(w.clock.watched(), ClockWatch::available());
  // No warm-up: the calls asked for; slow calls: at least `min_calls`.
  EXPECT_EQ(time_back_to_back(t, [] {}, 0, 7).ms.size(), 7u);
  EXPECT_EQ(time_back_to_back(t, [] {}, 2, 70).ms.size(), 70u);
  // A first call that takes 1 s (a shader compiled) does not cut the span: 200 ms of 4 ms calls.
  struct SlowFirstTimer final : StepTimer {
    int calls = 0, ended = 0;
    void begin() override {}
    void end() override { ++ended; }
    std::vector<double> take() override {
      std::vector<double> ms;
      for (; ended > 0; --ended) ms.push_back(calls++ == 0 ? 1000.0 : 4.0);
      return ms;
    }
    std::string clock() const override { return "fixed"; }
  } slow;
  EXPECT_EQ(time_back_to_back(slow, [] {}, 3, 5).ms.size(), 50u);
  slow.calls = 0;
  EXPECT_EQ(time_back_to_back(slow, [] {}, 2, 5).ms.size(), 50u) << "two warm-up calls";
}

// The clock is watched on the GPU that runs a pipeline: none for the CPU pipelines; where NVML
// sees a GPU, the one running each GPU pipeline available here, by its PCI bus id.
TEST(Pipelines, ClockWatchedOnTheGpuThatRunsThem) {
  EXPECT_EQ(gpu_bus_id(*pipelines().find("cpu")), "");
  EXPECT_EQ(gpu_bus_id(*pipelines().find("omp")), "");
  if (!ClockWatch::available()) DEFORMLAB_SKIP_IF_UNAVAILABLE("no NVIDIA driver's NVML here");
  for (const char* name : {"cuda-fused", "glsl-compute", "glsl-tf", "hybrid"}) {
    const PipelineEntry& e = *pipelines().find(name);
    if (!e.unavailable().empty()) continue;
    const std::string bus = gpu_bus_id(e);
    EXPECT_FALSE(bus.empty()) << name;
    ClockWatch w(bus);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const ClockSummary c = w.stop();
    EXPECT_TRUE(c.watched()) << name << " on " << bus;
    EXPECT_NE(c.device.find(bus), std::string::npos) << c.device;
  }
}

// Option names and values are read before anything runs: a name the pipeline does not read,
// and every value a backend built here cannot read, are refused with the pipeline's name.
TEST(Pipelines, OptionsAreReadBeforeAnythingRuns) {
  const PipelineRegistry& r = pipelines();
  const auto refusal = [&](const char* pipeline, const PipelineOptions& o) {
    try {
      check_options(*r.find(pipeline), o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(refusal("cpu", {{"tile", "8x8"}}), "option 'tile' is not an option of cpu (it has none)");
  EXPECT_EQ(refusal("glsl-tf", {{"window", "64"}}), "option 'window' is not an option of glsl-tf");
  // Backends this build lacks stand in without reading values (their names are still checked).
  int read = 0;
  for (const auto& e : r.all()) {
    if (!e.read_options) continue;
    ++read;
    EXPECT_EQ(refusal(e.name.c_str(), {{"math", "fast"}}), "") << e.name;
    EXPECT_EQ(refusal(e.name.c_str(), {{"math", "rough"}}), e.name + ": option math 'rough' is not exact or fast");
  }
  if (read == 0) GTEST_SKIP() << "this build has no GPU backend, whose options have values to read";
  const std::vector<std::pair<const char*, PipelineOptions>> bad = {
      {"cuda-fused", {{"tile", "0x8"}}},           {"cuda-naive", {{"tile", "65536x65536"}}},  // 2^32 threads, not 0
      {"cuda-temporal", {{"steps_per_launch", "9"}}},
      {"cuda-temporal", {{"tile", "40x"}}},        {"glsl-compute", {{"window", "0"}}},
      {"glsl-tf", {{"link_view", "many"}}},        {"hybrid", {{"interop", "telepathy"}}},
      {"hybrid-compute", {{"force", "fused"}}},    {"glsl-compute", {{"memory", "host"}}},
      {"glsl-compute", {{"window", "064"}}},       {"cuda-fused", {{"tile", "32x08"}}}};
  for (const auto& [name, o] : bad) {
    if (r.find(name)->read_options) {
      EXPECT_TRUE(refusal(name, o).starts_with(std::string(name) + ": ")) << name;
    }
  }
  // A count with a leading zero is told so (it is refused to keep one spelling of each value).
  for (const auto& [name, o] : std::vector<std::pair<const char*, PipelineOptions>>{
           {"glsl-compute", {{"window", "064"}}}, {"cuda-fused", {{"tile", "32x08"}}},
           {"cuda-temporal", {{"steps_per_launch", "02"}}}, {"cuda-temporal", {{"tile", "040x40"}}}}) {
    if (r.find(name)->read_options) {
      EXPECT_NE(refusal(name, o).find("no leading zero"), std::string::npos) << refusal(name, o);
    }
  }
  for (const char* name : {"cuda-temporal", "glsl-compute"}) {
    if (r.find(name)->read_options) {
      EXPECT_EQ(refusal(name, {{"math", "exact"}}), "") << name;
    }
  }
  // Every value of a choice that `deformlab list` shows, and an instance of every form it shows
  // ("WxH or WxHxD", "N", "1-8": each letter a 4, a range's ends), is one its pipelines read.
  for (const auto& e : r.all()) {
    if (!e.read_options) continue;
    for (const auto& name : e.options) {
      const std::string values = option_values(e, name) + "|";
      const bool range = std::isdigit(static_cast<unsigned char>(values[0]));
      std::string v;
      for (std::size_t at = 0; at < values.size(); ++at) {
        const bool or_word = values.compare(at, 4, " or ") == 0;
        if (values[at] == '|' || or_word || (range && values[at] == '-')) {
          EXPECT_EQ(refusal(e.name.c_str(), {{name, v}}), "") << e.name << " " << name << "=" << v;
          v.clear();
          at += or_word ? 3 : 0;
        } else {
          v += std::string("WHDN").find(values[at]) != std::string::npos ? '4' : values[at];
        }
      }
    }
  }
}

// An option that would do nothing on the run's model is refused with the pipeline's name: a
// mesh's option on a grid, a thread block where the kernels take none, a tile's depth on a cloth.
TEST(Pipelines, OptionsThatWouldDoNothingOnTheModelAreRefused) {
  const PipelineRegistry& r = pipelines();
  const auto refusal = [&](const char* pipeline, const PipelineOptions& o, Topology t) {
    try {
      check_options(*r.find(pipeline), o, t);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const Topology cloth = Topology::cloth_grid, lattice = Topology::lattice, mesh = Topology::general;
  int checked = 0;
  const auto idle = [&](const char* pipeline, const PipelineOptions& o, Topology t, const std::string& why) {
    if (!r.find(pipeline)->idle_option) return;
    ++checked;
    EXPECT_EQ(refusal(pipeline, o, t), why.empty() ? "" : std::string(pipeline) + ": option " + why) << pipeline;
  };
  for (const char* gl : {"glsl-tf", "glsl-compute"}) {
    idle(gl, {{"link_view", "64"}}, cloth, "link_view: a mesh's option (links per texture-buffer view of its "
                                           "adjacency), and this model is a grid");
    idle(gl, {{"link_view", "64"}}, mesh, "");
  }
  const std::string block = "tile: on a mesh this pipeline runs one thread per node in blocks of its own (of the "
                            "CUDA pipelines only cuda-tiled takes a tile there: its nodes per tile)";
  for (const char* cuda : {"cuda-naive", "cuda-fused"}) {
    idle(cuda, {{"tile", "16x8"}}, mesh, block);
    idle(cuda, {{"tile", "16x8"}}, lattice, "");
  }
  idle("cuda-tiled", {{"tile", "16x8"}}, mesh, "");
  idle("cuda-fused", {{"tma", "off"}}, lattice, "tma: the tensor memory accelerator's kernel is a cloth's");
  idle("cuda-fused", {{"tma", "off"}}, cloth, "");
  idle("cuda-temporal", {{"tile", "8x8x4"}}, cloth, "tile '8x8x4': a cloth's tile is WxH nodes (WxHxD is a lattice's)");
  idle("cuda-temporal", {{"tile", "8x8x4"}}, lattice, "");
  idle("cuda-temporal", {{"tile", "8x8"}}, cloth, "");
  for (const char* hybrid : {"hybrid", "hybrid-compute"}) {
    idle(hybrid, {{"tile", "16x8"}, {"force", "scatter"}}, cloth,
         "tile: the scatter force pass (force=scatter) runs one thread per spring in blocks of its own");
    idle(hybrid, {{"tile", "16x8"}}, mesh, "tile: on a mesh only the tiled force pass (force=tiled) takes a tile, its "
                                           "nodes per tile");
    idle(hybrid, {{"tile", "16x8"}, {"force", "tiled"}}, mesh, "");
    idle(hybrid, {{"tile", "16x8"}}, cloth, "");
  }
  if (checked == 0) GTEST_SKIP() << "this build has no GPU backend, whose options depend on the model";
}

// The check before a run adds the model, the pipeline's own host bytes and a state, and names
// the limit that refuses it; grids cost the same whatever their spring count.
TEST(Pipelines, HostMemoryCheckNamesTheNeedAndTheLimit) {
  const PipelineRegistry& r = pipelines();
  const PipelineEntry& cpu = *r.find("cpu");
  const ModelSize small{128 * 128, 6 * 128 * 128, true};
  EXPECT_EQ(host_memory_shortfall(small, cpu, Integrator::semi_implicit_euler, {}), "");
  // The tightest limit: /proc/meminfo's MemAvailable (read here before and after, other
  // processes taking and giving back memory in between) or, where tighter, a cgroup's.
  auto available = [] {
    std::ifstream meminfo("/proc/meminfo");
    std::string key, unit;
    for (std::int64_t kb; meminfo >> key >> kb >> unit;)
      if (key == "MemAvailable:") return double(kb) * 1024;
    return 0.0;
  };
  const double before = available();
  const auto limit = host_memory_limit();
  const double after = available();
  ASSERT_TRUE(limit.has_value());
  ASSERT_GT(before, 0);
  EXPECT_GT(limit->bytes, 0);
  EXPECT_LE(double(limit->bytes), 1.1 * std::max(before, after));
  if (limit->name == "MemAvailable (/proc/meminfo)") EXPECT_GE(double(limit->bytes), 0.9 * std::min(before, after));
  else EXPECT_EQ(limit->name.rfind("the cgroup's memory limit (", 0), 0u) << limit->name;
  // Semi-implicit Euler on cpu: slots (x, v), one acceleration, next (x, v): 5 vec3 of floats.
  EXPECT_EQ(cpu.footprint(small, Integrator::semi_implicit_euler, {}).host, small.nodes * 5 * 12);
  // 2^30 nodes by backward Euler in doubles: terabytes, more than any machine here has.
  const ModelSize big{std::int64_t(1) << 30, 6 * (std::int64_t(1) << 30), true};
  const PipelineEntry& ref = *r.find("reference");
  const std::int64_t need = model_host_bytes(big) + ref.footprint(big, Integrator::backward_euler, {}).host +
                            state_host_bytes(big.nodes);
  ASSERT_GT(need, limit->bytes);
  const std::string why = host_memory_shortfall(big, ref, Integrator::backward_euler, {});
  EXPECT_NE(why.find("on reference needs " + gib(need) + " of host memory (model 16 GiB, pipeline "), std::string::npos)
      << why;
  EXPECT_NE(why.find(", state 24 GiB); " + limit->name + " leaves " + gib(limit->bytes)), std::string::npos) << why;
  EXPECT_NE(host_memory_shortfall({(std::int64_t(1) << 30) + 1, 0, true}, cpu, Integrator::verlet, {})
                .find("exceeds the limit of 2^30 nodes"),
            std::string::npos);
  // With --compare, the reference pipeline (doubles) and its state are counted too:
  // 5 vec3 of doubles and a state, 144 GiB at 2^30 nodes.
  const std::string both = host_memory_shortfall(big, cpu, Integrator::semi_implicit_euler, {}, &ref);
  EXPECT_NE(both.find("reference pipeline and state 144 GiB"), std::string::npos) << both;
  // Before a pipeline is chosen (`view`'s best): the model and its state alone, 40 GiB.
  const std::string model = model_memory_shortfall(big, Integrator::semi_implicit_euler);
  if (model_host_bytes(big) + state_host_bytes(big.nodes) > limit->bytes)
    EXPECT_EQ(model, "a model of 1073741824 nodes needs at least 40 GiB of host memory (model 16 GiB, state 24 GiB); " +
                         limit->name + " leaves " + gib(limit->bytes));
  else
    EXPECT_EQ(model, "");
}

}  // namespace
}  // namespace deformlab
