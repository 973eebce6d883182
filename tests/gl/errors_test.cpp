// Failures are reported where they happen: a broken shader with its name and the driver's
// log (and a non-zero exit of the command), no EGL display or a bad option value with one clear
// error (exit 2).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sys/wait.h>
#include <utility>
#include <vector>

#include "core/memory.hpp"
#include "gl_test_support.hpp"
#include "gl/objects.hpp"

namespace deformlab::test {
namespace {

struct Command {
  int exit_code;
  std::string output;  // stdout and stderr
};

Command run_deformlab(const std::string& env, const std::string& args) {
  const std::string cmd = env + " '" DEFORMLAB_EXE "' " + args + " 2>&1";
  FILE* f = ::popen(cmd.c_str(), "r");
  if (!f) return {-1, "popen failed"};
  std::string out;
  std::array<char, 4096> buf;
  for (std::size_t n; (n = std::fread(buf.data(), 1, buf.size(), f)) > 0;) out.append(buf.data(), n);
  const int status = ::pclose(f);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

std::filesystem::path temp_dir(const std::string& tag) {
  auto d = std::filesystem::temp_directory_path() / ("deformlab-" + tag + "-" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d;
}

TEST(GlErrors, BrokenShaderGivesItsNameAndLog) {
  DEFORMLAB_REQUIRE_GL();
  try {
    gl::make_program_from_source(GL_VERTEX_SHADER, "broken.vert",
                                 "#version 430 core\nvoid main() { gl_Position = vec4(undefined_thing); }\n");
    FAIL() << "a broken shader compiled";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("broken.vert"), std::string::npos) << msg;
    EXPECT_NE(msg.find("undefined_thing"), std::string::npos) << "no driver log in: " << msg;
  }
}

TEST(GlErrors, BrokenShaderFileFailsTheRun) {
  DEFORMLAB_REQUIRE_GL();
  const auto dir = temp_dir("shaders");
  std::ofstream(dir / "step.vert") << "#version 430 core\nvoid main() { this is not glsl; }\n";
  const Command c = run_deformlab("DEFORMLAB_SHADER_DIR='" + dir.string() + "'",
                                  "run -p glsl-tf --grid 8x8 --steps 2 -o '" + (dir / "out").string() + "'");
  std::filesystem::remove_all(dir);
  EXPECT_NE(c.exit_code, 0) << c.output;
  EXPECT_NE(c.output.find("step.vert"), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("failed to compile"), std::string::npos) << c.output;
}

// No EGL vendor library at all: what a machine without a GL driver looks like.
TEST(GlErrors, MissingEglDisplayIsOneClearError) {
  const std::string env = "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent/egl_vendor.json";
  const auto dir = temp_dir("nodisplay");
  const Command run = run_deformlab(env, "run -p glsl-compute --grid 8x8 --steps 1 -o '" + (dir / "out").string() + "'");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("OpenGL unavailable: no EGL display"), std::string::npos) << run.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "nothing is written";
  std::filesystem::remove_all(dir);
  const Command list = run_deformlab(env, "list");
  EXPECT_EQ(list.exit_code, 0) << list.output;
  EXPECT_NE(list.output.find("glsl-tf        unavailable"), std::string::npos) << list.output;
  EXPECT_NE(list.output.find("why: OpenGL unavailable"), std::string::npos) << list.output;
}

TEST(GlErrors, UnknownGlDeviceIsBadInput) {
  DEFORMLAB_REQUIRE_GL();
  const auto dir = temp_dir("device");
  const Command c = run_deformlab("", "run -p glsl-tf --grid 8x8 --steps 1 --gl-device 99 -o '" + (dir / "out").string() + "'");
  std::filesystem::remove_all(dir);
  EXPECT_EQ(c.exit_code, 2) << c.output;
  EXPECT_NE(c.output.find("--gl-device 99 does not exist"), std::string::npos) << c.output;
}

// A pipeline option's bad value is bad input like the flags' (tests/unit/bad_input_test.cpp,
// which runs without GL): one line, exit 2, nothing written. So are a mesh's option on a grid
// and memory=cuda on a software renderer, which has no CUDA device behind it.
TEST(GlErrors, BadOptionValuesAreBadInput) {
  DEFORMLAB_REQUIRE_GL();
  for (const char* name : {"glsl-tf", "glsl-compute"}) {
    std::vector<std::pair<std::string, std::string>> cases = {
        {"math=foo", std::string(name) + ": option math 'foo' is not exact or fast\n"},
        {"memory=host", std::string(name) + ": option memory 'host' is not one of gl, cuda\n"},
        {"link_view=4", std::string(name) + ": option link_view: a mesh's option (links per texture-buffer view of "
                        "its adjacency), and this model is a grid\n"}};
    if (gl::context().software) cases.push_back({"memory=cuda", std::string(name) + ": memory cuda is not available: "});
    for (const auto& [option, error] : cases) {
      const auto dir = temp_dir("option");
      const Command c = run_deformlab("", std::string("run -p ") + name + " --grid 8x8 --steps 1 --option " + option +
                                              " -o '" + (dir / "out").string() + "'");
      EXPECT_EQ(c.exit_code, 2) << c.output;
      EXPECT_TRUE(c.output.starts_with("deformlab: error: " + error)) << c.output;
      EXPECT_EQ(std::count(c.output.begin(), c.output.end(), '\n'), 1) << c.output;
      EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "nothing is written";
      std::filesystem::remove_all(dir);
    }
  }
}

// On a software renderer the GL buffers are host memory: a grid whose model and state fit but
// whose buffers would not is refused with the host-memory check, before the model is built.
TEST(GlErrors, ASoftwareRenderersBuffersAreCountedBeforeTheModelIsBuilt) {
  DEFORMLAB_REQUIRE_GL();
  if (!gl::context().software) GTEST_SKIP() << "a GPU's GL buffers are checked against its own memory";
  const auto limit = host_memory_limit();
  ASSERT_TRUE(limit.has_value());
  // A node takes 52 bytes of host memory without the buffers and 116 with them (semi-implicit
  // Euler's four node buffers): at limit / 80 nodes, 0.65 and 1.45 of the limit.
  if (limit->bytes / 80 > (std::int64_t(1) << 30)) GTEST_SKIP() << "such a grid passes the limit of 2^30 nodes";
  const int side = int(std::sqrt(double(limit->bytes) / 80));
  const std::string grid = std::to_string(side) + "x" + std::to_string(side);
  const auto dir = temp_dir("gl-memory");
  const Command c = run_deformlab("", "run -p glsl-tf --integrator semi-implicit-euler --grid " + grid +
                                          " --steps 1 --no-state -o '" + (dir / "out").string() + "'");
  EXPECT_EQ(c.exit_code, 2) << c.output;
  EXPECT_TRUE(c.output.starts_with("deformlab: error: --grid (cloth " + grid + "): a model of " +
                                   std::to_string(std::int64_t(side) * side) + " nodes on glsl-tf needs "))
      << c.output;
  EXPECT_NE(c.output.find(" of host memory (model "), std::string::npos) << c.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "nothing is written";
  std::filesystem::remove_all(dir);
}

// The command end to end: frames every N steps and the final one, each a span, committed with
// the run;
// the pass's spans in the sampled steps 1-8 of the 12 (every step with --trace).
TEST(GlCommand, RunWritesFramesAndGlFacts) {
  DEFORMLAB_REQUIRE_GL();
  const auto dir = temp_dir("run");
  auto pass_spans = [&] {
    std::ifstream csv(dir / "out" / "spans.csv");
    int n = 0;
    for (std::string line; std::getline(csv, line);) n += line.rfind("force+update,", 0) == 0;
    return n;
  };
  const Command traced = run_deformlab("", "run -p glsl-compute --grid 16x16 --steps 12 --trace -o '" + (dir / "out").string() + "'");
  EXPECT_EQ(traced.exit_code, 0) << traced.output;
  EXPECT_EQ(pass_spans(), 12);
  std::filesystem::remove_all(dir / "out");
  const Command c = run_deformlab("", "run -p glsl-compute --grid 16x16 --steps 12 --frames 5 -o '" + (dir / "out").string() + "'");
  EXPECT_EQ(c.exit_code, 0) << c.output;
  EXPECT_EQ(pass_spans(), 8);
  std::ifstream spans(dir / "out" / "spans.csv");
  int frame_spans = 0;
  for (std::string line; std::getline(spans, line);) frame_spans += line.rfind("frame,", 0) == 0;
  EXPECT_EQ(frame_spans, 3) << "one span a frame drawn and written (5, 10 and the last, 12), none for the steps "
                               "between";
  for (const char* f : {"frame_000005.png", "frame_000010.png", "frame_000012.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / "frames" / f)) << f;
  std::ifstream manifest(dir / "out" / "manifest.json");
  const std::string text((std::istreambuf_iterator<char>(manifest)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"renderer\""), std::string::npos) << "GL facts in the manifest";
  EXPECT_NE(text.find("\"render_ms_median\""), std::string::npos);
  std::filesystem::remove_all(dir);
}

// A GPU pipeline's run warms up (untimed steps from rest for 1000 ms by default) and then
// starts again from rest: the final state is the one a run without the warm-up reaches.
TEST(GlCommand, WarmsUpThenRunsFromRest) {
  DEFORMLAB_REQUIRE_GL();
  const auto dir = temp_dir("warm");
  auto slurp = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string args = "run -p glsl-compute --integrator verlet --grid 16x16 --steps 20 -o '";
  const Command warm = run_deformlab("", args + (dir / "warm").string() + "'");
  ASSERT_EQ(warm.exit_code, 0) << warm.output;
  const Command cold = run_deformlab("", args + (dir / "cold").string() + "' --warmup-ms 0");
  ASSERT_EQ(cold.exit_code, 0) << cold.output;
  const std::string manifest = slurp(dir / "warm" / "manifest.json");
  const auto at = manifest.find("\"warm_up\"");
  ASSERT_NE(at, std::string::npos);
  const auto ms = manifest.find("\"ms\":", at), steps = manifest.find("\"steps\":", at);
  EXPECT_GE(std::stod(manifest.substr(ms + 5)), 1000.0) << manifest.substr(at, 200);
  EXPECT_GT(std::stoi(manifest.substr(steps + 8)), 0) << manifest.substr(at, 200);
  EXPECT_NE(warm.output.find("untimed steps from rest in"), std::string::npos) << warm.output;
  EXPECT_EQ(cold.output.find("untimed steps"), std::string::npos) << cold.output;
  const std::string warm_state = slurp(dir / "warm" / "state.ply");
  EXPECT_GT(warm_state.size(), 100u) << "a state was written";
  EXPECT_EQ(warm_state, slurp(dir / "cold" / "state.ply")) << "the run starts from rest";
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace deformlab::test
