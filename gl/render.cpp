#include "render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include "gl_pipeline.hpp"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace deformlab::gl {
namespace {

using Mat4 = std::array<float, 16>;  // column-major

Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr)
      for (int k = 0; k < 4; ++k) r[c * 4 + rr] += a[k * 4 + rr] * b[c * 4 + k];
  return r;
}

Vec3f normalized(Vec3f v) { return v * (1.f / norm(v)); }

Mat4 look_at(Vec3f eye, Vec3f at, Vec3f up) {
  const Vec3f f = normalized(at - eye), s = normalized(cross(f, up)), u = cross(s, f);
  return {s.x, u.x, -f.x, 0, s.y, u.y, -f.y, 0, s.z, u.z, -f.z, 0, -dot(s, eye), -dot(u, eye), dot(f, eye), 1};
}

Mat4 perspective(float fovy, float aspect, float znear, float zfar) {
  const float t = 1.f / std::tan(fovy / 2);
  return {t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (zfar + znear) / (znear - zfar), -1,
          0, 0, 2 * zfar * znear / (znear - zfar), 0};
}

// The framebuffer to restore after drawing (the context keeps a 1x1 one bound: see context.cpp).
GLint bound_framebuffer(GLenum which = GL_DRAW_FRAMEBUFFER_BINDING) {
  GLint id = 0;
  glGetIntegerv(which, &id);
  return id;
}

}  // namespace

struct Renderer::Impl {
  const Model& m;
  RenderOptions o;
  bool surface;  // a cloth grid's surface, made from the grid
  bool mesh;     // a mesh's triangles (Model::triangle), drawn by index
  Buffer elements;
  Framebuffer fbo;
  Renderbuffer color, depth;
  Program prog;
  VertexArray vao;
  Buffer upload;
  Texture draw_tex;
  // What one draw call covers: the texture range over the positions it reads (from node
  // tex_first, tex_count nodes) and its points or quad rows.
  struct Band {
    std::int64_t tex_first, tex_count;
    int first, count;  // points: nodes; surface: quad rows of the sampled grid
  };
  std::vector<Band> bands;
  int stride = 1;  // surface: every stride-th row and column (a frame shows no more)
  Mat4 view_proj{};
  Vec3f eye;
  Timer timer;

