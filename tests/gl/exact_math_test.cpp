// The GL pipelines' option math: exact (the default) runs shaders/exact_math.glsl.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "gl/objects.hpp"
#include "gl_test_support.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

// A compute shader over exact_math.glsl (after `defines`) that writes out_[i] = `expr` of
// a = in_[i] for i < u_n.
std::string map_shader(const std::string& defines, const std::string& in_type, const std::string& out_type,
                       const std::string& expr) {
  return "#version 430 core\n" + defines + gl::shader_file("exact_math.glsl") +
         "layout(local_size_x = 256) in;\n"
         "layout(std430, binding = 0) readonly buffer In { " + in_type + " in_[]; };\n"
         "layout(std430, binding = 1) writeonly buffer Out { " + out_type + " out_[]; };\n"
         "layout(location = 0) uniform uint u_n;\n"
         "void main() {\n"
         "  uint i = gl_GlobalInvocationID.x;\n"
         "  if (i < u_n) {\n"
         "    " + in_type + " a = in_[i];\n"
         "    out_[i] = " + expr + ";\n"
         "  }\n"
         "}\n";
}

// Runs a map_shader program over n inputs of in_size bytes into n outputs of out_size bytes.
void run_map(const gl::Program& prog, const void* in, std::size_t in_size, void* out, std::size_t out_size,
             std::size_t n) {
  const gl::Buffer ib = gl::make_buffer(n * in_size, in), ob = gl::make_buffer(n * out_size);
  glUseProgram(prog.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ib.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, ob.id());
  glUniform1ui(0, GLuint(n));
  glDispatchCompute(GLuint((n + 255) / 256), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  gl::read_buffer(ob.id(), 0, n * out_size, out);
  glUseProgram(0);
}

// dl_recip and dl_sqrt of floats given by their bits, run in a compute shader whose driver
// starting values are moved by `guess_ulps` (DL_GUESS_ULPS).
class ExactMath {
 public:
  explicit ExactMath(int guess_ulps)
      : prog_(gl::make_program_from_source(GL_COMPUTE_SHADER, "exact_math_test.comp", source(guess_ulps))) {}

  // The results' bits, (1/x, sqrt(x)) for each x.
  std::vector<std::uint32_t> run(const std::vector<std::uint32_t>& x) const {
    constexpr std::size_t kChunk = std::size_t(1) << 20;
    std::vector<std::uint32_t> out(2 * x.size());
    for (std::size_t first = 0; first < x.size(); first += kChunk)
      run_map(prog_, x.data() + first, 4, out.data() + 2 * first, 8, std::min(kChunk, x.size() - first));
    return out;
  }

 private:
  static std::string source(int guess_ulps) {
    return map_shader("#define DL_GUESS_ULPS " + std::to_string(guess_ulps) + "\n", "uint", "uvec2",
                      "uvec2(floatBitsToUint(dl_recip(uintBitsToFloat(a))), "
                      "floatBitsToUint(dl_sqrt(uintBitsToFloat(a))))");
  }
  gl::Program prog_;
};

std::string hex(float f) {
  char s[48];
  std::snprintf(s, sizeof s, "%a (0x%08x)", double(f), std::bit_cast<std::uint32_t>(f));
  return s;
}

// Every float's result equal to the CPU's correctly rounded 1.0f / x and std::sqrt(x) bit for
// bit (a NaN to any NaN); the first few differences are named.
void expect_correctly_rounded(const ExactMath& em, const std::vector<std::uint32_t>& xs, const std::string& what) {
  const std::vector<std::uint32_t> r = em.run(xs);
  std::size_t wrong = 0;
  auto check = [&](const char* op, float x, std::uint32_t got, float want) {
    if (std::isnan(want) ? std::isnan(std::bit_cast<float>(got)) : got == std::bit_cast<std::uint32_t>(want)) return;
    if (wrong++ < 5) ADD_FAILURE() << what << ": " << op << "(" << hex(x) << ") = " << hex(std::bit_cast<float>(got))
                                   << ", correctly rounded " << hex(want);
  };
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const float x = std::bit_cast<float>(xs[k]);
    check("recip", x, r[2 * k], 1.0f / x);
    check("sqrt", x, r[2 * k + 1], std::sqrt(x));
  }
  EXPECT_EQ(wrong, 0u) << what << ": results not correctly rounded, of " << xs.size() << " floats";
}

