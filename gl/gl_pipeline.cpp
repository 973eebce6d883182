#include "gl_pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace deformlab::gl {
namespace {

constexpr int kMaxSpheres = 8;
constexpr int kMaxStencil = 16;

// std140 mirror of SimParams in shaders/sim.glsl.
struct SimParams {
  std::int32_t dims[4];
  float gravity_dt[4];
  float wind_damping[4];
  float stiffness[4];
  float spring_damping[4];
  float dt_terms[4];
  std::int32_t flags[4];
  std::int32_t stencil_size[4];
  float spheres[kMaxSpheres][4];
  std::int32_t stencil[kMaxStencil][4];
  float stencil_rest[kMaxStencil][4];
};

constexpr int kDragNone = 0, kDragHard = 1, kDragSpring = 2;

}  // namespace

std::vector<StencilOffset> grid_stencil(const Model& m) {
  if (m.topology == Topology::general || m.nx < 1 || m.ny < 1 || m.nz < 1) return {};
  const int nx = m.nx, ny = m.ny, nz = m.nz;
  // The builder derives rest lengths from float rest positions, so one offset's springs
  // differ by the rounding of those positions; within that they share the first one's.
  float largest = 0.f;
  for (const auto& p : m.rest_position) largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  const float rounding = 4.f * largest * std::numeric_limits<float>::epsilon();
  auto coord = [&](int v) { return std::array<int, 3>{v % nx, (v / nx) % ny, v / (nx * ny)}; };
  std::vector<StencilOffset> st;
  std::vector<std::int64_t> count;
  std::vector<std::uint32_t> seen(std::size_t(m.node_count()), 0);  // per node: offsets already met
  for (int e = 0; e < m.spring_count(); ++e) {
    const auto a = coord(m.spring_i[e]), b = coord(m.spring_j[e]);
    const int di = b[0] - a[0], dj = b[1] - a[1], dk = b[2] - a[2];
    const int kind = int(m.kind[e]);
    int s = 0;
    while (s < int(st.size()) && !(st[s].di == di && st[s].dj == dj && st[s].dk == dk)) ++s;
    if (s == int(st.size())) {
      if (s == kMaxStencil) return {};
      st.push_back({di, dj, dk, kind, m.rest_length[e]});
      count.push_back(0);
    }
    if (st[s].kind != kind || std::abs(st[s].rest - m.rest_length[e]) > rounding) return {};
    std::uint32_t& bit = seen[std::size_t(m.spring_i[e])];
    if (bit & (1u << s)) return {};  // the same pair twice
    bit |= 1u << s;
    ++count[s];
  }
  // Every in-bounds pair of every offset must be a spring (the shader visits them all).
  for (std::size_t s = 0; s < st.size(); ++s) {
    const std::int64_t pairs = std::int64_t(std::max(0, nx - std::abs(st[s].di))) *
                               std::max(0, ny - std::abs(st[s].dj)) * std::max(0, nz - std::abs(st[s].dk));
    if (pairs != count[s]) return {};
  }
  return st;
}