  Impl(const Model& model, RenderOptions opt) : m(model), o(opt) {
    if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384)
      throw std::invalid_argument("frame size must be between 1 and 16384 pixels");
    const bool surface_wanted = o.mode == RenderOptions::Mode::surface ||
                                (o.mode == RenderOptions::Mode::automatic &&
                                 (m.topology == Topology::cloth_grid || !m.triangle.empty()));
    mesh = surface_wanted && !m.triangle.empty();
    surface = surface_wanted && !mesh;
    if (surface && (m.topology != Topology::cloth_grid || m.nx < 2 || m.ny < 2))
      throw std::invalid_argument("surface rendering needs a cloth grid of at least 2x2 nodes or a mesh's triangles");
    GLuint id = 0;
    glGenRenderbuffers(1, &id);
    color = Renderbuffer(id);
    glBindRenderbuffer(GL_RENDERBUFFER, id);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, o.width, o.height);
    glGenRenderbuffers(1, &id);
    depth = Renderbuffer(id);
    glBindRenderbuffer(GL_RENDERBUFFER, id);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, o.width, o.height);
    glGenFramebuffers(1, &id);
    fbo = Framebuffer(id);
    const GLint previous = bound_framebuffer();
    glBindFramebuffer(GL_FRAMEBUFFER, id);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color.id());
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth.id());
    const bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(previous));
    if (!complete) throw std::runtime_error("the render framebuffer is incomplete");
    prog = make_program({{GL_VERTEX_SHADER, "render.vert"}, {GL_FRAGMENT_SHADER, "render.frag"}});
    glGenVertexArrays(1, &id);
    vao = VertexArray(id);
    GLint texels = 0, align = 16;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &texels);
    glGetIntegerv(GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT, &align);
    plan_bands(o.band_texels > 0 ? std::min<std::int64_t>(o.band_texels, texels) : texels,
               std::lcm(std::max(align, 1), 16) / 16);
    if (mesh) {
      if (bands.size() > 1)
        throw std::invalid_argument("a mesh of " + std::to_string(m.node_count()) +
                                    " nodes is more than one texture buffer holds (" + std::to_string(texels) +
                                    " texels): draw it as points");
      elements = make_buffer(m.triangle.size() * sizeof(std::int32_t), m.triangle.data());
    }
    // Camera: in front of and above the rest shape and the space below it where a pinned
    // model hangs, looking at the centre of both.
    Vec3f lo = m.rest_position[0], hi = lo;
    for (const auto& p : m.rest_position)
      for (int c = 0; c < 3; ++c) { lo[c] = std::min(lo[c], p[c]); hi[c] = std::max(hi[c], p[c]); }
    lo.y -= 0.6f * std::max({hi.x - lo.x, hi.z - lo.z});
    if (o.ground) {  // dropped onto the ground: down to it, and half the model's size to each side
      const Vec3f half = (hi - lo) * 0.5f;
      lo = lo - Vec3f{half.x, 0.f, half.z};
      hi = hi + Vec3f{half.x, 0.f, half.z};
      lo.y = std::min(lo.y, *o.ground - 0.05f * (hi.y - lo.y));
    }
    const Vec3f centre = (lo + hi) * 0.5f;
    const float radius = std::max(0.5f * norm(hi - lo), 1e-3f);
    eye = centre + Vec3f{0.f, 0.9f, 2.2f} * radius;
    const float dist = norm(eye - centre);
    view_proj = mul(perspective(0.8f, float(o.width) / float(o.height), dist * 0.05f, dist * 4.f),
                    look_at(eye, centre, {0.f, 1.f, 0.f}));
    check("renderer setup");
  }

  // Splits the drawing into bands whose positions fit in one texture buffer view of at most
  // `texels` texels starting at a multiple of `align` nodes.
  void plan_bands(std::int64_t texels, std::int64_t align) {
    const std::int64_t n = m.node_count();
    if (!surface) {
      const std::int64_t per = std::min<std::int64_t>(n, (texels - align) / align * align);
      for (std::int64_t first = 0; first < n; first += per)
        bands.push_back({first, std::min(per, n - first), int(first), int(std::min(per, n - first))});
      return;
    }
    stride = std::max(1, int(std::max(m.nx, m.ny) / (2 * std::max(o.width, o.height))));
    const int rows = (m.ny - 2) / stride + 1;  // quad rows of the sampled grid
    // A band of r quad rows reads node rows from one stride above its first to one below its last.
    const std::int64_t fit = (texels - align) / m.nx / stride - 3;
    if (fit < 1) throw std::invalid_argument("cloth rows of " + std::to_string(m.nx) + " nodes are too long to draw");
    for (int first = 0; first < rows; first += int(fit)) {
      const int count = int(std::min<std::int64_t>(fit, rows - first));
      const std::int64_t row0 = std::max(0, (first - 1) * stride);
      const std::int64_t row1 = std::min<std::int64_t>(m.ny - 1, std::int64_t(first + count + 1) * stride);
      const std::int64_t tex_first = row0 * m.nx / align * align;
      bands.push_back({tex_first, (row1 + 1) * m.nx - tex_first, first, count});
    }
  }

  void draw_buffer(GLuint positions) {
    timer.begin();
    const GLint previous = bound_framebuffer();
    glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
    glViewport(0, 0, o.width, o.height);
    glClearColor(0.12f, 0.13f, 0.15f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glUseProgram(prog.id());
    glUniformMatrix4fv(uniform(prog.id(), "u_view_proj"), 1, GL_FALSE, view_proj.data());
    glUniform2i(uniform(prog.id(), "u_grid"), m.nx, m.ny);
    glUniform1i(uniform(prog.id(), "u_surface"), surface ? 1 : 0);
    glUniform1i(uniform(prog.id(), "u_mesh"), mesh ? 1 : 0);
    glUniform1f(uniform(prog.id(), "u_point_size"),
                std::clamp(float(o.width) / std::sqrt(float(m.node_count())) * 0.4f, 1.f, 8.f));
    glUniform3f(uniform(prog.id(), "u_eye"), eye.x, eye.y, eye.z);
    glUniform1i(uniform(prog.id(), "u_stride"), stride);
    if (!draw_tex) draw_tex = make_texture();
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_BUFFER, draw_tex.id());
    glBindVertexArray(vao.id());
    const int quads_per_row = (m.nx - 2) / stride + 1;
    for (const Band& b : bands) {
      glTexBufferRange(GL_TEXTURE_BUFFER, GL_RGBA32F, positions, GLintptr(b.tex_first * 16), GLsizeiptr(b.tex_count * 16));
      glUniform1i(uniform(prog.id(), "u_first"), b.first);
      glUniform1i(uniform(prog.id(), "u_tex_first"), int(b.tex_first));
      if (mesh) {
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, elements.id());
        glDrawElements(GL_TRIANGLES, GLsizei(m.triangle.size()), GL_UNSIGNED_INT, nullptr);
      } else if (surface) {
        glDrawArrays(GL_TRIANGLES, 0, GLsizei(6 * std::int64_t(quads_per_row) * b.count));
      } else {
        glDrawArrays(GL_POINTS, 0, b.count);
      }
    }
    glBindVertexArray(0);
    glUseProgram(0);
    glDisable(GL_DEPTH_TEST);
    timer.end();
    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(previous));
    check("rendering a frame");
  }

  static Texture make_texture() {
    GLuint id = 0;
    glGenTextures(1, &id);
    return Texture(id);
  }
};

