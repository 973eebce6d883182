#include "gl_pipeline.hpp"
#include "pipelines_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/step_params.hpp"

namespace deformlab::gl {
namespace {

using P = Physics<float>;

// std140 mirror of the uniform block Sim in shaders/sim.glsl.
struct SimBlock {
  P::StepParams params;
  P::StencilEntry stencil[MAX_STENCIL];
};
static_assert(sizeof(P::StepParams) == 208 && sizeof(P::StencilEntry) == 32 && offsetof(SimBlock, stencil) == 208,
              "StepParams and StencilEntry must keep the std140 layout of shaders/sim.glsl");

// Nodes between a node and its farthest spring neighbour in the node order (general: any).
std::int64_t spring_reach(const Model& m) {
  if (!m.grid()) return m.node_count();
  std::int64_t reach = 0;
  for (int e = 0; e < grid_stencil_size(m.volume()); ++e) {
    const GridOffset o = grid_offset(m.volume(), e);
    reach = std::max(reach, std::abs(o.di + std::int64_t(o.dj) * m.nx + std::int64_t(o.dk) * m.nx * m.ny));
  }
  return reach;
}

// The option "math", its error naming the pipeline.
Math read_math(const std::string& name, const PipelineOptions& o) {
  try {
    return math_option(o);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(name + ": " + e.what());
  }
}

}  // namespace

std::string stencil_defines(bool volume) {
  const int n = grid_stencil_size(volume);
  std::string offsets;
  for (int e = 0; e < n; ++e) {
    const GridOffset o = grid_offset(volume, e);
    offsets += std::string(e ? ", " : "") + "ivec3(" + std::to_string(o.di) + ", " + std::to_string(o.dj) + ", " +
               std::to_string(o.dk) + ")";
  }
  return "#define STENCIL_SIZE " + std::to_string(n) + "\n#define STENCIL_VOLUME " + (volume ? "true" : "false") +
         "\n#define STENCIL_OFFSETS ivec3[](" + offsets + ")\n";
}

std::vector<NodeWindow> node_windows(std::int64_t n, std::int64_t reach, std::int64_t max_nodes, std::int64_t align) {
  if (n <= max_nodes) return {{0, int(n), 0, int(n)}};
  const std::int64_t width = (max_nodes - 2 * reach - 2 * align) / align * align;
  if (width < align)
    throw std::invalid_argument("a model of " + std::to_string(n) + " nodes whose springs reach " +
                                std::to_string(reach) + " nodes apart does not fit in storage-buffer windows of " +
                                std::to_string(max_nodes) + " nodes");
  std::vector<NodeWindow> out;
  for (std::int64_t first = 0; first < n; first += width) {
    const std::int64_t count = std::min(width, n - first);
    const std::int64_t read_first = std::max<std::int64_t>(0, first - reach) / align * align;
    const std::int64_t read_end = std::min(n, first + count + reach);
    out.push_back({int(first), int(count), int(read_first), int(read_end - read_first)});
  }
  return out;
}

void read_options(const PipelineOptions& o) {
  math_option(o);
  if (const auto it = o.find("memory"); it != o.end() && it->second != "gl" && it->second != "cuda")
    throw std::invalid_argument("option memory '" + it->second + "' is not one of gl, cuda");
  for (const char* name : {"window", "link_view"})
    if (const auto it = o.find(name); it != o.end() && !option_count(it->second, INT64_MAX))
      throw std::invalid_argument(std::string("option ") + name + " '" + it->second +
                                  "' is not a count of 1 or more (plain digits, no leading zero)");
}

std::string idle_option(const PipelineOptions& o, Topology t) {
  if (o.count("link_view") && t != Topology::general)
    return "option link_view: a mesh's option (links per texture-buffer view of its adjacency), and this model is a grid";
  return {};
}

Footprint footprint(const ModelSize& m, Integrator i, bool outside_forces) {
  const Schedule s = make_schedule(i);
  const std::int64_t n = m.nodes, node_buffers = 4 + 3 * s.stage_states + (outside_forces ? 1 : 0);
  const std::int64_t chunk = 16 * std::min<std::int64_t>(n, kTransferChunkNodes);  // staging, host and GPU
  const std::int64_t adjacency = m.grid || outside_forces ? 0 : (n + 1) * 4 + 2 * m.springs * 16;
  return {chunk, n * 16 * node_buffers + adjacency + chunk};
}

GlPipeline::GlPipeline(const PipelineSetup& s, std::string name, SharedAllocator shared, const CudaMemory& cuda)
    : name_(std::move(name)),
      shared_(std::move(shared)),
      m_(s.model),
      p_(s.params),
      rule_(info(s.integrator).rule),
      sched_(make_schedule(s.integrator)),
      math_(read_math(name_, s.options)) {
  context();
  n_ = m_.node_count();
  if (n_ < 1) throw std::invalid_argument(name_ + ": the model has no nodes");
  GLint max_texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
  max_texels_ = max_texels;
  const bool adjacency = !m_.grid() && !shared_;  // general models read it through texture buffers
  if (adjacency) require_texels(n_ + 1, "the adjacency offsets");
  if (sched_.stage_states > 0) require_texels(n_, "the Runge-Kutta stage slopes");
  plan_windows(s.options);
  if (adjacency) plan_link_views(s.options);
  require_memory(footprint(m_.size(), s.integrator, bool(shared_)).device);
  plan();
  choose_memory(s.options, cuda);
  make_buffers();
  upload_params();
  if (adjacency) upload_adjacency();
  const std::uint32_t zeros[2] = {0, 0};
  result_ = make_buffer(sizeof zeros, zeros);
  GLuint id = 0;
  glCreateBuffers(1, &id);
  readback_ = Buffer(id);
  const GLbitfield flags = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
  const std::uint64_t none = 0;
  glNamedBufferStorage(id, 8, &none, flags);
  readback_word_ = static_cast<std::uint64_t*>(glMapNamedBufferRange(id, 0, 8, flags));
  if (!readback_word_) throw std::runtime_error(name_ + ": mapping the displacement read-back failed");
}

GlPipeline::~GlPipeline() {
  if (read_done_) glDeleteSync(read_done_);
}

void GlPipeline::require_texels(std::int64_t texels, const std::string& what) const {
  if (texels > max_texels_)
    throw std::invalid_argument(name_ + ": " + what + " need texture buffers of " + std::to_string(texels) +
                                " texels; this driver's limit is " + std::to_string(max_texels_) +
                                " (GL_MAX_TEXTURE_BUFFER_SIZE)");
}

void GlPipeline::require_memory(std::int64_t bytes) const {
  std::optional<MemoryLimit> limit;
  if (GLEW_NVX_gpu_memory_info) {
    GLint kb = 0;
    glGetIntegerv(GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX, &kb);
    limit = MemoryLimit{std::int64_t(kb) * 1024, "the GPU's free memory (GL_NVX_gpu_memory_info)"};
  } else if (context().software) {
    limit = host_memory_limit();  // a software renderer's buffers are host memory
  }
  if (limit && bytes > limit->bytes)
    throw std::invalid_argument(name_ + " for " + std::to_string(n_) + " nodes needs " + gib(bytes) +
                                " of GL buffers; " + limit->name + " leaves " + gib(limit->bytes));
}

std::int64_t GlPipeline::count_option(const PipelineOptions& o, const std::string& name, std::int64_t most,
                                      const std::string& limit) const {
  const auto it = o.find(name);
  if (it == o.end()) return most;
  const auto v = option_count(it->second, most);
  if (!v)
    throw std::invalid_argument(name_ + ": option " + name + " '" + it->second + "' is not a count from 1 to " +
                                std::to_string(most) + " (" + limit + "; plain digits, no leading zero)");
  return *v;
}

void GlPipeline::plan_windows(const PipelineOptions& o) {
  GLint64 block = 0;
  GLint align = 1;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
  glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &align);
  max_block_nodes_ = block / 16;
  const std::int64_t window = count_option(o, "window", max_block_nodes_, "GL_MAX_SHADER_STORAGE_BLOCK_SIZE / 16");
  windows_ = node_windows(n_, spring_reach(m_), window, std::lcm<std::int64_t>(std::max(align, 1), 16) / 16);
}