// Both signs of: zeros, infinities, NaNs, subnormals, every power of two and its neighbours,
// floats near 1, 2 and 4, the smallest and largest normals, and those whose 1/x is subnormal.
std::vector<std::uint32_t> edge_cases() {
  std::vector<std::uint32_t> v = {0x00000000, 0x7f800000, 0x7fc00000, 0x7f800001, 0x00000001, 0x00000002,
                                  0x00000003, 0x000003ff, 0x00400000, 0x00400001, 0x007fffff, 0x00800000,
                                  0x00800001, 0x00ffffff, 0x7f7fffff, 0x7f7ffffe, 0x7e800001, 0x7effffff};
  for (std::uint32_t e = 1; e < 255; ++e)
    for (std::uint32_t d : {0u, 1u, 2u, 0x7fffffu, 0x7ffffeu}) v.push_back((e << 23) + d);
  for (std::uint32_t base : {0x3f800000u, 0x40000000u, 0x40800000u})
    for (std::uint32_t d = 0; d < 64; ++d) v.insert(v.end(), {base + d, base - 1 - d});
  for (std::uint32_t d = 0; d < 4096; ++d) v.push_back(0x7e800000u + d * 0x1fffu);  // [2^126, 2^128)
  for (std::size_t k = 0, n = v.size(); k < n; ++k) v.push_back(v[k] | 0x80000000u);
  return v;
}

std::vector<std::uint32_t> random_bits(std::size_t n, std::uint32_t lo, std::uint32_t hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint32_t> d(lo, hi);
  std::vector<std::uint32_t> v(n);
  for (auto& b : v) b = d(rng);
  return v;
}

// dl_recip and dl_sqrt are correctly rounded: bit for bit the CPU's 1.0f / x and std::sqrt(x)
// on every float in [1, 4) (every significand with both exponent parities: the functions reduce
// their argument to there by its bits), on the edge cases, and on random bit patterns (every
// exponent and sign, subnormals and NaNs). Again on the edge cases and samples with the
// driver's starting values moved by 3 ulp (past GLSL's 2.5 for 1/x), 24 and 30 ulp (the method
// takes them within 30), which must not change a bit: llvmpipe's 1/x and sqrt are correctly
// rounded already, a GPU's are not.
TEST(ExactMath, ReciprocalAndSquareRootAreCorrectlyRounded) {
  DEFORMLAB_REQUIRE_GL();
  gl::context();
  const ExactMath driver(0);
  std::vector<std::uint32_t> one_to_four(0x40800000u - 0x3f800000u);
  for (std::uint32_t k = 0; k < one_to_four.size(); ++k) one_to_four[k] = 0x3f800000u + k;
  expect_correctly_rounded(driver, one_to_four, "[1, 4)");
  expect_correctly_rounded(driver, edge_cases(), "edge cases");
  expect_correctly_rounded(driver, random_bits(std::size_t(1) << 20, 0u, 0xffffffffu, 1), "random bits");
  for (int ulps : {-30, -24, -3, 3, 24, 30}) {
    const ExactMath moved(ulps);
    const std::string what = "starting values moved by " + std::to_string(ulps) + " ulp, ";
    expect_correctly_rounded(moved, edge_cases(), what + "edge cases");
    expect_correctly_rounded(moved, random_bits(std::size_t(1) << 18, 0x3f800000u, 0x407fffffu, 2), what + "[1, 4)");
    expect_correctly_rounded(moved, random_bits(std::size_t(1) << 18, 0u, 0xffffffffu, 3), what + "random bits");
  }
  gl::check("exact math test");
}