GlPipeline::GlPipeline(const PipelineSetup& s, std::string name, ExternalForces* forces)
    : name_(std::move(name)), forces_(forces), m_(s.model), p_(s.params), integrator_(s.integrator) {
  context();
  n_ = m_.node_count();
  if (n_ < 1) throw std::invalid_argument(name_ + ": the model has no nodes");
  if (int(p_.spheres.size()) > kMaxSpheres)
    throw std::invalid_argument(name_ + " supports at most " + std::to_string(kMaxSpheres) + " spheres");
  stencil_ = grid_stencil(m_);
  // Node states are texture buffers of one texel per node; a model without a grid stencil
  // also has its adjacency in texture buffers (two entries per spring).
  GLint max_texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
  const std::int64_t adjacency = stencil_.empty() ? std::int64_t(2) * m_.spring_count() : 0;
  if (adjacency > max_texels || n_ + 1 > max_texels)
    throw std::invalid_argument(name_ + ": the model needs texture buffers larger than this driver's " +
                                std::to_string(max_texels) + " texels");

  const std::size_t bytes = std::size_t(n_) * 16;
  // The states forces are evaluated at (and the accelerations) belong to the external
  // force stage when there is one.
  auto node_buffer = [&](bool forces_read) {
    NodeBuffer b;
    if (forces_ && forces_read)
      b.external = forces_->node_buffer(bytes, NodeRole::state);
    else
      b.buf = make_buffer(bytes);
    b.tex = make_texture_buffer(b.id(), GL_RGBA32F);
    return b;
  };
  const Schedule sched = make_schedule(integrator_);
  for (int k = 0; k < 2; ++k) {
    x_[k] = node_buffer(true);
    v_[k] = node_buffer(true);
    if (integrator_ == Integrator::verlet) xp_[k] = node_buffer(false);
    if (!sched.single_pass()) {
      sx_[k] = node_buffer(true);
      sv_[k] = node_buffer(true);
      ax_[k] = node_buffer(false);
      av_[k] = node_buffer(false);
    }
  }
  if (forces_) {
    forces_acc_.external = forces_->node_buffer(bytes, NodeRole::accelerations);
    forces_acc_.tex = make_texture_buffer(forces_acc_.id(), GL_RGBA32F);
  }

  SimParams u{};
  const float dt = p_.dt;
  const int sets[4] = {m_.nx, m_.ny, m_.nz, n_};
  std::memcpy(u.dims, sets, sizeof sets);
  const float g[4] = {p_.gravity.x, p_.gravity.y, p_.gravity.z, dt};
  std::memcpy(u.gravity_dt, g, sizeof g);
  const float w[4] = {p_.wind.x, p_.wind.y, p_.wind.z, p_.damping};
  std::memcpy(u.wind_damping, w, sizeof w);
  for (int k = 0; k < kSpringKinds; ++k) {
    u.stiffness[k] = m_.stiffness[k];
    u.spring_damping[k] = m_.damping[k];
  }
  u.stiffness[3] = p_.drag.stiffness;
  // The same float expressions as the CPU pipeline: dt * dt, 0.5 * dt * dt, 1 / dt.
  u.dt_terms[0] = dt * dt;
  u.dt_terms[1] = 0.5f * dt * dt;
  u.dt_terms[2] = 1.f / dt;
  u.dt_terms[3] = p_.ground.value_or(0.f);
  u.flags[0] = p_.drag.active() ? p_.drag.node : -1;
  u.flags[1] = !p_.drag.active() ? kDragNone : (p_.drag.as_spring ? kDragSpring : kDragHard);
  u.flags[2] = p_.ground ? 1 : 0;
  u.flags[3] = int(p_.spheres.size());
  for (std::size_t k = 0; k < p_.spheres.size(); ++k) {
    const float sp[4] = {p_.spheres[k].center.x, p_.spheres[k].center.y, p_.spheres[k].center.z,
                         p_.spheres[k].radius};
    std::memcpy(u.spheres[k], sp, sizeof sp);
  }
  u.stencil_size[0] = int(stencil_.size());
  for (std::size_t s = 0; s < stencil_.size(); ++s) {
    const int o[4] = {stencil_[s].di, stencil_[s].dj, stencil_[s].dk, stencil_[s].kind};
    std::memcpy(u.stencil[s], o, sizeof o);
    u.stencil_rest[s][0] = stencil_[s].rest;
  }
  params_ubo_ = make_buffer(sizeof u, &u);

  if (stencil_.empty()) {
    std::vector<std::int32_t> entry(2 * m_.adj_node.size());
    std::vector<float> rest(m_.adj_node.size());
    for (std::size_t e = 0; e < m_.adj_node.size(); ++e) {
      const int sp = m_.adj_spring[e];
      entry[2 * e] = m_.adj_node[e];
      entry[2 * e + 1] = int(m_.kind[sp]);
      rest[e] = m_.rest_length[sp];
    }
    // Texture buffers of zero size are not allowed: keep at least one texel.
    entry.resize(std::max<std::size_t>(entry.size(), 2));
    rest.resize(std::max<std::size_t>(rest.size(), 1));
    adj_offset_ = make_buffer(m_.adj_offset.size() * 4, m_.adj_offset.data());
    adj_entry_ = make_buffer(entry.size() * 4, entry.data());
    adj_rest_ = make_buffer(rest.size() * 4, rest.data());
    adj_offset_tex_ = make_texture_buffer(adj_offset_.id(), GL_R32I);
    adj_entry_tex_ = make_texture_buffer(adj_entry_.id(), GL_RG32I);
    adj_rest_tex_ = make_texture_buffer(adj_rest_.id(), GL_R32F);
  }
  const std::uint32_t zero = 0;
  result_ = make_buffer(4, &zero);
  plan(sched);
}

GlPipeline::~GlPipeline() = default;

