#include "render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include "core/frame_files.hpp"
#include "core/write_error.hpp"
#include "gl_pipeline.hpp"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace deformlab::gl {
namespace {

using Mat4 = std::array<float, 16>;  // column-major

constexpr int kSphereSlices = 48, kSphereStacks = 24;  // quads a sphere is drawn with

Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr)
      for (int k = 0; k < 4; ++k) r[c * 4 + rr] += a[k * 4 + rr] * b[c * 4 + k];
  return r;
}

Vec3f normalized(Vec3f v) { return v * (1.f / norm(v)); }

Mat4 view_matrix(const Camera& c) {
  const auto [f, s, u] = c.axes();
  const Vec3f e = c.eye;
  return {s.x, u.x, -f.x, 0, s.y, u.y, -f.y, 0, s.z, u.z, -f.z, 0, -dot(s, e), -dot(u, e), dot(f, e), 1};
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

Camera::Axes Camera::axes() const {
  const Vec3f f = normalized(target - eye), s = normalized(cross(f, up));
  return {f, s, cross(s, f)};
}

std::pair<Vec3f, Vec3f> Camera::ray(double px, double py, int w, int h) const {
  const auto [f, s, u] = axes();
  const float t = std::tan(fovy / 2), aspect = float(w) / float(h);
  const float nx = float(2 * px / w - 1), ny = float(1 - 2 * py / h);
  return {eye, normalized(f + s * (nx * t * aspect) + u * (ny * t))};
}

std::array<double, 2> Camera::pixel(Vec3f x, int w, int h) const {
  const auto [f, s, u] = axes();
  const Vec3f d = x - eye;
  const double t = std::tan(fovy / 2), aspect = double(w) / h, depth = dot(d, f);
  if (!(depth > 0)) return {std::nan(""), std::nan("")};  // behind the eye
  const double nx = dot(d, s) / (depth * t * aspect), ny = dot(d, u) / (depth * t);
  return {(nx + 1) * w / 2, (1 - ny) * h / 2};
}

Camera framing(const Model& m, std::optional<float> ground) {
  Vec3f lo = m.rest_position[0], hi = lo;
  for (const auto& p : m.rest_position)
    for (int c = 0; c < 3; ++c) { lo[c] = std::min(lo[c], p[c]); hi[c] = std::max(hi[c], p[c]); }
  lo.y -= 0.6f * std::max({hi.x - lo.x, hi.z - lo.z});
  if (ground) {
    const Vec3f half = (hi - lo) * 0.5f;
    lo = lo - Vec3f{half.x, 0.f, half.z};
    hi = hi + Vec3f{half.x, 0.f, half.z};
    lo.y = std::min(lo.y, *ground - 0.05f * (hi.y - lo.y));
  }
  const Vec3f centre = (lo + hi) * 0.5f;
  const float radius = std::max(0.5f * norm(hi - lo), 1e-3f);
  return {centre + Vec3f{0.f, 0.9f, 2.2f} * radius, centre};
}

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
  Camera camera;
  bool wireframe = false;
  Colour colour = Colour::plain;
  float scale = 1.f;
  Buffer rest, prev;  // colour by strain: rest positions; by speed: the positions last drawn
  Texture rest_tex, prev_tex, tri_tex;
  double time = 0.0, prev_time = 0.0;
  bool have_prev = false;
  GLint texels = 0, align = 16;
  Timer timer;
  Program obstacle_prog;  // made where there are obstacles
  Vec3f ground_centre;    // the ground's square: under the first camera's target, 1.5 x its
  float ground_half = 0;  // distance from the eye to each side

  Impl(const Model& model, RenderOptions opt) : m(model), o(opt), camera(framing(model, opt.ground)) {
    make_framebuffer();
    prog = make_program({{GL_VERTEX_SHADER, "render.vert"}, {GL_FRAGMENT_SHADER, "render.frag"}});
    if (o.ground || !o.spheres.empty())
      obstacle_prog = make_program({{GL_VERTEX_SHADER, "obstacle.vert"}, {GL_FRAGMENT_SHADER, "obstacle.frag"}});
    if (o.ground) {
      ground_centre = {camera.target.x, *o.ground, camera.target.z};
      ground_half = 1.5f * norm(camera.eye - camera.target);
    }
    GLuint id = 0;
    glGenVertexArrays(1, &id);
    vao = VertexArray(id);
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &texels);
    glGetIntegerv(GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT, &align);
    set_mode(o.mode);
    check("renderer setup");
  }

  void set_mode(RenderOptions::Mode mode) {
    const bool surface_wanted = mode == RenderOptions::Mode::surface ||
                                (mode == RenderOptions::Mode::automatic &&
                                 (m.topology == Topology::cloth_grid || !m.triangle.empty()));
    const bool want_mesh = surface_wanted && !m.triangle.empty(), want_surface = surface_wanted && !want_mesh;
    if (want_surface && (m.topology != Topology::cloth_grid || m.nx < 2 || m.ny < 2))
      throw std::invalid_argument("surface rendering needs a cloth grid of at least 2x2 nodes or a mesh's triangles");
    o.mode = mode;
    mesh = want_mesh;
    surface = want_surface;
    bands.clear();
    plan_bands(o.band_texels > 0 ? std::min<std::int64_t>(o.band_texels, texels) : texels,
               std::lcm(std::max(align, 1), 16) / 16);
    if (mesh) {
      if (bands.size() > 1)
        throw std::invalid_argument("a mesh of " + std::to_string(m.node_count()) +
                                    " nodes is more than one texture buffer holds (" + std::to_string(texels) +
                                    " texels): draw it as points");
      if (!elements) elements = make_buffer(m.triangle.size() * sizeof(std::int32_t), m.triangle.data());
    }
  }

  void make_framebuffer() {
    if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384)
      throw std::invalid_argument("frame size must be between 1 and 16384 pixels");
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
  }

  // Near and far planes at 0.05 and 4 x the eye's distance from the target (surface_at
  // inverts this projection).
  Mat4 view_proj() const {
    const float dist = norm(camera.eye - camera.target);
    return mul(perspective(camera.fovy, float(o.width) / float(o.height), dist * 0.05f, dist * 4.f),
               view_matrix(camera));
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
    if (wireframe) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glUseProgram(prog.id());
    const Mat4 vp = view_proj();
    glUniformMatrix4fv(uniform(prog.id(), "u_view_proj"), 1, GL_FALSE, vp.data());
    glUniform2i(uniform(prog.id(), "u_grid"), m.nx, m.ny);
    glUniform1i(uniform(prog.id(), "u_surface"), surface ? 1 : 0);
    glUniform1i(uniform(prog.id(), "u_mesh"), mesh ? 1 : 0);
    glUniform1f(uniform(prog.id(), "u_point_size"),
                std::clamp(float(o.width) / std::sqrt(float(m.node_count())) * 0.4f, 1.f, 8.f));
    glUniform3f(uniform(prog.id(), "u_eye"), camera.eye.x, camera.eye.y, camera.eye.z);
    glUniform1i(uniform(prog.id(), "u_stride"), stride);
    glUniform1i(uniform(prog.id(), "u_colour"), int(colour));
    glUniform1f(uniform(prog.id(), "u_scale"), scale);
    glUniform1f(uniform(prog.id(), "u_frame_dt"), have_prev ? float(time - prev_time) : 0.f);
    if (!draw_tex) draw_tex = make_texture();
    if (colour != Colour::plain) bind_colour_data();
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_BUFFER, draw_tex.id());
    glBindVertexArray(vao.id());
    const int quads_per_row = (m.nx - 2) / stride + 1;
    for (const Band& b : bands) {
      glTexBufferRange(GL_TEXTURE_BUFFER, GL_RGBA32F, positions, GLintptr(b.tex_first * 16), GLsizeiptr(b.tex_count * 16));
      if (colour != Colour::plain) {
        glTextureBufferRange(rest_tex.id(), GL_RGBA32F, rest.id(), GLintptr(b.tex_first * 16), GLsizeiptr(b.tex_count * 16));
        glTextureBufferRange(prev_tex.id(), GL_RGBA32F, prev.id(), GLintptr(b.tex_first * 16), GLsizeiptr(b.tex_count * 16));
      }
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
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    draw_obstacles(vp);
    glBindVertexArray(0);
    glUseProgram(0);
    glDisable(GL_DEPTH_TEST);
    if (colour == Colour::speed) {  // these positions are the next draw's previous ones
      glCopyNamedBufferSubData(positions, prev.id(), 0, 0, GLsizeiptr(m.node_count()) * 16);
      prev_time = time;
      have_prev = true;
    }
    timer.end();
    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(previous));
    check("rendering a frame");
  }

  // After the model, depth-tested without writing depth: the model hides them, and surface_at
  // finds only the model. They are drawn a thousandth of the view distance behind their
  // surfaces (obstacle.vert: the ground lower, a sphere along the eye's rays, so that its outline
  // keeps its size): 50 times what the depth buffer resolves there, and more than a sphere's
  // facets depart from it. A model resting on them then shows in front wherever its
  // triangles, chords between nodes on the surface, dip into a sphere by less than that (a
  // chord of length L by L^2 / 8R on a sphere of radius R). A sphere culls its back faces
  // (convex: each pixel gets its front) and drops what lies on the other side of the ground from
  // the eye (obstacle.frag); spheres that cut into each other are drawn whole, the nearer centre
  // over the other.
  void draw_obstacles(const Mat4& vp) {
    if (!obstacle_prog) return;
    const GLuint id = obstacle_prog.id();
    glUseProgram(id);
    glUniformMatrix4fv(uniform(id, "u_view_proj"), 1, GL_FALSE, vp.data());
    glUniform3f(uniform(id, "u_eye"), camera.eye.x, camera.eye.y, camera.eye.z);
    glUniform1f(uniform(id, "u_inset"), 1e-3f * norm(camera.eye - camera.target));
    glDepthMask(GL_FALSE);
    glUniform1i(uniform(id, "u_has_ground"), o.ground.has_value());
    glUniform1f(uniform(id, "u_ground"), o.ground.value_or(0.f));
    if (o.ground) {
      glUniform1i(uniform(id, "u_kind"), 0);
      glUniform3f(uniform(id, "u_center"), ground_centre.x, ground_centre.y, ground_centre.z);
      glUniform1f(uniform(id, "u_size"), ground_half);
      glUniform1f(uniform(id, "u_check"), ground_half / 10);
      glDrawArrays(GL_TRIANGLES, 0, 6);
    }
    glEnable(GL_CULL_FACE);
    glUniform1i(uniform(id, "u_kind"), 1);
    glUniform2i(uniform(id, "u_grid"), kSphereSlices, kSphereStacks);
    // The farthest first, so that a nearer sphere covers one behind it.
    std::vector<Sphere> spheres = o.spheres;
    std::sort(spheres.begin(), spheres.end(), [&](const Sphere& a, const Sphere& b) {
      return norm(a.center - camera.eye) > norm(b.center - camera.eye);
    });
    for (const Sphere& sphere : spheres) {
      glUniform3f(uniform(id, "u_center"), sphere.center.x, sphere.center.y, sphere.center.z);
      glUniform1f(uniform(id, "u_size"), sphere.radius);
      glDrawArrays(GL_TRIANGLES, 0, 6 * kSphereSlices * kSphereStacks);
    }
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
  }

  // The rest positions, the previous positions and a mesh's triangles as texture buffers on
  // units 1 to 3 (made on first use).
  void bind_colour_data() {
    const std::size_t n = std::size_t(m.node_count());
    if (!rest) {
      std::vector<float> r(4 * n);
      for (std::size_t i = 0; i < n; ++i) std::copy_n(&m.rest_position[i].x, 3, &r[4 * i]);
      rest = make_buffer(r.size() * 4, r.data());
      prev = make_buffer(n * 16);
      for (Texture* t : {&rest_tex, &prev_tex, &tri_tex}) {
        GLuint id = 0;
        glCreateTextures(GL_TEXTURE_BUFFER, 1, &id);
        *t = Texture(id);
      }
      if (elements) glTextureBuffer(tri_tex.id(), GL_R32I, elements.id());
    }
    glBindTextureUnit(1, rest_tex.id());
    glBindTextureUnit(2, prev_tex.id());
    glBindTextureUnit(3, tri_tex.id());
  }

  static Texture make_texture() {
    GLuint id = 0;
    glGenTextures(1, &id);
    return Texture(id);
  }
};