void GlPipeline::plan_link_views(const PipelineOptions& o) {
  GLint align = 1;
  glGetIntegerv(GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT, &align);
  const std::int64_t step = std::lcm<std::int64_t>(std::max(align, 1), 16) / 16;  // texels between view starts
  link_view_ = count_option(o, "link_view", max_texels_, "GL_MAX_TEXTURE_BUFFER_SIZE") / step * step;
  const std::int64_t links = 2 * m_.spring_count(), views = (links + link_view_ - 1) / std::max<std::int64_t>(link_view_, 1);
  if (link_view_ < 1 || views > kLinkViews)
    throw std::invalid_argument(name_ + ": the adjacency's " + std::to_string(links) + " links (two per spring) need " +
                                std::to_string(views) + " texture-buffer views of " + std::to_string(link_view_) +
                                " texels; the shaders bind at most " + std::to_string(kLinkViews));
}

void GlPipeline::bind_nodes(GLuint index, const NodeBuffer& b, int first, int count) {
  glBindBufferRange(GL_SHADER_STORAGE_BUFFER, index, b.id, GLintptr(first) * 16, GLsizeiptr(count) * 16);
}

std::string CudaMemory::why_not() const {
  return make ? unavailable() : "this build has no CUDA-OpenGL interop";
}