void GlPipeline::plan(const Schedule& s) {
  if (s.passes.empty() || s.passes.back().op == Pass::Op::solve)
    throw std::invalid_argument(name_ + ": " + std::string(info(s.integrator).name) + " is not available on " + name_);
  std::vector<double> weights;
  for (const Pass& p : s.passes)
    if (p.op == Pass::Op::combine) weights = p.weights;
  int last_slot = -1;  // stage slot written by the previous GPU pass
  for (std::size_t k = 0; k < s.passes.size(); ++k) {
    const Pass& f = s.passes[k];
    if (f.op != Pass::Op::force) continue;
    if (k + 1 >= s.passes.size()) throw std::logic_error("a force pass ends the schedule");
    const Pass& next = s.passes[k + 1];
    GpuPass g{};
    g.time_fraction = f.time_fraction;
    g.first = passes_.empty();
    g.src_slot = f.src == 0 ? -1 : last_slot;
    if (f.src != 0 && (last_slot < 0 || f.src != f.acc))
      throw std::logic_error("schedule shape not supported on the GL pipelines");
    g.weight = f.acc < int(weights.size()) ? float(weights[f.acc]) : 0.f;
    switch (next.op) {
      case Pass::Op::fused:
        g.kind = integrator_ == Integrator::explicit_euler  ? PassKind::explicit_euler
                 : integrator_ == Integrator::verlet        ? PassKind::verlet
                                                            : PassKind::semi_implicit_euler;
        break;
      case Pass::Op::stage:
        if (next.src != f.acc || next.dst != f.acc + 1)
          throw std::logic_error("schedule shape not supported on the GL pipelines");
        g.kind = PassKind::stage;
        g.h = float(next.coef * double(p_.dt));
        g.out_slot = last_slot = (last_slot + 1) % 2;
        break;
      case Pass::Op::combine:
        g.kind = PassKind::combine;
        break;
      default: throw std::logic_error("schedule shape not supported on the GL pipelines");
    }
    passes_.push_back(g);
  }
}

void GlPipeline::init() {
  static const char* kind_define[] = {"PASS_EXPLICIT_EULER", "PASS_SEMI_IMPLICIT_EULER", "PASS_VERLET",
                                      "PASS_STAGE", "PASS_COMBINE"};
  const std::string topo = std::string(stencil_.empty() ? "#define TOPOLOGY_GENERAL 1\n" : "#define TOPOLOGY_GRID 1\n") +
                           (forces_ ? "#define EXTERNAL_FORCES 1\n" : "");
  for (const GpuPass& g : passes_) {
    PassProgram& pp = programs_[int(g.kind)];
    if (pp.prog) continue;
    pp.prog = make_program(g.kind, std::string("#define PASS ") + kind_define[int(g.kind)] + "\n" + topo);
    const GLuint id = pp.prog.id();
    pp.drag_force_target = uniform(id, "u_drag_force_target");
    pp.drag_next = uniform(id, "u_drag_next");
    pp.stage_h = uniform(id, "u_stage_h");
    pp.weight = uniform(id, "u_weight");
    pp.first = uniform(id, "u_first");
    pp.has_prev = uniform(id, "u_has_prev");
  }
  reduce_ = gl::make_program({{GL_COMPUTE_SHADER, "reduce.comp"}});
  reduce_n_ = uniform(reduce_.id(), "u_n");
  copy_ = gl::make_program({{GL_COMPUTE_SHADER, "copy.comp"}});
  copy_n_ = uniform(copy_.id(), "u_n");
  check(name_ + " setup");
  set_state(rest_state(m_));
}

void GlPipeline::bind_model_textures() const {
  if (!stencil_.empty()) return;
  const GLuint tex[3] = {adj_offset_tex_.id(), adj_entry_tex_.id(), adj_rest_tex_.id()};
  for (int k = 0; k < 3; ++k) {
    glActiveTexture(GL_TEXTURE4 + k);
    glBindTexture(GL_TEXTURE_BUFFER, tex[k]);
  }
  glActiveTexture(GL_TEXTURE0);
}

void GlPipeline::set_state(const State& s) {
  const std::size_t n = std::size_t(n_);
  if (s.x.size() != n || s.v.size() != n || (!s.x_prev.empty() && s.x_prev.size() != n))
    throw std::invalid_argument("state size does not match the model");
  context();
  auto upload = [&](const NodeBuffer& b, const std::vector<Vec3f>& src, bool inv_mass) {
    std::vector<float> data(4 * n);
    for (std::size_t i = 0; i < n; ++i) {
      data[4 * i] = src[i].x;
      data[4 * i + 1] = src[i].y;
      data[4 * i + 2] = src[i].z;
      data[4 * i + 3] = inv_mass ? m_.inv_mass[i] : 0.f;
    }
    // Through a shader copy (see shaders/copy.comp): buffers of the external force stage
    // may be memory imported from another API, with immutable storage.
    const Buffer staging = make_buffer(data.size() * 4, data.data());
    glUseProgram(copy_.id());
    glUniform1i(copy_n_, n_);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, staging.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, b.id());
    glDispatchCompute(GLuint(std::min(65535, (n_ + 255) / 256)), 1, 1);
    glUseProgram(0);
  };
  upload(x_[cur_], s.x, true);
  upload(v_[cur_], s.v, false);
  has_prev_ = !s.x_prev.empty() && integrator_ == Integrator::verlet;
  if (has_prev_) upload(xp_[cur_], s.x_prev, true);
  glMemoryBarrier(GL_ALL_BARRIER_BITS);
  t_ = s.t;
  stepped_ = false;
  on_set_state();
  check(name_ + " set_state");
}