RenderOptions with_obstacles(RenderOptions o, const Params& p) {
  o.ground = p.ground;
  o.spheres = p.spheres;
  return o;
}

Renderer::Renderer(const Model& m, RenderOptions o) {
  context();
  impl_ = std::make_unique<Impl>(m, o);
}

Renderer::~Renderer() = default;

void Renderer::draw(Pipeline& p) {
  context();
  if (const GLuint b = p.gl_position_buffer())
    impl_->draw_buffer(b);
  else
    draw(p.state());
}

void Renderer::draw_positions(unsigned buffer) {
  context();
  impl_->draw_buffer(buffer);
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
    throw write_error(file.string());
}

std::vector<double> Renderer::take_draw_ms() { return impl_->timer.take(); }
std::string Renderer::timing_method() const { return impl_->timer.method(); }
int Renderer::width() const { return impl_->o.width; }
int Renderer::height() const { return impl_->o.height; }
const Camera& Renderer::camera() const { return impl_->camera; }
void Renderer::set_camera(const Camera& c) { impl_->camera = c; }
void Renderer::set_wireframe(bool on) { impl_->wireframe = on; }
void Renderer::set_time(double t) { impl_->time = t; }

void Renderer::set_colour(Colour c, float scale) {
  if (!(scale > 0.f)) throw std::invalid_argument("a colour scale must be positive");
  if (c == Colour::speed && impl_->colour != Colour::speed) impl_->have_prev = false;
  impl_->colour = c;
  impl_->scale = scale;
}
unsigned Renderer::framebuffer() const { return impl_->fbo.id(); }

