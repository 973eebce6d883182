#include "calibrate.hpp"

#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <numeric>
#include <vector>

#include "core/timed_work.hpp"
#include "cuda_kernels/check.cuh"
#include "cuda_kernels/cuda_pipeline.hpp"
#include "gl/context.hpp"
#include "gl/objects.hpp"
#include "shared_buffers.hpp"

namespace deformlab::interop {
namespace {

using cuda::check;
using clock_type = std::chrono::steady_clock;

double since_ms(clock_type::time_point t0) {
  return std::chrono::duration<double, std::milli>(clock_type::now() - t0).count();
}

// GL work timed as the steps are (time_back_to_back on GL timer queries, or the host clock on a
// software driver): `reps` calls at the least, after 3; the GPU `bus` watched.
TimedWork gl_timed(int reps, const std::string& bus, const std::function<void()>& work) {
  gl::QueryStepTimer timer;
  return time_back_to_back(timer, work, 3, reps, bus);
}

// How `w` was timed on `clock`, for the JSON.
std::string method_words(const std::string& clock, const TimedWork& w) {
  const double span = std::accumulate(w.ms.begin(), w.ms.end(), 0.0);
  return clock + ", median of " + std::to_string(w.ms.size()) + " back to back (" + std::to_string(int(span)) +
         " ms of them)";
}

nlohmann::json tf_rate(std::int64_t n, int reps, const std::string& bus) {
  const std::size_t bytes = std::size_t(n) * 16;
  gl::Buffer in_x = gl::make_buffer(bytes), in_v = gl::make_buffer(bytes);
  gl::Buffer out_x = gl::make_buffer(bytes), out_v = gl::make_buffer(bytes);
  gl::Program prog = gl::make_program({{GL_VERTEX_SHADER, "passthrough.vert"}}, "", {"o0", "o1"});
  GLuint vao = 0, tfo = 0;
  glGenVertexArrays(1, &vao);
  gl::VertexArray vao_h(vao);
  glBindVertexArray(vao);
  const GLuint attrs[2] = {in_x.id(), in_v.id()};
  for (GLuint a = 0; a < 2; ++a) {
    glBindBuffer(GL_ARRAY_BUFFER, attrs[a]);
    glVertexAttribPointer(a, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(a);
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glGenTransformFeedbacks(1, &tfo);
  gl::TransformFeedback tfo_h(tfo);
  glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, tfo);
  glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, out_x.id());
  glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 1, out_v.id());
  glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, 0);
  const TimedWork w = gl_timed(reps, bus, [&] {
    glUseProgram(prog.id());
    glEnable(GL_RASTERIZER_DISCARD);
    glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, tfo);
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, 0, GLsizei(n));
    glEndTransformFeedback();
    glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, 0);
    glDisable(GL_RASTERIZER_DISCARD);
    glUseProgram(0);
  });
  glBindVertexArray(0);
  gl::check("pass-through transform feedback");
  const double ms = w.median_ms();
  return {{"vertices", n},
          {"ms", ms},
          {"vertices_per_s", double(n) / (ms * 1e-3)},
          {"what", "vertex shader copying two vec4 attributes into two transform feedback buffers, rasteriser off"},
          {"method", method_words(gl::Timer().method(), w)},
          {"sm_clock", to_json(w.clock)}};
}

// Between two buffers of `memory`.
nlohmann::json compute_copy(std::int64_t n, int reps, const std::string& bus, gl::NodeMemory& memory) {
  const std::size_t bytes = std::size_t(n) * 16;
  const GLuint a = memory.add(bytes), b = memory.add(bytes);
  gl::Program prog = gl::make_program({{GL_COMPUTE_SHADER, "copy.comp"}});
  const GLuint groups = GLuint(std::min<std::int64_t>(65535, (n + 255) / 256));
  const TimedWork w = gl_timed(reps, bus, [&] {
    glUseProgram(prog.id());
    glUniform1i(gl::uniform(prog.id(), "u_n"), GLint(n));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, a);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, b);
    glDispatchCompute(groups, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(0);
  });
  gl::check("compute-shader copy");
  const double ms = w.median_ms();
  return {{"nodes", n},
          {"bytes_read_and_written", 2 * bytes},
          {"ms", ms},
          {"GB_per_s", 2.0 * double(bytes) / (ms * 1e6)},
          {"what", "compute shader copying one vec4 per node between two storage buffers"},
          {"memory", memory.name()},
          {"method", method_words(gl::Timer().method(), w)},
          {"sm_clock", to_json(w.clock)}};
}

