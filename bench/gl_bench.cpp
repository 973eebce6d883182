// `deformlab-bench gl`: glsl-tf and glsl-compute ms per step on cloth grids, beside a
// pass-through transform feedback that only copies the two state attributes (the ceiling of
// the transform-feedback route on this GPU) and glsl-compute's bare gather (its loads and
// stores without its arithmetic).
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "bench.hpp"
#include "experiments/pipelines.hpp"
#include "gl/gl_pipeline.hpp"
#include "gl/pipelines_internal.hpp"
#if DEFORMLAB_HAVE_INTEROP
#include "interop/shared_buffers.hpp"
#endif

namespace deformlab::bench {

namespace {

// The GPU behind the GL context, whose clock the cases watch.
const std::string& gl_bus() {
  static const std::string bus = gpu_bus_id(*pipelines().find("glsl-compute"));
  return bus;
}

// `work` on GL timer queries (after `prepare`, untimed, each time) as the steps are timed
// (time_back_to_back: o.warmup calls, then about kGpuTimedMs of them, o.reps at the least).
Stats time_work(const std::function<void()>& prepare, const std::function<void()>& work, const StepOptions& o) {
  gl::QueryStepTimer timer;
  return stats(time_back_to_back(timer, work, o.warmup, o.reps, gl_bus(), 1, prepare));
}

// GPU ms per step of a GL pipeline, each step on its step clock after the warm-up; the GPU's
// clock over the timed steps.
Stats time_pipeline(Pipeline& p, const Model& m, const StepOptions& o) {
  const Stats s = stats(time_steps(p, m, o.warmup_ms, o.warmup, o.reps, gl_bus()));
  if (!(p.max_displacement() >= 0.0)) throw std::runtime_error("the benchmark state diverged");
  return s;
}

// The memory glsl-compute's node buffers take when no memory option is given (a build without
// interop has no CUDA memory to offer: GL's buffers).
std::unique_ptr<gl::NodeMemory> default_memory() {
#if DEFORMLAB_HAVE_INTEROP
  return interop::cuda_memory().make_default();
#else
  return gl::CudaMemory{}.make_default();
#endif
}

// Two vec4 attributes copied by a vertex shader into two transform feedback buffers,
// ping-pong, one vertex per node: the TF traffic of a glsl-tf step without its physics.
Stats time_passthrough(int n, const StepOptions& o) {
  using namespace gl;
  Program prog = make_program({{GL_VERTEX_SHADER, "passthrough.vert"}}, "", {"o0", "o1"});
  Buffer buf[2][2];
  VertexArray vao[2];
  TransformFeedback tfo[2];
  for (int s = 0; s < 2; ++s) {
    GLuint id = 0;
    glGenVertexArrays(1, &id);
    vao[s] = VertexArray(id);
    glBindVertexArray(id);
    for (GLuint a = 0; a < 2; ++a) {
      buf[s][a] = make_buffer(std::size_t(n) * 16);
      glBindBuffer(GL_ARRAY_BUFFER, buf[s][a].id());
      glVertexAttribPointer(a, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
      glEnableVertexAttribArray(a);
    }
  }
  glBindVertexArray(0);
  for (int s = 0; s < 2; ++s) {
    GLuint id = 0;
    glGenTransformFeedbacks(1, &id);
    tfo[s] = TransformFeedback(id);
    glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, id);
    for (GLuint a = 0; a < 2; ++a) glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, a, buf[s][a].id());
  }
  glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, 0);
  glUseProgram(prog.id());
  glEnable(GL_RASTERIZER_DISCARD);
  int k = 0;
  const auto copy = [&] {
    const int c = k++ % 2;
    glBindVertexArray(vao[c].id());
    glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, tfo[1 - c].id());
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, 0, n);
    glEndTransformFeedback();
  };
  warm_up(copy, glFinish, o.warmup_ms);
  const Stats s = time_work([] {}, copy, o);
  glDisable(GL_RASTERIZER_DISCARD);
  glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, 0);
  glBindVertexArray(0);
  glUseProgram(0);
  check("pass-through transform feedback");
  return s;
}

// glsl-compute's bare gather (shaders/bare_gather.comp) on an n x n cloth: step.comp's loads
// and stores for a one-pass integrator, ping-pong; its buffers where glsl-compute's node
// buffers are (the memory option's default here).
Stats time_bare_gather(int n, const StepOptions& o) {
  using namespace gl;
  const std::string defines = compute_tile_defines() + stencil_defines(false);
  Program prog = make_program({{GL_COMPUTE_SHADER, "bare_gather.comp"}}, defines);
  std::unique_ptr<NodeMemory> memory = default_memory();
  GLuint buf[2][2];
  const float half = 0.5f;
  for (int c = 0; c < 2; ++c)
    for (int a = 0; a < 2; ++a) {
      buf[c][a] = memory->add(std::size_t(n) * n * 16);
      glClearNamedBufferData(buf[c][a], GL_R32F, GL_RED, GL_FLOAT, &half);
    }
  glUseProgram(prog.id());
  glUniform1i(0, n);
  int k = 0;
  const auto bind = [&] {
    const int c = k++ % 2;
    for (GLuint a = 0; a < 2; ++a) {
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, a, buf[c][a]);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2 + a, buf[1 - c][a]);
    }
  };
  const auto dispatch = [&] {
    glDispatchCompute(GLuint((n + kComputeTileX - 1) / kComputeTileX), GLuint((n + kComputeTileY - 1) / kComputeTileY),
                      1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  };
  warm_up(
      [&] {
        bind();
        dispatch();
      },
      glFinish, o.warmup_ms);
  const Stats s = time_work(bind, dispatch, o);
  glUseProgram(0);
  check("the bare gather");
  return s;
}