State GlPipeline::state() {
  context();
  const std::size_t n = std::size_t(n_);
  std::vector<float> data(4 * n);
  auto download = [&](const NodeBuffer& b, std::vector<Vec3f>& out) {
    read_buffer(b.id(), data.size() * 4, data.data());
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) out[i] = {data[4 * i], data[4 * i + 1], data[4 * i + 2]};
  };
  State s;
  s.t = t_;
  download(x_[cur_], s.x);
  download(v_[cur_], s.v);
  if (has_prev_) download(xp_[cur_], s.x_prev);
  check(name_ + " state read-back");
  return s;
}

void GlPipeline::step() {
  const bool debug = context().debug;
  const int c = cur_, d = 1 - cur_;
  const double dt = p_.dt;
  const Vec3f next = p_.drag.active() ? p_.drag.target(t_ + dt) : Vec3f{};
  // With an external force stage, it times the passes (GL timer spans may not nest).
  const bool timed = prof_ && !forces_;
  if (timed) {
    if (spans_.pending() >= 512) spans_.collect(prof_);
    spans_.begin(*prof_, span::force_update);
  }
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, params_ubo_.id());
  bind_model_textures();
  for (const GpuPass& g : passes_) {
    const PassProgram& pp = programs_[int(g.kind)];
    const GLuint id = pp.prog.id();
    const Vec3f target = p_.drag.active() ? p_.drag.target(t_ + g.time_fraction * dt) : Vec3f{};
    glProgramUniform3f(id, pp.drag_force_target, target.x, target.y, target.z);
    glProgramUniform3f(id, pp.drag_next, next.x, next.y, next.z);
    glProgramUniform1f(id, pp.stage_h, g.h);
    glProgramUniform1f(id, pp.weight, g.weight);
    glProgramUniform1i(id, pp.first, g.first ? 1 : 0);
    glProgramUniform1i(id, pp.has_prev, has_prev_ ? 1 : 0);
    PassIO io{};
    io.set = c;
    io.s0_x = &x_[c];
    io.s0_v = &v_[c];
    io.s0_p = &xp_[c];
    const bool at_s0 = g.src_slot < 0;
    io.src_x = at_s0 ? &x_[c] : &sx_[g.src_slot];
    io.src_v = at_s0 ? &v_[c] : &sv_[g.src_slot];
    // Running sums of the previous pass (not read on the first pass; any buffer will do).
    const int acc_slot = at_s0 ? 0 : g.src_slot;
    io.acc_x = g.kind == PassKind::stage || g.kind == PassKind::combine ? &ax_[acc_slot] : &x_[c];
    io.acc_v = g.kind == PassKind::stage || g.kind == PassKind::combine ? &av_[acc_slot] : &v_[c];
    if (g.kind == PassKind::stage) {
      io.out = {&sx_[g.out_slot], &sv_[g.out_slot], &ax_[g.out_slot], &av_[g.out_slot]};
      io.outputs = 4;
    } else {
      io.out = {&x_[d], &v_[d], &xp_[d], nullptr};
      io.outputs = g.kind == PassKind::verlet ? 3 : 2;
    }
    if (forces_) {
      forces_->forces(io.src_x->id(), io.src_v->id(), forces_acc_.id(), t_ + g.time_fraction * dt);
      io.forces_acc = &forces_acc_;
    }
    run_pass(id, io);
    if (forces_) forces_->update_issued();
    if (debug) check_debug(name_ + " pass " + std::to_string(&g - passes_.data()));  // no string otherwise
  }
  if (timed) spans_.end();
  check(name_ + " step");
  cur_ = d;
  t_ += dt;
  stepped_ = true;
  if (integrator_ == Integrator::verlet) has_prev_ = true;
}

void GlPipeline::set_profiler(Profiler* p) {
  if (forces_) return;  // the external force stage times the passes
  spans_.collect(prof_);
  prof_ = p;
}

double GlPipeline::max_displacement() {
  if (!stepped_) return 0.0;
  context();
  const std::uint32_t zero = 0;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, result_.id());
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, 4, &zero);
  glUseProgram(reduce_.id());
  glUniform1i(reduce_n_, n_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, v_[cur_].id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, result_.id());
  glDispatchCompute(GLuint(std::min(1024, (n_ + 255) / 256)), 1, 1);
  std::uint32_t bits = 0;
  read_buffer(result_.id(), 4, &bits);
  glUseProgram(0);
  check(name_ + " displacement reduction");
  float d;
  std::memcpy(&d, &bits, 4);
  return std::isfinite(d) ? double(d) : std::numeric_limits<double>::quiet_NaN();
}

GLuint GlPipeline::position_buffer() {
  context();
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  return x_[cur_].id();
}

}  // namespace deformlab::gl
