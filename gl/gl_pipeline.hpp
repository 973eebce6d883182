// What the glsl-tf and glsl-compute pipelines share: the model and state on the GPU, the
// integrator's schedule as GPU passes, the displacement reduction and the timers. The two
// differ only in how a pass runs (transform feedback or compute shader).
#pragma once
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/pipeline.hpp"
#include "core/stage.hpp"
#include "objects.hpp"

namespace deformlab::gl {

// Buffers that a force stage outside GL shares with it (the hybrid pipelines): it allocates
// the states the forces are evaluated at (it reads them) and the accelerations (it writes them).
enum class NodeRole { state, accelerations };
using SharedAllocator = std::function<GLuint(std::size_t bytes, NodeRole role)>;

// Where a GL pipeline's own node buffers live (option "memory"): "gl", GL's own buffers, or
// "cuda", memory from CUDA's allocator imported into GL, which GL's passes reach faster on
// large unordered meshes (docs/speed.md). The interop layer provides the latter.
class NodeMemory {
 public:
  virtual ~NodeMemory() = default;
  // A buffer of `bytes` (contents undefined), its GL name valid while this object lives.
  virtual GLuint add(std::size_t bytes) = 0;
  // The option's value for this memory: "gl" or "cuda".
  virtual const char* name() const = 0;
};
// memory=gl: GL's own buffers.
class GlBufferMemory final : public NodeMemory {
 public:
  GLuint add(std::size_t bytes) override;
  const char* name() const override { return "gl"; }

 private:
  std::vector<Buffer> buffers_;
};
struct CudaMemory {
  std::function<std::string()> unavailable;  // empty when usable here, else why not
  std::function<std::unique_ptr<NodeMemory>()> make;

  // Empty when this build has CUDA's memory and this machine can use it, else why not.
  std::string why_not() const;
  // The memory a GL pipeline takes when no option names one: CUDA's where usable, else GL's.
  std::unique_ptr<NodeMemory> make_default() const;
};

// A range of nodes one storage-buffer dispatch covers: it writes [first, first + count) and
// reads [read_first, read_first + read_count), the written nodes and their springs' reach.
struct NodeWindow {
  int first, count, read_first, read_count;
};
// Windows over n nodes whose bound ranges hold at most max_nodes nodes each and start at
// multiples of align nodes (one window when n fits); throws std::invalid_argument when the
// reach leaves no room. A driver addresses a storage buffer binding with 32-bit offsets
// (GL_MAX_SHADER_STORAGE_BLOCK_SIZE): larger models run window by window.
std::vector<NodeWindow> node_windows(std::int64_t n, std::int64_t reach, std::int64_t max_nodes, std::int64_t align);

// Reads the options' values as far as they do not depend on the GL context (PipelineEntry::
// read_options): math, memory, and window and link_view as counts.
void read_options(const PipelineOptions& o);
// Why an option of `o` would do nothing on a model of topology t (link_view on a grid), else empty.
std::string idle_option(const PipelineOptions& o, Topology t);

// Host and GPU bytes of a GL pipeline beyond the model (with an outside force stage: its
// accelerations buffer too).
Footprint footprint(const ModelSize& m, Integrator i, bool outside_forces);

class GlPipeline : public Pipeline, public ForceStage, public UpdateStage {
 public:
  ~GlPipeline() override;
  void set_state(const State& s) override;
  State state() override;
  void set_drag(const DragHandle& d) override;
  void step() override;  // the schedule's passes with the forces in the shaders, then finish_step()
  // The shaders evaluate a force pass inside the GPU pass of the update that follows it:
  // this records the time of those forces.
  void forces(int src, int acc, double t) override;
  // The schedule's next GPU pass: the forces (or, with an outside force stage, the
  // accelerations it wrote) and this update.
  void update(const Pass& pass) override;
  // After a step's last pass: the result becomes the current state.
  void finish_step();
  double time() const { return t_; }