void run_gl(const StepOptions& o) {
  const gl::ContextInfo& ctx = gl::context();  // first: on a software renderer the buffers count as host memory
  const Integrator integ = o.checked({"glsl-tf", "glsl-compute"});
  const SceneKind kind = o.scene_kind();
  CsvFile csv =
      open_csv(o.csv, "device,grid,nodes,what,median_ms,min_ms,p90_ms,sm_mhz_median,slowed_fraction", kRunColumns);
  std::cout << title("gl") << " ms per step (" << o.integrator << "), cloth grid, 12 springs per interior node\n"
            << describe(kind) << "\n"
            << "device: " << ctx.renderer << " (" << ctx.version << ")\n"
            << "method: each step on the " << gl::Timer().method() << "; " << warm_up_words(o)
            << counted(o.warmup, "warm-up step")
            << ", the median of steps timed back to back for about " << fixed(kGpuTimedMs, 0)
            << " ms (at least " << o.reps << ")\n"
            << "pass-through: transform feedback copying the two vec4 attributes (no physics), "
               "the ceiling of the transform-feedback route\n"
            << "bare gather: glsl-compute's loads and stores (its work groups and stencil) without its arithmetic; "
               "glsl-compute in exact and fast math\n"
            << "X of Y: Y's time over X's, the share of Y's speed that X reaches (ms columns: ms a step)\n\n"
            << std::setw(8) << "grid" << std::setw(16) << "pass-through" << std::setw(12) << "glsl-tf"
            << std::setw(14) << "tf of ceiling" << std::setw(14) << "bare gather" << std::setw(15) << "compute exact"
            << std::setw(14) << "compute fast" << std::setw(14) << "fast of bare" << "\n";
  ClockTally clocks;
  std::string memory;  // where the node buffers live, as the registry's pipelines chose
  // The registry's pipelines, as `deformlab run` makes them.
  auto make = [&](const char* name, const PipelineSetup& s) {
    auto p = pipelines().find(name)->make(s);
    const auto chosen = p->chosen_options();
    if (const auto it = chosen.find("memory"); it != chosen.end()) memory = it->second;
    return p;
  };
  for (int n : o.sizes) {
    const BenchScene scene(n, kind);
    const Model& m = scene.model;
    const PipelineSetup setup = scene.setup(integ);
    const Stats ceiling = time_passthrough(m.node_count(), o),
                bare = time_bare_gather(n, o);
    Stats tf, compute, compute_fast;
    std::string neighbours;
    {
      auto pipe = make("glsl-tf", setup);
      neighbours = dynamic_cast<gl::GlPipeline&>(*pipe).neighbour_mode();
      tf = time_pipeline(*pipe, m, o);
    }
    {
      auto pipe = make("glsl-compute", setup);
      compute = time_pipeline(*pipe, m, o);
    }
    {
      PipelineSetup fast = setup;
      fast.options["math"] = "fast";
      auto pipe = make("glsl-compute", fast);
      compute_fast = time_pipeline(*pipe, m, o);
    }
    std::cout << std::setw(8) << (std::to_string(n) + "^2") << std::fixed << std::setprecision(3) << std::setw(16)
              << ceiling.median << std::setw(12) << tf.median << std::setw(14)
              << fixed(100 * ceiling.median / tf.median, 1) + "%" << std::setw(14) << bare.median << std::setw(15)
              << compute.median << std::setw(14) << compute_fast.median << std::setw(14)
              << fixed(100 * bare.median / compute_fast.median, 1) + "%"
              << (neighbours == "grid arithmetic" ? "" : "  (" + neighbours + ")") << "\n";
    const std::pair<const char*, Stats> rows[] = {
        {"passthrough-tf", ceiling}, {"glsl-tf", tf}, {"compute-bare-gather", bare}, {"glsl-compute", compute},
        {"glsl-compute-fast", compute_fast}};
    for (const auto& [what, s] : rows) {
      clocks.add(std::to_string(n) + "^2 " + what, s.clock);
      if (csv)
        csv << '"' << ctx.renderer << "\"," << n << "x" << n << "," << m.node_count() << "," << what << ","
            << s.median << "," << s.min << "," << s.p90 << ","
            << clock_columns(s.clock) << run_columns(o) << "\n";
    }
  }
  if (!memory.empty())
    std::cout << "node buffers of glsl-tf, glsl-compute and the bare gather: memory=" << memory
              << " (chosen for this machine)\n";
  print_clocks(std::cout, clocks, "timed steps");
}

}  // namespace

void add_gl_bench(CLI::App& app) {
  add_step_bench(app, "gl", "glsl-tf and glsl-compute ms/step beside the pass-through transform feedback ceiling",
                 {256, 512, 1024, 2048}, 10, 50, "Timed steps at the least (more where they take under 200 ms)",
                 run_gl, Device::gpu);
}

}  // namespace deformlab::bench