GLuint GlBufferMemory::add(std::size_t bytes) {
  buffers_.push_back(make_buffer(bytes));
  return buffers_.back().id();
}

std::unique_ptr<NodeMemory> CudaMemory::make_default() const {
  if (why_not().empty()) return make();
  return std::make_unique<GlBufferMemory>();
}

void GlPipeline::choose_memory(const PipelineOptions& o, const CudaMemory& cuda) {
  read_options(o);
  const auto it = o.find("memory");
  if (it == o.end()) {
    memory_ = cuda.make_default();
    // The hybrids take no option memory: their interop mode places the states they share.
    if (!shared_) chosen_["memory"] = memory_->name();
  } else if (it->second == "cuda") {
    const std::string why = cuda.why_not();
    if (!why.empty()) throw std::invalid_argument(name_ + ": memory cuda is not available: " + why);
    memory_ = cuda.make();
  } else {
    memory_ = std::make_unique<GlBufferMemory>();
  }
}

void GlPipeline::make_buffers() {
  const std::size_t bytes = std::size_t(n_) * 16;
  // The states forces are evaluated at (and the accelerations) belong to the outside
  // force stage when there is one.
  auto node_buffer = [&](bool forces_read) {
    NodeBuffer b;
    b.id = shared_ && forces_read ? shared_(bytes, NodeRole::state) : memory_->add(bytes);
    if (n_ <= max_texels_) b.tex = make_texture_buffer(b.id, GL_RGBA32F);  // else no pass reads it
    return b;
  };
  for (int k = 0; k < 2; ++k) {
    x_[k] = node_buffer(true);
    v_[k] = node_buffer(true);
  }
  for (int k = 0; k < sched_.stage_states; ++k) {
    sx_[k] = node_buffer(true);
    sv_[k] = node_buffer(true);
    sa_[k] = node_buffer(false);
  }
  if (shared_) {
    forces_acc_.id = shared_(bytes, NodeRole::accelerations);
    if (n_ <= max_texels_) forces_acc_.tex = make_texture_buffer(forces_acc_.id, GL_RGBA32F);
  }
}

void GlPipeline::set_drag(const DragHandle& d) {
  validate(d, n_);
  const bool same = d.active() == p_.drag.active() && d.node == p_.drag.node && d.as_spring == p_.drag.as_spring &&
                    d.stiffness == p_.drag.stiffness;
  p_.drag = d;
  if (!same) upload_params();  // the targets are uniforms set at each pass
}

void GlPipeline::upload_params() {
  SimBlock u{};
  u.params = step_params<float>(m_, p_);
  const auto stencil = stencil_entries<float>(m_);
  std::copy(stencil.begin(), stencil.end(), u.stencil);
  params_ubo_ = make_buffer(sizeof u, &u);
}