  // For an outside force stage: the positions and velocities of state slot `slot` (GL wrote
  // them before the stage runs) and the accelerations it writes (GL reads them after).
  std::array<GLuint, 2> slot_buffers(int slot) const;
  GLuint force_buffer() const { return forces_acc_.id; }
  double max_displacement() override;
  // The state sets ping-pong: the set before the last step is kept until the next one.
  bool can_step_back() const override { return true; }
  void step_back() override;
  void queue_displacement() override;
  double take_displacement() override;
  std::string timing_method() const override { return spans_.method(); }
  std::unique_ptr<StepTimer> step_timer() override { return std::make_unique<QueryStepTimer>(); }
  std::map<std::string, std::string> chosen_options() const override { return chosen_; }

  unsigned gl_position_buffer() override;
  // While profiled, each step's passes are one force+update span timed by the GL clock
  // (without an outside force stage, whose pipeline times the passes itself).
  void set_profiler(Profiler* p) override;
  // "grid arithmetic" or "adjacency buffer": how the shaders find a node's springs.
  std::string neighbour_mode() const { return m_.grid() ? "grid arithmetic" : "adjacency buffer"; }

 protected:
  // A GPU pass: the forces at stage `stage`, then (see shaders/sim.glsl) the step's result by
  // the one-pass rule (one), the next stage state (stage) or the step's result (result).
  enum class PassKind { one, stage, result };
  struct NodeBuffer {
    GLuint id = 0;  // owned by memory_ or by the outside force stage
    Texture tex;    // texture buffer view (RGBA32F)
  };
  // What one pass reads and writes (besides the earlier stages' slopes, bound as textures
  // for both pipelines). s0: the current state; src: the state the forces are evaluated at.
  struct PassIO {
    int set;  // index of the current state set (VAO set of the TF pipeline)
    const NodeBuffer *s0_x, *s0_v, *src_x, *src_v;
    std::array<const NodeBuffer*, 3> out;
    int outputs;
    const NodeBuffer* forces_acc;  // accelerations from an outside force stage, else null
    // Passes that write the step's result: the buffer of the stop-rule words (else 0) and the
    // word of this step (set by its destination state set; the other is the step before's).
    GLuint result_max;
    int result_word;
    // Result passes of pipelines that post their words (posts_words): the host-mapped buffer
    // the pass's first work group posts the step before's word into, tagged with launch - 1,
    // the number of that step's result pass (low 32 bits).
    GLuint posted;
    std::uint32_t launch;
  };

  // With `shared`, the passes read accelerations that an outside force stage writes into
  // buffers it allocates, instead of evaluating forces. Options: "window", nodes per
  // storage-buffer window; "link_view", links per texture-buffer view of a general model's
  // adjacency (default for both: the driver's limit); "math", exact or fast (core/pipeline.hpp);
  // "memory", gl or cuda (the latter from `cuda`; default: cuda where `cuda` is available, else gl).
  GlPipeline(const PipelineSetup& s, std::string name, SharedAllocator shared, const CudaMemory& cuda);
  // Throws std::invalid_argument naming the driver's limit when `texels` texels do not fit
  // in one texture buffer.
  void require_texels(std::int64_t texels, const std::string& what) const;
  // Binds nodes [first, first + count) of `b` to storage binding `index`.
  static void bind_nodes(GLuint index, const NodeBuffer& b, int first, int count);
  // Compiles the programs of the schedule's passes; call at the end of the subclass constructor.
  void init();
  // `defines` selects the pass kind, its stage, the update rule, the neighbour mode and the
  // math (see shaders/sim.glsl); `outputs` values per node are written.
  virtual Program make_program(int outputs, const std::string& defines) = 0;
  virtual void run_pass(GLuint program, const PassIO& io) = 0;
  // The state was replaced from the host.
  virtual void on_set_state() {}
  // Leaves the last step's largest displacement (a float's bits) in its stop-rule word
  // (PassIO::result_word of its result pass), visible to a buffer copy. By default it reduces
  // the w of the current velocities (the passes' stop-rule terms), window by window.
  virtual void reduce_displacement();
  // Whether each result pass posts the step before's word (PassIO::posted): a queued read then
  // needs no copy and no fence when the next step follows it.
  virtual bool posts_words() const { return false; }