// dl_floor_div(a, b) and the floor of the float quotient it starts from, run on the GPU for
// each pair.
std::vector<std::int32_t> floor_div_on_gl(const std::vector<std::int32_t>& ab) {
  const gl::Program prog = gl::make_program_from_source(
      GL_COMPUTE_SHADER, "floor_div_test.comp",
      map_shader("", "ivec2", "ivec2", "ivec2(dl_floor_div(a.x, a.y), int(floor(float(a.x) / float(a.y))))"));
  std::vector<std::int32_t> q(ab.size());
  run_map(prog, ab.data(), 8, q.data(), 8, ab.size() / 2);
  return q;
}

// dl_floor_div, which the two functions' integer steps use, is floor(a / b) over its domain
// (every int a, 2^23 <= b < 2^26): quotients near every integer an int allows (a = k b - 1, k b,
// k b + 1, k b + b - 1, up to |k| = 256) for divisors at the domain's ends and between, and
// random pairs. Some inputs need each of its two corrections on the device under test: the floor
// of its float quotient is one too high for some and one too low for others.
TEST(ExactMath, FloorDivisionIsExactOverItsDomain) {
  DEFORMLAB_REQUIRE_GL();
  gl::context();
  constexpr std::int64_t kMin = INT32_MIN, kMax = INT32_MAX;
  std::vector<std::int64_t> bs = {1 << 23, (1 << 23) + 1, (3 << 22) + 7, (1 << 24) - 1, 1 << 24, (1 << 25) + 3,
                                  (1 << 26) - 1};
  std::mt19937 rng(4);
  for (int k = 0; k < 64; ++k) bs.push_back(std::uniform_int_distribution<std::int64_t>(1 << 23, (1 << 26) - 1)(rng));
  std::vector<std::int32_t> ab;
  auto add = [&](std::int64_t a, std::int64_t b) {
    if (a >= kMin && a <= kMax) ab.insert(ab.end(), {std::int32_t(a), std::int32_t(b)});
  };
  for (std::int64_t b : bs) {
    for (std::int64_t k = -256; k <= 256; ++k)
      for (std::int64_t a : {k * b - 1, k * b, k * b + 1, k * b + b - 1}) add(a, b);
    add(kMin, b);
    add(kMax, b);
  }
  for (int k = 0; k < (1 << 16); ++k)
    add(std::uniform_int_distribution<std::int64_t>(kMin, kMax)(rng),
        std::uniform_int_distribution<std::int64_t>(1 << 23, (1 << 26) - 1)(rng));
  const std::vector<std::int32_t> q = floor_div_on_gl(ab);
  std::size_t wrong = 0, float_high = 0, float_low = 0;
  for (std::size_t i = 0; i < ab.size(); i += 2) {
    const std::int64_t a = ab[i], b = ab[i + 1];
    const std::int64_t want = a >= 0 ? a / b : -((b - 1 - a) / b);
    float_high += q[i + 1] > want;
    float_low += q[i + 1] < want;
    if (q[i] != want && wrong++ < 5)
      ADD_FAILURE() << "dl_floor_div(" << a << ", " << b << ") = " << q[i] << ", want " << want;
  }
  EXPECT_EQ(wrong, 0u) << "of " << ab.size() / 2 << " pairs";
  EXPECT_GT(float_high, 0u) << "no input needs the downward correction";
  EXPECT_GT(float_low, 0u) << "no input needs the upward correction";
  gl::check("floor division test");
}

// math=exact is the default (the same bits as without the option); a value other than exact
// or fast is refused naming the pipeline.
TEST(MathOption, ExactIsTheDefaultAndOtherValuesAreRefused) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(9, 7);
  const Params p = small_params();
  const State s0 = perturbed_state(m, 5);
  for (const char* name : {"glsl-tf", "glsl-compute"}) {
    auto plain = make_gl(name, {m, p, Integrator::rk4});
    auto exact = make_gl(name, {m, p, Integrator::rk4, {{"math", "exact"}}});
    EXPECT_TRUE(bitwise_equal(advance(*plain, s0, 5), advance(*exact, s0, 5))) << name;
    try {
      make_gl(name, {m, p, Integrator::rk4, {{"math", "precise"}}});
      ADD_FAILURE() << name << " accepted math=precise";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), std::string(name) + ": option math 'precise' is not exact or fast");
    }
  }
}

}  // namespace
}  // namespace deformlab::test