void GlPipeline::upload_adjacency() {
  // One RGBA32F texel per link: the other node's index (as float bits), rest length, k, kd.
  std::vector<float> links(4 * std::max<std::size_t>(m_.adj_node.size(), 1));  // no empty texture buffers
  for (std::size_t e = 0; e < m_.adj_node.size(); ++e) {
    const int sp = m_.adj_spring[e];
    std::memcpy(&links[4 * e], &m_.adj_node[e], 4);
    links[4 * e + 1] = m_.rest_length[sp];
    links[4 * e + 2] = m_.spring_k(sp);
    links[4 * e + 3] = m_.spring_kd(sp);
  }
  adj_offset_ = make_buffer(m_.adj_offset.size() * 4, m_.adj_offset.data());
  links_ = make_buffer(links.size() * 4, links.data());
  adj_offset_tex_ = make_texture_buffer(adj_offset_.id(), GL_R32I);
  const std::int64_t texels = std::int64_t(links.size() / 4);
  for (std::int64_t first = 0; first < texels; first += link_view_)
    link_views_.push_back(make_texture_buffer(links_.id(), GL_RGBA32F, first * 16, std::min(link_view_, texels - first) * 16));
}

// One GPU pass per force pass of the schedule, with the update that follows it.
void GlPipeline::plan() {
  const Schedule& s = sched_;
  if (s.rule == UpdateRule::backward_euler)
    throw std::invalid_argument(name_ + ": " + std::string(info(s.integrator).name) + " is not available on " + name_);
  for (std::size_t k = 0; k + 1 < s.passes.size(); k += 2) {
    const Pass &f = s.passes[k], &next = s.passes[k + 1];
    if (f.op != Pass::Op::force || f.src != f.acc || f.src != int(passes_.size()))
      throw std::logic_error("schedule shape not supported on the GL pipelines");
    GpuPass g{};
    g.stage = f.src;
    g.kind = s.single_pass() ? PassKind::one : next.dst == Pass::kResult ? PassKind::result : PassKind::stage;
    g.weights = {float(s.weight()), 0.f, 0.f, 0.f};
    if (next.op == Pass::Op::combine)
      for (std::size_t j = 0; j < next.weights.size(); ++j) g.weights[j] = float(next.weights[j]);
    passes_.push_back(std::move(g));
  }
}

void GlPipeline::init() {
  static const char* kind_define[] = {"PASS_ONE", "PASS_STAGE", "PASS_RESULT"};
  const std::string common = "#define RULE " + std::to_string(int(rule_)) + "\n" +
                             (m_.grid() ? "#define TOPOLOGY_GRID 1\n" + stencil_defines(m_.volume())
                                        : "#define TOPOLOGY_GENERAL 1\n") +
                             "#define LINK_VIEW " + std::to_string(std::max<std::int64_t>(link_view_, 1)) + "\n" +
                             (math_ == Math::exact ? "#define MATH_EXACT 1\n" : "#define MATH_FAST 1\n") +
                             (shared_ ? "#define EXTERNAL_FORCES 1\n" : "");
  for (GpuPass& g : passes_) {
    const int outputs = g.kind == PassKind::stage ? 3 : 2;
    g.prog = make_program(outputs, std::string("#define PASS ") + kind_define[int(g.kind)] + "\n#define STAGE " +
                                       std::to_string(g.stage) + "\n" + common);
    const GLuint id = g.prog.id();
    g.drag_force_target = uniform(id, "u_drag_force_target");
    g.drag_next = uniform(id, "u_drag_next");
    g.half_step = uniform(id, "u_half_step");
    glProgramUniform1fv(id, uniform(id, "u_weights"), kMaxStages, g.weights.data());
  }
  reduce_ = gl::make_program({{GL_COMPUTE_SHADER, "reduce.comp"}});
  reduce_n_ = uniform(reduce_.id(), "u_n");
  reduce_word_ = uniform(reduce_.id(), "u_word");
  copy_ = gl::make_program({{GL_COMPUTE_SHADER, "copy.comp"}});
  copy_n_ = uniform(copy_.id(), "u_n");
  check(name_ + " setup");
  set_state(rest_state(m_));
}