// Round trips GL -> CUDA -> GL over three buffers of `nodes` vec4 (two CUDA reads, one it
// writes, as a hybrid force pass), with a token of work on each side so that each API
// really touches the buffers: GL clears 16 bytes of the first, CUDA sets 16 bytes of the
// third. Host clock over all rounds after a full drain, per hand-off (two per round).
nlohmann::json hand_off(Mode m, std::int64_t nodes, int rounds) {
  nlohmann::json j = {{"mode", to_string(m)}, {"nodes", nodes}, {"bytes_per_buffer", nodes * 16}};
  if (const std::string why = unavailable(m); !why.empty()) {
    j["unavailable"] = why;
    return j;
  }
  auto sb = make_shared_buffers(m);
  const std::size_t bytes = std::size_t(nodes) * 16;
  const GLuint x = sb->add(bytes, CudaAccess::read), v = sb->add(bytes, CudaAccess::read);
  const GLuint acc = sb->add(bytes, CudaAccess::write);
  const std::vector<GLuint> handed{x, v, acc};
  const float zero = 0.f;
  auto round = [&] {
    glClearNamedBufferSubData(x, GL_R32F, 0, 16, GL_RED, GL_FLOAT, &zero);
    sb->to_cuda(handed);
    check(cudaMemsetAsync(sb->cuda_ptr(acc), 0, 16, sb->stream()), "the token CUDA work");
    sb->to_gl();
  };
  auto drain = [&] {
    glFinish();
    check(cudaStreamSynchronize(sb->stream()), "draining the hand-off rounds");
  };
  for (int r = 0; r < 20; ++r) round();
  drain();
  const auto t0 = clock_type::now();
  double host_wait = 0.0;
  for (int r = 0; r < rounds; ++r) {
    const auto t = clock_type::now();
    round();
    host_wait += since_ms(t);
  }
  drain();
  const double ms = since_ms(t0);
  gl::check("hand-off rounds");
  j["us_per_hand_off"] = ms * 1e3 / (2.0 * rounds);
  j["host_us_per_round"] = host_wait * 1e3 / rounds;
  j["method"] = "host clock over " + std::to_string(rounds) + " round trips after a drain, divided by " +
                std::to_string(2 * rounds) + " hand-offs";
  return j;
}

// The floor: GL signals, CUDA waits and signals back, GL waits; no buffers, no work.
nlohmann::json floor_ping_pong(int rounds) {
  nlohmann::json j = {{"what", "timeline semaphore ping-pong between GL and CUDA, no work, no buffers"}};
  if (const std::string why = unavailable(Mode::external_gpusync); !why.empty()) {
    j["unavailable"] = why;
    return j;
  }
  auto sb = make_shared_buffers(Mode::external_gpusync);
  auto drain = [&] {
    glFinish();
    check(cudaStreamSynchronize(sb->stream()), "draining the ping-pong");
  };
  for (int r = 0; r < 20; ++r) { sb->to_cuda({}); sb->to_gl(); }
  drain();
  const auto t0 = clock_type::now();
  for (int r = 0; r < rounds; ++r) {
    sb->to_cuda({});
    sb->to_gl();
  }
  drain();
  const double ms = since_ms(t0);
  gl::check("semaphore ping-pong");
  j["us_per_hand_off"] = ms * 1e3 / (2.0 * rounds);
  j["method"] = "host clock over " + std::to_string(rounds) + " round trips queued without CPU waits, divided by " +
                std::to_string(2 * rounds) + " hand-offs";
  return j;
}

}  // namespace

double hand_off_floor_us(int round_trips) {
  const nlohmann::json j = floor_ping_pong(round_trips);
  return j.contains("us_per_hand_off") ? j["us_per_hand_off"].get<double>() : std::nan("");
}

