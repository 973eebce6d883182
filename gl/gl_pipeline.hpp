// What the glsl-tf and glsl-compute pipelines share: the model and state on the GPU, the
// integrator's schedule as GPU passes, the displacement reduction and the timers. The two
// differ only in how a pass runs (transform feedback or compute shader).
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "core/pipeline.hpp"
#include "objects.hpp"

namespace deformlab::gl {

// Forces from outside the GL layer (the hybrid pipelines): another stage writes each node's
// acceleration into a GL buffer that the update passes read instead of evaluating forces.
enum class NodeRole { state, accelerations };
class ExternalForces {
 public:
  virtual ~ExternalForces() = default;
  // A GL buffer of `bytes` that the force stage owns: a state the forces are evaluated at
  // (the stage reads it) or the accelerations (the stage writes them).
  virtual GLuint node_buffer(std::size_t bytes, NodeRole role) = 0;
  // Before each update pass: acc = a(x, v) at time t. GL commands issued before this call
  // wrote x and v; those issued after it read acc.
  virtual void forces(GLuint x, GLuint v, GLuint acc, double t) = 0;
  // After each update pass was issued.
  virtual void update_issued() {}
};

class GlPipeline : public Pipeline {
 public:
  ~GlPipeline() override;
  void set_state(const State& s) override;
  State state() override;
  void step() override;
  double max_displacement() override;
  std::string timing_method() const override { return spans_.method(); }

  // The current positions, one vec4 per node (w: inverse mass), ready to be read by GL.
  GLuint position_buffer();
  // While profiled, each step's passes are one force+update span timed by the GL clock
  // (without an external force stage, which times the passes itself).
  void set_profiler(Profiler* p) override;
  // "grid arithmetic" or "adjacency buffer": how the shaders find a node's springs.
  std::string neighbour_mode() const { return m_.grid() ? "grid arithmetic" : "adjacency buffer"; }

 protected:
  // A GPU pass: the forces at stage `stage`, then (see shaders/sim.glsl) the step's result by
  // the one-pass rule (one), the next stage state (stage) or the step's result (result).
  enum class PassKind { one, stage, result };
  struct NodeBuffer {
    Buffer buf;           // owned here, or
    GLuint external = 0;  // owned by the external force stage
    Texture tex;          // texture buffer view (RGBA32F)
    GLuint id() const { return external ? external : buf.id(); }
  };
  // What one pass reads and writes (besides the earlier stages' slopes, bound as textures
  // for both pipelines). s0: the current state (and Verlet's previous positions); src: the
  // state the forces are evaluated at.
  struct PassIO {
    int set;  // index of the current state set (VAO set of the TF pipeline)
    const NodeBuffer *s0_x, *s0_v, *s0_p, *src_x, *src_v;
    std::array<const NodeBuffer*, 3> out;
    int outputs;
    const NodeBuffer* forces_acc;  // accelerations from the external force stage, else null
  };

  // With `forces`, the passes read accelerations from it instead of evaluating forces.
  GlPipeline(const PipelineSetup& s, std::string name, ExternalForces* forces = nullptr);
  // Compiles the programs of the schedule's passes; call at the end of the subclass constructor.
  void init();
  // `defines` selects the pass kind, its stage, the update rule and the neighbour mode (see
  // shaders/sim.glsl); `outputs` values per node are written.
  virtual Program make_program(int outputs, const std::string& defines) = 0;
  virtual void run_pass(GLuint program, const PassIO& io) = 0;
  // The state was replaced from the host.
  virtual void on_set_state() {}

  int n_ = 0;
  const std::string name_;
  ExternalForces* const forces_;
  NodeBuffer forces_acc_;  // what the external force stage writes
  std::array<NodeBuffer, 2> x_, v_, xp_;  // state sets, ping-pong (xp_: Verlet)
  // Runge-Kutta stages: sx_[k], sv_[k] the state of stage k + 1, sa_[k] the acceleration at stage k.
  std::array<NodeBuffer, kMaxStages - 1> sx_, sv_, sa_;

 private:
  struct GpuPass {
    PassKind kind;
    int stage;
    double time_fraction;
    std::array<float, kMaxStages> weights;  // of the slopes 0..stage (one: b_0)
    Program prog;
    GLint drag_force_target, drag_next, has_prev;
  };
  void make_buffers(const Schedule& s);
  void upload_params();
  void upload_adjacency();
  void plan(const Schedule& s);
  void bind_textures(int stage) const;  // earlier stages' slopes and the adjacency

  const Model& m_;
  const Params p_;
  const UpdateRule rule_;
  std::vector<GpuPass> passes_;
  Buffer params_ubo_, adj_offset_, links_, result_;
  Texture adj_offset_tex_, links_tex_;
  Program reduce_, copy_;
  GLint reduce_n_ = -1, copy_n_ = -1;
  Profiler* prof_ = nullptr;
  TimerSpans spans_;  // the profiled steps
  int cur_ = 0;
  bool has_prev_ = false, stepped_ = false;
  double t_ = 0.0;
};

}  // namespace deformlab::gl