void GlPipeline::set_state(const State& s) {
  const std::size_t n = std::size_t(n_);
  if (s.x.size() != n || s.v.size() != n) throw std::invalid_argument("state size does not match the model");
  context();
  // A chunk at a time through one staging buffer, then a shader copy (see shaders/copy.comp:
  // node buffers may be memory imported from CUDA).
  const int chunk = int(std::min<std::int64_t>(kTransferChunkNodes, max_block_nodes_));
  std::vector<float> data(4 * std::size_t(std::min(chunk, n_)));
  const Buffer staging = make_buffer(data.size() * 4);
  auto upload = [&](const NodeBuffer& b, const std::vector<Vec3f>& src, bool inv_mass) {
    glUseProgram(copy_.id());
    for (int base = 0; base < n_; base += chunk) {
      const int count = std::min(chunk, n_ - base);
      for (int i = 0; i < count; ++i) {
        const Vec3f& p = src[std::size_t(base + i)];
        data[4 * std::size_t(i)] = p.x;
        data[4 * std::size_t(i) + 1] = p.y;
        data[4 * std::size_t(i) + 2] = p.z;
        data[4 * std::size_t(i) + 3] = inv_mass ? m_.inv_mass[std::size_t(base + i)] : 0.f;
      }
      glNamedBufferSubData(staging.id(), 0, GLsizeiptr(count) * 16, data.data());
      glUniform1i(copy_n_, count);
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, staging.id(), 0, GLsizeiptr(count) * 16);
      bind_nodes(1, b, base, count);
      glDispatchCompute(GLuint(std::min(65535, (count + 255) / 256)), 1, 1);
    }
    glUseProgram(0);
  };
  upload(x_[cur_], s.x, true);
  upload(v_[cur_], s.v, false);
  half_step_ = s.half_step;
  const std::uint32_t zero = 0;
  glClearNamedBufferData(result_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glMemoryBarrier(GL_ALL_BARRIER_BITS);
  t_ = s.t;
  stepped_ = false;
  back_ = Back::none;
  if (read_done_) glDeleteSync(std::exchange(read_done_, nullptr));  // a read of the state replaced
  read_queued_ = false;
  next_pass_ = 0;
  on_set_state();
  check(name_ + " set_state");
}

State GlPipeline::state() {
  context();
  const std::size_t n = std::size_t(n_);
  const int chunk = std::min(kTransferChunkNodes, n_);
  std::vector<float> data(4 * std::size_t(chunk));
  // Each chunk is copied into a staging buffer on the GPU and read from there: a driver may
  // keep a host copy of whatever buffer is read back, which is then chunk-sized.
  const Buffer staging = make_buffer(std::size_t(chunk) * 16);
  auto download = [&](const NodeBuffer& b, std::vector<Vec3f>& out) {
    out.resize(n);
    for (int base = 0; base < n_; base += chunk) {
      const int count = std::min(chunk, n_ - base);
      glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
      glCopyNamedBufferSubData(b.id, staging.id(), GLintptr(base) * 16, 0, GLsizeiptr(count) * 16);
      read_buffer(staging.id(), 0, std::size_t(count) * 16, data.data());
      for (int i = 0; i < count; ++i)
        out[std::size_t(base + i)] = {data[4 * std::size_t(i)], data[4 * std::size_t(i) + 1], data[4 * std::size_t(i) + 2]};
    }
  };
  State s;
  s.t = t_;
  download(x_[cur_], s.x);
  download(v_[cur_], s.v);
  s.half_step = half_step_;
  check(name_ + " state read-back");
  return s;
}

void GlPipeline::bind_textures(int stage) const {
  // Units 2-4: velocities of stage states 1..3; 5-7: accelerations at stages 0..2 (sim.glsl),
  // bound only where this pass reads them; 8: the adjacency offsets of general models, 9 and 11-13
  // their link views (10: the hybrids' accelerations).
  for (int k = 0; k < kMaxStages - 1; ++k) {
    glActiveTexture(GL_TEXTURE2 + k);
    glBindTexture(GL_TEXTURE_BUFFER, k + 1 < stage ? sv_[k].tex.id() : 0);
    glActiveTexture(GL_TEXTURE5 + k);
    glBindTexture(GL_TEXTURE_BUFFER, k < stage ? sa_[k].tex.id() : 0);
  }
  if (adj_offset_tex_.id()) {
    glActiveTexture(GL_TEXTURE8);
    glBindTexture(GL_TEXTURE_BUFFER, adj_offset_tex_.id());
    for (std::size_t k = 0; k < link_views_.size(); ++k) {
      glActiveTexture(k == 0 ? GL_TEXTURE9 : GLenum(GL_TEXTURE10 + k));
      glBindTexture(GL_TEXTURE_BUFFER, link_views_[k].id());
    }
  }
  glActiveTexture(GL_TEXTURE0);
}