nlohmann::json calibrate(const CalibrateOptions& o, std::ostream& log) {
  int dev = -1;
  try {
    dev = cuda_device_of_gl();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("calibrate measures CUDA and OpenGL on one GPU: ") + e.what());
  }
  const gl::ContextInfo& ctx = gl::context();
  check(cudaSetDevice(dev), "selecting the CUDA device behind the OpenGL context");
  const cuda::DeviceInfo d = cuda::device_info();
  nlohmann::json j;
  j["device"] = {{"cuda_device", dev},
                 {"name", d.name},
                 {"sm_count", d.sm_count},
                 {"memory_gib", d.memory_gib},
                 {"compute_capability", std::to_string(d.cc_major) + "." + std::to_string(d.cc_minor)},
                 {"cuda_driver", d.driver_version},
                 {"cuda_runtime", d.runtime_version},
                 {"gl_renderer", ctx.renderer},
                 {"gl_version", ctx.version},
                 {"egl_platform", ctx.platform}};
  log << "calibrate: " << d.name << " (CUDA device " << dev << "), GL " << ctx.renderer << "\n";

  const TimedWork copy_work = cuda::time_copy(o.copy_bytes, o.reps, kGpuWarmUpMs);
  const double copy = copy_work.median_ms();
  j["copy"] = {{"bytes", o.copy_bytes},
               {"ms", copy},
               {"GB_per_s", 2.0 * double(o.copy_bytes) / (copy * 1e6)},
               {"what", "cudaMemcpy device to device; GB/s counts read + write"},
               {"method", method_words("CUDA events", copy_work) + " after " + std::to_string(int(kGpuWarmUpMs)) +
                              " ms of copies"},
               {"sm_clock", to_json(copy_work.clock)}};
  log << "  copy: " << j["copy"]["GB_per_s"].get<double>() << " GB/s\n";
  j["transform_feedback"] = tf_rate(o.tf_vertices, o.reps, d.pci_bus_id);
  log << "  transform feedback: " << j["transform_feedback"]["vertices_per_s"].get<double>() / 1e6 << " M vertices/s\n";
  // The ceiling on the memory the GL pipelines' node buffers take by default; where that is
  // CUDA's, the copy between GL's own buffers beside it.
  std::unique_ptr<gl::NodeMemory> memory = cuda_memory().make_default();
  j["compute_copy"] = compute_copy(o.compute_nodes, o.reps, d.pci_bus_id, *memory);
  log << "  compute copy (memory=" << memory->name() << "): " << j["compute_copy"]["GB_per_s"].get<double>()
      << " GB/s\n";
  if (std::string_view(memory->name()) != "gl") {
    memory.reset();
    gl::GlBufferMemory gl_buffers;
    j["compute_copy_gl_buffers"] = compute_copy(o.compute_nodes, o.reps, d.pci_bus_id, gl_buffers);
    log << "  compute copy (memory=gl): " << j["compute_copy_gl_buffers"]["GB_per_s"].get<double>() << " GB/s\n";
  }

  // external-gpusync last: it brings up Vulkan, the one mode that touches a third API.
  j["hand_off"] = nlohmann::json::array();
  for (Mode m : {Mode::map, Mode::external, Mode::staged, Mode::external_gpusync})
    for (std::int64_t n : o.hand_off_nodes) {
      nlohmann::json h;
      try {
        h = hand_off(m, n, o.round_trips);
      } catch (const std::exception& e) {
        h = {{"mode", to_string(m)}, {"nodes", n}, {"error", e.what()}};
      }
      log << "  hand-off " << to_string(m) << ", " << n << " nodes: ";
      if (h.contains("unavailable"))
        log << "unavailable: " << h["unavailable"].get<std::string>() << "\n";
      else if (h.contains("error"))
        log << "failed: " << h["error"].get<std::string>() << "\n";
      else
        log << h["us_per_hand_off"].get<double>() << " us\n";
      j["hand_off"].push_back(std::move(h));
    }
  try {
    j["floor"] = floor_ping_pong(10 * o.round_trips);
  } catch (const std::exception& e) {
    j["floor"] = {{"error", e.what()}};
    log << "  floor: failed: " << e.what() << "\n";
  }
  if (j["floor"].contains("us_per_hand_off"))
    log << "  floor (semaphore ping-pong, no work): " << j["floor"]["us_per_hand_off"].get<double>() << " us\n";
  return j;
}

}  // namespace deformlab::interop