std::optional<Vec3f> Renderer::surface_at(double px, double py) {
  context();
  const Impl& r = *impl_;
  const int x = int(px), y = r.o.height - 1 - int(py);
  if (x < 0 || y < 0 || x >= r.o.width || y >= r.o.height) return std::nullopt;
  float depth = 1.f;
  const GLint previous = bound_framebuffer(GL_READ_FRAMEBUFFER_BINDING);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, r.fbo.id());
  glReadPixels(x, y, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &depth);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, GLuint(previous));
  check("reading the depth under the cursor");
  if (!(depth < 1.f)) return std::nullopt;
  // The view distance along the camera's axis from the depth (the projection of view_proj()).
  const Camera& c = r.camera;
  const float dist = norm(c.eye - c.target), n = dist * 0.05f, f = dist * 4.f;
  const float z_ndc = 2.f * depth - 1.f, z = 2.f * f * n / ((f + n) - z_ndc * (f - n));
  const auto [o, d] = c.ray(px, py, r.o.width, r.o.height);
  return o + d * (z / dot(d, c.axes().forward));
}

void Renderer::set_mode(RenderOptions::Mode m) {
  context();
  impl_->set_mode(m);
}

void Renderer::resize(int width, int height) {
  context();
  if (width == impl_->o.width && height == impl_->o.height) return;
  impl_->o.width = width;
  impl_->o.height = height;
  impl_->make_framebuffer();
  impl_->set_mode(impl_->o.mode);  // a cloth's sampling follows the frame size
  check("resizing the frame");
}