void GlPipeline::step() {
  // With an outside force stage, its pipeline times the passes (GL timer spans may not nest).
  Profiler* p = shared_ ? nullptr : sampling(prof_);
  if (p) {
    if (spans_.pending() >= 512) spans_.collect(prof_);
    spans_.begin(*p, span::force_update);
  }
  run_passes(sched_, t_, p_.dt, *this, *this);
  if (p) spans_.end();
  finish_step();
}

void GlPipeline::forces(int src, int acc, double t) {
  if (shared_ || src != acc || std::size_t(src) != next_pass_)
    throw std::logic_error(name_ + ": force pass out of the order of its GPU passes");
  force_t_ = t;
}

void GlPipeline::update(const Pass& pass) {
  if (next_pass_ >= passes_.size() || pass.op == Pass::Op::force)
    throw std::logic_error(name_ + ": update pass out of the order of its GPU passes");
  const GpuPass& g = passes_[next_pass_++];
  const int c = cur_, d = 1 - cur_;
  const GLuint id = g.prog.id();
  const Vec3f target = p_.drag.active() ? p_.drag.target(force_t_) : Vec3f{};
  const Vec3f next = p_.drag.active() ? p_.drag.target(t_ + p_.dt) : Vec3f{};
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, params_ubo_.id());
  glProgramUniform3f(id, g.drag_force_target, target.x, target.y, target.z);
  glProgramUniform3f(id, g.drag_next, next.x, next.y, next.z);
  glProgramUniform1i(id, g.half_step, half_step_ ? 1 : 0);
  bind_textures(g.stage);
  PassIO io{};
  io.set = c;
  io.s0_x = &x_[c];
  io.s0_v = &v_[c];
  io.src_x = g.stage == 0 ? &x_[c] : &sx_[g.stage - 1];
  io.src_v = g.stage == 0 ? &v_[c] : &sv_[g.stage - 1];
  if (g.kind == PassKind::stage) {
    io.out = {&sa_[g.stage], &sx_[g.stage], &sv_[g.stage]};
    io.outputs = 3;
  } else {
    io.out = {&x_[d], &v_[d], nullptr};
    io.outputs = 2;
    io.result_max = result_.id();
    io.result_word = d;
    io.posted = readback_.id();
    io.launch = std::uint32_t(++launches_);
  }
  if (shared_) io.forces_acc = &forces_acc_;
  run_pass(id, io);
  if (context().debug) check_debug(name_ + " pass " + std::to_string(&g - passes_.data()));  // no string otherwise
}

void GlPipeline::finish_step() {
  if (next_pass_ != passes_.size()) throw std::logic_error(name_ + ": step finished before its last pass");
  check(name_ + " step");
  next_pass_ = 0;
  cur_ = 1 - cur_;
  back_t_ = t_;
  back_half_step_ = half_step_;
  back_ = Back::possible;
  t_ += p_.dt;
  stepped_ = true;
  if (rule_ == UpdateRule::verlet) half_step_ = true;
}

std::array<GLuint, 2> GlPipeline::slot_buffers(int slot) const {
  return slot == 0 ? std::array{x_[cur_].id, v_[cur_].id} : std::array{sx_[slot - 1].id, sv_[slot - 1].id};
}

void GlPipeline::set_profiler(Profiler* p) {
  if (shared_) return;  // the outside force stage's pipeline times the passes
  spans_.collect(prof_);
  prof_ = p;
}

unsigned GlPipeline::gl_position_buffer() {
  context();
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  return x_[cur_].id;
}

}  // namespace deformlab::gl
