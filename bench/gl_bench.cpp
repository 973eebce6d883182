// `deformlab-bench gl`: glsl-tf and glsl-compute ms per step on cloth grids, beside a
// pass-through transform feedback that only copies the two state attributes: the ceiling
// of the transform-feedback route on this GPU.
#include <iomanip>
#include <iostream>
#include <memory>

#include "bench.hpp"
#include "core/state.hpp"
#include "gl/gl_pipeline.hpp"
#include "gl/pipelines_internal.hpp"

namespace deformlab::bench {

namespace {

// GPU ms per step of a GL pipeline, each step on its step clock after the warm-up.
Stats time_pipeline(Pipeline& p, const Model& m, const StepOptions& o) {
  p.set_state(rest_state(m));
  const auto timer = p.step_timer();
  timed_steps(p, *timer, o.warmup);
  const Stats s = stats(timed_steps(p, *timer, o.reps));
  if (!(p.max_displacement() >= 0.0)) throw std::runtime_error("the benchmark state diverged");
  return s;
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
  Timer timer;
  glUseProgram(prog.id());
  glEnable(GL_RASTERIZER_DISCARD);
  for (int k = 0; k < o.warmup + o.reps; ++k) {
    if (k == o.warmup) timer.take();
    const int c = k % 2;
    timer.begin();
    glBindVertexArray(vao[c].id());
    glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, tfo[1 - c].id());
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, 0, n);
    glEndTransformFeedback();
    timer.end();
  }
  glDisable(GL_RASTERIZER_DISCARD);
  glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, 0);
  glBindVertexArray(0);
  glUseProgram(0);
  const Stats s = stats(timer.take());
  check("pass-through transform feedback");
  return s;
}

void run_gl(const StepOptions& o) {
  const Integrator integ = o.integ();
  const gl::ContextInfo& ctx = gl::context();
  const SceneKind kind = o.scene_kind();
  std::cout << "deformlab-bench gl: ms per step (" << o.integrator << "), cloth grid, 12 springs per interior node\n"
            << describe(kind) << "\n"
            << "device: " << ctx.renderer << " (" << ctx.version << ")\n"
            << "method: " << gl::Timer().method() << " around each step, " << o.warmup
            << " warm-up steps, median of " << o.reps << " timed steps\n"
            << "pass-through: transform feedback copying the two vec4 attributes (no physics), "
               "the ceiling of the transform-feedback route\n\n"
            << std::setw(8) << "grid" << std::setw(16) << "pass-through" << std::setw(12) << "glsl-tf"
            << std::setw(14) << "tf/ceiling" << std::setw(14) << "glsl-compute" << std::setw(16) << "tf Mnodes/s"
            << std::setw(18) << "compute Mnodes/s" << "\n";
  std::ofstream csv = open_csv(o.csv, "device,grid,nodes,what,median_ms,min_ms,p90_ms");
  for (int n : o.sizes) {
    const BenchScene scene(n, kind);
    const Model& m = scene.model;
    const PipelineSetup setup = scene.setup(integ);
    Stats ceiling = time_passthrough(m.node_count(), o), tf, compute;
    std::string neighbours;
    {
      auto pipe = gl::make_tf_pipeline(setup);
      neighbours = dynamic_cast<gl::GlPipeline&>(*pipe).neighbour_mode();
      tf = time_pipeline(*pipe, m, o);
    }
    {
      auto pipe = gl::make_compute_pipeline(setup);
      compute = time_pipeline(*pipe, m, o);
    }
    auto rate = [&](const Stats& s) { return m.node_count() / (s.median * 1e3); };
    std::cout << std::setw(8) << (std::to_string(n) + "^2") << std::fixed << std::setprecision(3) << std::setw(16)
              << ceiling.median << std::setw(12) << tf.median << std::setw(14) << std::setprecision(3)
              << tf.median / ceiling.median << std::setw(14) << compute.median << std::setw(16)
              << std::setprecision(1) << rate(tf) << std::setw(18) << rate(compute)
              << (neighbours == "grid arithmetic" ? "" : "  (" + neighbours + ")") << "\n";
    if (csv) {
      const std::pair<const char*, Stats> rows[] = {{"passthrough-tf", ceiling}, {"glsl-tf", tf}, {"glsl-compute", compute}};
      for (const auto& [what, s] : rows)
        csv << '"' << ctx.renderer << "\"," << n << "x" << n << "," << m.node_count() << "," << what << ","
            << s.median << "," << s.min << "," << s.p90 << "\n";
    }
  }
}

}  // namespace

void add_gl_bench(CLI::App& app) {
  add_step_bench(app, "gl", "glsl-tf and glsl-compute ms/step beside the pass-through transform feedback ceiling",
                 {256, 512, 1024, 2048}, 10, 50, run_gl);
}

}  // namespace deformlab::bench