Renderer::Renderer(const Model& m, RenderOptions o) {
  context();
  impl_ = std::make_unique<Impl>(m, o);
}

Renderer::~Renderer() = default;

void Renderer::draw(Pipeline& p) {
  context();
  if (auto* g = dynamic_cast<GlPipeline*>(&p))
    impl_->draw_buffer(g->position_buffer());
  else
    draw(p.state());
}

void Renderer::draw(const State& s) {
  context();
  Impl& r = *impl_;
  const std::size_t n = std::size_t(r.m.node_count());
  if (s.x.size() != n) throw std::invalid_argument("state size does not match the model");
  if (!r.upload) r.upload = make_buffer(n * 16);
  // A chunk at a time: no second host copy of the positions.
  std::vector<float> data(4 * std::min<std::size_t>(n, kTransferChunkNodes));
  for (std::size_t base = 0; base < n; base += kTransferChunkNodes) {
    const std::size_t count = std::min<std::size_t>(kTransferChunkNodes, n - base);
    for (std::size_t i = 0; i < count; ++i) {
      data[4 * i] = s.x[base + i].x;
      data[4 * i + 1] = s.x[base + i].y;
      data[4 * i + 2] = s.x[base + i].z;
      data[4 * i + 3] = r.m.inv_mass[base + i];
    }
    glNamedBufferSubData(r.upload.id(), GLintptr(base * 16), GLsizeiptr(count * 16), data.data());
  }
  r.draw_buffer(r.upload.id());
}

std::vector<std::uint8_t> Renderer::pixels() {
  context();
  const Impl& r = *impl_;
  std::vector<std::uint8_t> px(std::size_t(r.o.width) * r.o.height * 4);
  const GLint previous = bound_framebuffer(GL_READ_FRAMEBUFFER_BINDING);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, r.fbo.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, r.o.width, r.o.height, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, GLuint(previous));
  check("reading a frame back");
  // GL rows start at the bottom.
  const std::size_t row = std::size_t(r.o.width) * 4;
  for (int y = 0; y < r.o.height / 2; ++y)
    std::swap_ranges(px.begin() + long(y * row), px.begin() + long((y + 1) * row),
                     px.begin() + long((r.o.height - 1 - y) * row));
  return px;
}

void Renderer::write_png(const std::filesystem::path& file) {
  const auto px = pixels();
  if (!stbi_write_png(file.string().c_str(), impl_->o.width, impl_->o.height, 4, px.data(), impl_->o.width * 4))
    throw std::runtime_error("cannot write " + file.string());
}

std::vector<double> Renderer::take_draw_ms() { return impl_->timer.take(); }
std::string Renderer::timing_method() const { return impl_->timer.method(); }
int Renderer::width() const { return impl_->o.width; }
int Renderer::height() const { return impl_->o.height; }

FrameWriter::FrameWriter(const Model& m, std::filesystem::path dir, int every, RenderOptions o)
    : r_(m, o), dir_(std::move(dir)), every_(every) {
  if (every_ < 1) throw std::invalid_argument("--frames must be at least 1");
  std::filesystem::create_directories(dir_);
}

void FrameWriter::write(Pipeline& p, int step) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06d.png", step);
  r_.draw(p);
  r_.write_png(dir_ / name);
  const auto ms = r_.take_draw_ms();
  draw_ms_.insert(draw_ms_.end(), ms.begin(), ms.end());
  last_written_ = step;
  ++frames_;
}

void FrameWriter::after_step(Pipeline& p, int step) {
  if (step % every_ == 0) write(p, step);
}

void FrameWriter::finish(Pipeline& p, int last_step) {
  if (last_written_ != last_step) write(p, last_step);
  if (frames_ < 2 || std::system("command -v ffmpeg >/dev/null 2>&1") != 0) return;
  const std::string cmd = "ffmpeg -loglevel error -y -framerate 30 -pattern_type glob -i '" + dir_.string() +
                          "/frame_*.png' -c:v libx264 -pix_fmt yuv420p '" + dir_.string() + "/frames.mp4'";
  if (std::system(cmd.c_str()) == 0) movie_ = "frames.mp4";
}

nlohmann::json FrameWriter::manifest() const {
  nlohmann::json j = {{"frames", frames_},
                      {"every_steps", every_},
                      {"size", {r_.width(), r_.height()}},
                      {"render_ms_median", median(draw_ms_)},
                      {"render_timing", r_.timing_method()}};
  if (!movie_.empty()) j["movie"] = movie_;
  return j;
}

nlohmann::json run_manifest(Pipeline& p) {
  if (!context_created()) return nullptr;
  const ContextInfo& c = context();
  nlohmann::json j = {{"vendor", c.vendor}, {"renderer", c.renderer}, {"version", c.version}, {"platform", c.platform}};
  if (auto* g = dynamic_cast<GlPipeline*>(&p)) {
    j["neighbours"] = g->neighbour_mode();
  }
  return j;
}

}  // namespace deformlab::gl