FrameWriter::FrameWriter(const Model& m, std::filesystem::path dir, int every, RenderOptions o)
    : r_(m, o), dir_(std::move(dir)), every_(every) {
  if (every_ < 1) throw std::invalid_argument("--frames must be at least 1");
  std::filesystem::create_directories(dir_);
}

void FrameWriter::write(Pipeline& p, int step) {
  r_.draw(p);
  r_.write_png(dir_ / frame_file(step));
  const auto ms = r_.take_draw_ms();
  draw_ms_.insert(draw_ms_.end(), ms.begin(), ms.end());
  last_written_ = step;
  ++frames_;
}

void FrameWriter::after_step(Pipeline& p, int step) {
  if (due(step)) write(p, step);
}

void FrameWriter::write_last(Pipeline& p, int last_step) {
  if (last_written_ != last_step) write(p, last_step);
}

void FrameWriter::finish(Pipeline& p, int last_step) {
  write_last(p, last_step);
  if (frames_ < 2 || std::system("command -v ffmpeg >/dev/null 2>&1") != 0) return;
  const std::string cmd = "ffmpeg -loglevel error -y -framerate 30 -pattern_type glob -i '" + dir_.string() + "/" +
                          kFrameGlob + "' -c:v libx264 -pix_fmt yuv420p '" + dir_.string() + "/" + kFramesMovie + "'";
  if (std::system(cmd.c_str()) == 0) movie_ = kFramesMovie;
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