  const Model& model() const { return m_; }

  int n_ = 0;
  std::vector<NodeWindow> windows_;  // of the storage-buffer passes
  const std::string name_;
  const SharedAllocator shared_;
  // The own node buffers' memory. Declared before the buffers, so destroyed after them.
  std::unique_ptr<NodeMemory> memory_;
  NodeBuffer forces_acc_;  // what the outside force stage writes
  std::array<NodeBuffer, 2> x_, v_;  // state sets, ping-pong
  // Runge-Kutta stages: sx_[k], sv_[k] the state of stage k + 1, sa_[k] the acceleration at stage k.
  std::array<NodeBuffer, kMaxStages - 1> sx_, sv_, sa_;

 private:
  struct GpuPass {
    PassKind kind;
    int stage;
    std::array<float, kMaxStages> weights;  // of the slopes 0..stage (one: b_0)
    Program prog;
    GLint drag_force_target, drag_next, half_step;
  };
  // memory_ and chosen_ from option "memory".
  void choose_memory(const PipelineOptions& o, const CudaMemory& cuda);
  void make_buffers();
  void upload_params();
  void upload_adjacency();
  void plan();
  void bind_textures(int stage) const;  // earlier stages' slopes and the adjacency
  void plan_windows(const PipelineOptions& o);
  void plan_link_views(const PipelineOptions& o);
  // The value of count option `name`, from 1 to `most`, else `most`.
  std::int64_t count_option(const PipelineOptions& o, const std::string& name, std::int64_t most,
                            const std::string& limit) const;
  // Throws std::invalid_argument when the GPU (or, for a software renderer, the host) has
  // less free memory than `bytes`.
  void require_memory(std::int64_t bytes) const;

  std::map<std::string, std::string> chosen_;
  const Model& m_;
  Params p_;
  const UpdateRule rule_;
  Schedule sched_;
  const Math math_;
  std::vector<GpuPass> passes_;
  std::size_t next_pass_ = 0;  // of this step
  double force_t_ = 0.0;       // of the forces of the next pass
  // Byte offset in result_ of the stop-rule word of the step into state set `set`; zeroing it.
  static GLintptr word_offset(int set) { return GLintptr(set) * 4; }
  void clear_word(int set);

  Buffer params_ubo_, adj_offset_, links_, result_;
  // result_: a stop-rule word per state set, 0 before a step reduces into it. readback_,
  // mapped at readback_word_: the posted word (low half: its tag, high half: the word); a copy
  // of a word goes into its high half, and the fence read_done_ is signalled when it is done.
  Buffer readback_;
  std::uint64_t* readback_word_ = nullptr;
  GLsync read_done_ = nullptr;
  std::uint64_t launches_ = 0;  // result passes queued
  // A queued read: of the word of result pass read_launch_ (0: no step since the state was set).
  bool read_queued_ = false;
  std::uint64_t read_launch_ = 0;
  void copy_word();             // queues the copy of the last step's word and the fence
  std::uint32_t copied_word();  // waits for the copy
  std::uint32_t posted_word(std::uint64_t launch);  // waits for the word the next pass posts
  Texture adj_offset_tex_;
  // The links in views of link_view_ texels each (units 9, then 11.. in shaders/sim.glsl).
  static constexpr int kLinkViews = 4;
  std::vector<Texture> link_views_;
  std::int64_t link_view_ = 0;
  Program reduce_, copy_;
  GLint reduce_n_ = -1, reduce_word_ = -1, copy_n_ = -1;
  std::int64_t max_texels_ = 0, max_block_nodes_ = 0;
  Profiler* prof_ = nullptr;
  TimerSpans spans_;  // the profiled steps
  int cur_ = 0;
  bool half_step_ = false, stepped_ = false;
  double t_ = 0.0;
  // Whether the last step can be taken back, and what it changed besides cur_.
  enum class Back { none, possible, taken };
  Back back_ = Back::none;
  double back_t_ = 0.0;
  bool back_half_step_ = false;
};

}  // namespace deformlab::gl
