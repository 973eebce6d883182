// Rendering: the cloth shows where the camera looks, from GL buffers and from CPU states.
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/cpu_backend.hpp"
#include "core/node_order.hpp"
#include "gl_test_support.hpp"
#include "gl/render.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

struct Coverage {
  long pixels = 0;
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
};

// Pixels that differ from the background (the top-left corner's colour).
Coverage coverage(const std::vector<std::uint8_t>& px, int w, int h) {
  Coverage c;
  const std::array<std::uint8_t, 3> bg = {px[0], px[1], px[2]};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint8_t* p = &px[(std::size_t(y) * w + x) * 4];
      if (p[0] == bg[0] && p[1] == bg[1] && p[2] == bg[2]) continue;
      ++c.pixels;
      c.x0 = std::min(c.x0, x); c.x1 = std::max(c.x1, x);
      c.y0 = std::min(c.y0, y); c.y1 = std::max(c.y1, y);
    }
  return c;
}

// Pixels that differ between frames a and b (w x h) in the square of cx, cy and `half` pixels
// to each side, within the frame.
long pixels_differing(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b, int w, int h, int cx,
                      int cy, int half) {
  long n = 0;
  for (int y = std::max(0, cy - half); y <= std::min(h - 1, cy + half); ++y)
    for (int x = std::max(0, cx - half); x <= std::min(w - 1, cx + half); ++x) {
      const std::size_t i = (std::size_t(y) * w + x) * 4;
      n += a[i] != b[i] || a[i + 1] != b[i + 1] || a[i + 2] != b[i + 2];
    }
  return n;
}

// Frames of m at rest drawn with `look`, and with `look` and the spheres `more` after its own.
std::array<std::vector<std::uint8_t>, 2> without_and_with(const Model& m, gl::RenderOptions look,
                                                          const std::vector<Sphere>& more) {
  gl::Renderer without(m, look);
  look.spheres.insert(look.spheres.end(), more.begin(), more.end());
  gl::Renderer with(m, look);
  without.draw(rest_state(m));
  with.draw(rest_state(m));
  return {without.pixels(), with.pixels()};
}

void expect_centred(const Coverage& c, int w, int h, double min_fraction, const std::string& what) {
  const double frac = double(c.pixels) / (double(w) * h);
  EXPECT_GT(frac, min_fraction) << what << ": too few pixels drawn";
  EXPECT_LT(frac, 0.9) << what << ": the frame is filled";
  // The camera looks at the model's centre from the front: the drawing straddles the
  // middle column, spans a good part of the width and lies inside the frame, not cut.
  EXPECT_LE(c.x0, w / 2) << what;
  EXPECT_GE(c.x1, w / 2) << what;
  EXPECT_GT(c.x1 - c.x0, w / 3) << what << ": the cloth should span the frame";
  EXPECT_GT(c.x0, 0) << what;
  EXPECT_LT(c.x1, w - 1) << what;
  EXPECT_GT(c.y0, 0) << what;
  EXPECT_LT(c.y1, h - 1) << what;
}

TEST(GlRender, ClothSurfaceFromEveryKindOfPipeline) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(32, 32);
  const Params p = small_params();
  gl::Renderer r(m, {256, 256});
  std::vector<long> counts;
  for (const char* name : {"glsl-tf", "glsl-compute", "cpu"}) {
    auto pipe = std::string(name) == "cpu" ? make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, false)
                                           : make_gl(name, {m, p, Integrator::semi_implicit_euler});
    pipe->set_state(rest_state(m));
    for (int k = 0; k < 30; ++k) pipe->step();
    r.draw(*pipe);
    const Coverage c = coverage(r.pixels(), 256, 256);
    expect_centred(c, 256, 256, 0.1, name);
    counts.push_back(c.pixels);
  }
  // The same state drawn from GL buffers or uploaded from the CPU covers the same pixels
  // up to the float rounding of the two trajectories.
  EXPECT_NEAR(double(counts[0]), double(counts[2]), 0.01 * double(counts[2]));
  EXPECT_NEAR(double(counts[1]), double(counts[2]), 0.01 * double(counts[2]));
  EXPECT_EQ(r.take_draw_ms().size(), 3u);
}

// A model drawn in bands (each draw reading a few rows of positions, as the largest models
// are past the texture buffer limit) gives the pixels of one draw; a cloth wider than twice
// the frame is drawn every stride-th row and column, still framed.
TEST(GlRender, BandsAndStridesDrawTheSameModel) {
  DEFORMLAB_REQUIRE_GL();
  for (const Model& m : {small_cloth(40, 33), small_lattice(9, 8, 7)}) {
    const State s = perturbed_state(m, 3, 0.01f, 0.f);
    gl::Renderer whole(m, {200, 200}), banded(m, {200, 200, gl::RenderOptions::Mode::automatic, 8 * m.nx});
    whole.draw(s);
    banded.draw(s);
    const auto a = whole.pixels(), b = banded.pixels();
    EXPECT_EQ(a, b) << m.nx << "x" << m.ny << "x" << m.nz;
    expect_centred(coverage(a, 200, 200), 200, 200, 0.02, "whole");
  }
  const Model wide = small_cloth(700, 90);  // 700 > 2 x 128 pixels: every 2nd node drawn
  gl::Renderer r(wide, {128, 128, gl::RenderOptions::Mode::automatic, 20 * 700});
  r.draw(rest_state(wide));
  expect_centred(coverage(r.pixels(), 128, 128), 128, 128, 0.015, "a 700x90 cloth drawn every 2nd node");
}

// A mesh is drawn as its triangles (a volume as its boundary): a closed surface where its
// points alone leave gaps, the same from a shuffled node order and from a GL pipeline's buffers.
TEST(GlRender, MeshTrianglesInAnyNodeOrder) {
  DEFORMLAB_REQUIRE_GL();
  Mesh box = tetrahedralised_box(6, 5, 4);
  repair(box);
  const Model m = mesh_model(box, Material{}, 0.f);
  Model shuffled = m;
  reorder(shuffled, node_order(shuffled, NodeOrder::shuffled, 4));
  gl::Renderer faces(m, {200, 200}), again(shuffled, {200, 200}), points(m, {200, 200, gl::RenderOptions::Mode::points});
  faces.draw(rest_state(m));
  again.draw(rest_state(shuffled));
  points.draw(rest_state(m));
  const Coverage f = coverage(faces.pixels(), 200, 200), p = coverage(points.pixels(), 200, 200);
  expect_centred(f, 200, 200, 0.05, "a tetrahedral box's boundary");
  EXPECT_GT(f.pixels, 2 * p.pixels) << "the faces fill what the points leave open";
  EXPECT_EQ(coverage(again.pixels(), 200, 200).pixels, f.pixels);
  auto pipe = make_gl("glsl-compute", {shuffled, small_params(), Integrator::semi_implicit_euler});
  pipe->set_state(rest_state(shuffled));
  again.draw(*pipe);
  EXPECT_EQ(coverage(again.pixels(), 200, 200).pixels, f.pixels) << "drawn from the pipeline's own buffer";
}

// The colour under `x`: red minus blue (positive: the hot end of the ramp).
int warmth(gl::Renderer& r, Vec3f x) {
  const auto px = r.pixels();
  const auto p = r.camera().pixel(x, r.width(), r.height());
  const std::uint8_t* q = &px[(std::size_t(p[1]) * r.width() + std::size_t(p[0])) * 4];
  return int(q[0]) - int(q[2]);
}

// Strain: at rest blue, stretched by 30% (over a scale of 20%) red, on a cloth grid (by node)
// and on a mesh (by triangle). Speed: nodes moved 0.2 m in 0.1 s (over 1 m/s) red, then still.
TEST(GlRender, ColoursByStrainAndSpeed) {
  DEFORMLAB_REQUIRE_GL();
  Mesh sheet = triangulated_square(30, 30);
  repair(sheet);
  for (const Model& m : {small_cloth(30, 30), mesh_model(sheet, Material{}, 0.f)}) {
    const int centre = 30 * 15 + 15;
    const Vec3f c = m.rest_position[centre];
    State stretched = rest_state(m);
    for (Vec3f& x : stretched.x) x = c + (x - c) * 1.3f;
    gl::Renderer r(m, {300, 300});
    r.set_colour(gl::Renderer::Colour::strain, 0.2f);
    r.draw(rest_state(m));
    EXPECT_LT(warmth(r, c), -50) << "at rest: no strain";
    r.draw(stretched);
    EXPECT_GT(warmth(r, c), 50) << "stretched by 30%";

    State moved = rest_state(m);
    for (Vec3f& x : moved.x) x.y += 0.2f;
    r.set_colour(gl::Renderer::Colour::speed, 1.f);
    r.set_time(0.0);
    r.draw(rest_state(m));
    EXPECT_LT(warmth(r, c), -50) << "nothing drawn before: no speed";
    r.set_time(0.1);
    r.draw(moved);
    EXPECT_GT(warmth(r, c + Vec3f{0.f, 0.2f, 0.f}), 50) << "2 m/s";
    r.set_time(0.2);
    r.draw(moved);
    EXPECT_LT(warmth(r, c + Vec3f{0.f, 0.2f, 0.f}), -50) << "still";
  }
}

// The scene's ground and spheres are drawn where the model does not hide them: a sphere beside
// the cloth shows blue-grey, one behind it stays hidden, the ground shows grey where there was
// background, every pixel of the cloth is what it is without obstacles, and picking
// (surface_at) finds the cloth but no point on an obstacle.
TEST(GlRender, GroundAndSpheresWhereTheModelDoesNotHideThem) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(16, 16);  // horizontal, 0.75 m wide, at y = 1
  const int w = 256, h = 256;
  const float ground_y = 0.6f;
  const gl::Camera cam = gl::framing(m, ground_y);
  const Vec3f centre = {0.f, 1.f, 0.f}, beside = {0.6f, 1.f, 0.f};  // the cloth's centre; right of its edge
  const Vec3f behind = centre + (centre - cam.eye) * (0.5f / norm(centre - cam.eye));
  gl::RenderOptions look{w, h};
  look.ground = ground_y;
  look.spheres = {{beside, 0.08f}, {behind, 0.03f}};
  gl::Renderer r(m, look), alone(m, {w, h});
  alone.set_camera(cam);
  alone.draw(rest_state(m));
  const auto before = alone.pixels();
  r.draw(rest_state(m));
  const auto px = r.pixels();
  auto at = [&](const std::vector<std::uint8_t>& img, int x, int y) { return &img[(std::size_t(y) * w + x) * 4]; };
  const std::uint8_t* bg = at(before, 0, 0);
  auto is_bg = [&](const std::uint8_t* p) { return p[0] == bg[0] && p[1] == bg[1] && p[2] == bg[2]; };

  long cloth = 0, changed = 0, ground = 0;
  std::array<int, 2> ground_px{-1, -1};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint8_t *a = at(before, x, y), *b = at(px, x, y);
      if (!is_bg(a)) {
        ++cloth;
        changed += a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
      } else if (!is_bg(b) && std::abs(int(b[0]) - int(b[2])) <= 12) {
        ++ground;
        if (ground_px[0] < 0 && y > h / 2) ground_px = {x, y};
      }
    }
  EXPECT_GT(cloth, 1000);
  EXPECT_EQ(changed, 0) << "of " << cloth << " cloth pixels: the ground or the hidden sphere drawn over the cloth";
  EXPECT_GT(ground, w * h / 10) << "the ground's grey over the background";
  const auto [sx, sy] = cam.pixel(beside, w, h);
  ASSERT_TRUE(sx > 0 && sx < w && sy > 0 && sy < h) << "the sphere beside the cloth is in view";
  const std::uint8_t* sphere = at(px, int(sx), int(sy));
  EXPECT_GT(int(sphere[2]), int(sphere[0]) + 20) << "blue-grey: " << int(sphere[0]) << " " << int(sphere[2]);
  EXPECT_FALSE(r.surface_at(sx, sy)) << "a sphere is not picked";
  ASSERT_GE(ground_px[0], 0);
  EXPECT_FALSE(r.surface_at(ground_px[0] + 0.5, ground_px[1] + 0.5)) << "the ground is not picked";
  const auto [cx, cy] = cam.pixel(centre, w, h);
  const auto picked = r.surface_at(cx, cy);
  ASSERT_TRUE(picked) << "the cloth is picked";
  EXPECT_NEAR(picked->y, 1.f, 0.01f);
}

// A model resting on the obstacles, exactly on their surfaces where the constraints put it (a
// cloth on the ground and over the cap of a sphere that rises through it), shows whole in front
// of them: every pixel of the cloth is what it is without obstacles, none the ground's or the
// sphere's, while the ground shows around it and a sphere beside it shows whole. (The cap is
// low enough that the cloth's triangles, chords between nodes on the sphere, dip into it by
// less than the drawing's inset.)
TEST(GlRender, AModelRestingOnTheObstaclesShowsInFrontOfThem) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = cloth_grid(49, 49, 0.75f / 48, 1.f, Material{});  // horizontal, 0.75 m wide, at y = 1
  const int w = 256, h = 256;
  const float ground_y = 1.f, radius = 0.2f;
  const Vec3f centre = {0.f, ground_y - 0.1f, 0.f};  // a cap 0.1 m high and 0.35 m across
  State s = rest_state(m);
  int on_sphere = 0;
  for (Vec3f& x : s.x) {
    const float q = radius * radius - x.x * x.x - x.z * x.z;
    if (q <= 0.f || centre.y + std::sqrt(q) <= ground_y) continue;
    x.y = centre.y + std::sqrt(q);
    ++on_sphere;
  }
  ASSERT_GT(on_sphere, 300);
  const gl::Camera cam = gl::framing(m, ground_y);
  gl::RenderOptions look{w, h};
  look.ground = ground_y;
  const Vec3f beside = {0.6f, ground_y + 0.1f, 0.f};  // right of the cloth's edge, above the ground
  look.spheres = {{centre, radius}, {beside, 0.08f}};
  gl::Renderer with(m, look), alone(m, {w, h});
  with.set_camera(cam);
  alone.set_camera(cam);
  with.draw(s);
  alone.draw(s);
  const auto a = alone.pixels(), b = with.pixels();
  long cloth = 0, changed = 0, ground = 0;
  for (std::size_t i = 0; i < a.size(); i += 4) {
    if (a[i] == a[0] && a[i + 1] == a[1] && a[i + 2] == a[2]) {  // the background without obstacles
      ground += std::abs(int(b[i]) - int(b[i + 2])) <= 12 && b[i] != a[0];
      continue;
    }
    ++cloth;
    changed += a[i] != b[i] || a[i + 1] != b[i + 1] || a[i + 2] != b[i + 2];
  }
  EXPECT_GT(cloth, 2000);
  EXPECT_EQ(changed, 0) << "of " << cloth << " cloth pixels: the ground or the sphere drawn through the cloth";
  EXPECT_GT(ground, w * h / 10) << "the ground's grey around the cloth";
  // The sphere beside the cloth: blue-grey a pixel inside its outline at the height of its centre,
  // the ground's grey a pixel outside.
  const auto [sx, sy] = cam.pixel(beside, w, h);
  const auto [ex, ey] = cam.pixel(beside + Vec3f{0.08f, 0.f, 0.f}, w, h);
  auto px = [&](double x, double y) { return &b[(std::size_t(y) * w + std::size_t(x)) * 4]; };
  const std::uint8_t *mid = px(sx, sy), *in = px(ex - 2, ey), *out = px(ex + 2, ey);
  EXPECT_GT(int(mid[2]), int(mid[0]) + 20) << "blue-grey at its centre";
  EXPECT_GT(int(in[2]), int(in[0]) + 20) << "blue-grey just inside its outline";
  EXPECT_LE(std::abs(int(out[2]) - int(out[0])), 12) << "the ground just outside its outline";
}

// The ground hides what of a sphere lies under it: a sphere wholly under the ground leaves the
// frame as it is without it, and one half under shows its upper half.
TEST(GlRender, TheGroundHidesWhatOfASphereIsUnderIt) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(16, 16);  // horizontal, 0.75 m wide, at y = 1
  const int w = 256, h = 256;
  const float ground_y = 0.6f;
  const Vec3f under = {0.6f, ground_y - 0.1f, 0.f}, half = {-0.6f, ground_y, 0.f};
  gl::RenderOptions look{w, h};
  look.ground = ground_y;
  const auto [a, b] = without_and_with(m, look, {{under, 0.08f}, {half, 0.08f}});
  const gl::Camera cam = gl::framing(m, ground_y);
  auto changed_near = [&](Vec3f centre) {
    const auto [sx, sy] = cam.pixel(centre, w, h);
    return pixels_differing(a, b, w, h, int(sx), int(sy), 30);
  };
  EXPECT_EQ(changed_near(under), 0) << "pixels of the sphere under the ground";
  EXPECT_GT(changed_near(half), 100) << "the upper half of the sphere on the ground";
  const auto [tx, ty] = cam.pixel(half + Vec3f{0.f, 0.07f, 0.f}, w, h);
  const auto [bx, by] = cam.pixel(half - Vec3f{0.f, 0.07f, 0.f}, w, h);
  const std::uint8_t *top = &b[(std::size_t(ty) * w + int(tx)) * 4], *bottom = &b[(std::size_t(by) * w + int(bx)) * 4];
  EXPECT_GT(int(top[2]), int(top[0]) + 20) << "blue-grey near its top";
  EXPECT_LE(std::abs(int(bottom[2]) - int(bottom[0])), 12) << "grey ground over its bottom";
}

// A sphere in front of another covers it, whatever their order in the scene.
TEST(GlRender, ANearerSphereCoversOneBehindIt) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(16, 16);
  const int w = 256, h = 256;
  const gl::Camera cam = gl::framing(m, std::nullopt);
  const Vec3f near = {0.f, 1.25f, 0.f}, ray = (near - cam.eye) * (1.f / norm(near - cam.eye));
  const Vec3f far = near + ray * 0.3f + Vec3f{0.f, 0.08f, 0.f};  // its edge behind the near one's centre
  gl::RenderOptions look{w, h};
  look.spheres = {{near, 0.05f}};
  const auto [a, b] = without_and_with(m, look, {{far, 0.12f}});  // the far sphere after the near one
  const auto [sx, sy] = cam.pixel(near, w, h);
  ASSERT_TRUE(sx > 3 && sx < w - 4 && sy > 3 && sy < h - 4) << "the near sphere is in view";
  EXPECT_EQ(pixels_differing(a, b, w, h, int(sx), int(sy), 3), 0)
      << "of 49 pixels at the near sphere's centre, the far sphere drawn over it";
  EXPECT_GT(coverage(b, w, h).pixels, coverage(a, w, h).pixels + 200) << "the far sphere around the near one";
}

// A sphere shows at its own size, not shrunk by the inset that keeps it behind a model resting
// on it: at 2048 x 2048, where a sphere drawn that much smaller showed 3 px short of its outline
// on each side, the row through its centre is blue-grey to within 1.5 px of its outline on both
// sides (its 48 slices' chords fall a fraction of a pixel short of it) and not 1.5 px outside it.
TEST(GlRender, ASphereShowsAtItsOwnSize) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(16, 16);
  const int w = 2048, h = 2048;
  const float ground_y = 0.6f, radius = 0.08f;
  const Vec3f centre = {0.6f, ground_y + 0.1f, 0.f};
  const gl::Camera cam = gl::framing(m, ground_y);
  gl::RenderOptions look{w, h};
  look.ground = ground_y;
  look.spheres = {{centre, radius}};
  gl::Renderer renderer(m, look);
  renderer.set_camera(cam);
  renderer.draw(rest_state(m));
  const auto b = renderer.pixels();
  // Its outline on the row through its centre: where the pixels' rays graze it (bisection).
  const double row = cam.pixel(centre, w, h)[1], middle = cam.pixel(centre, w, h)[0];
  auto outside = [&](double x) {
    const auto [eye, ray] = cam.ray(x, row, w, h);
    const Vec3f to = centre - eye;
    return norm(to - ray * dot(to, ray)) > radius;
  };
  auto edge = [&](double far) {
    double in = middle;
    for (int k = 0; k < 40; ++k) (outside((in + far) / 2) ? far : in) = (in + far) / 2;
    return in;
  };
  const double left = edge(0), right_edge = edge(w - 1);
  auto blue = [&](double x) {
    const std::uint8_t* p = &b[(std::size_t(row) * w + std::size_t(x)) * 4];
    return int(p[2]) > int(p[0]) + 20;
  };
  EXPECT_TRUE(blue(left + 1.5)) << "blue-grey 1.5 px inside its left outline";
  EXPECT_TRUE(blue(right_edge - 1.5)) << "blue-grey 1.5 px inside its right outline";
  EXPECT_FALSE(blue(left - 1.5)) << "not blue-grey 1.5 px outside its left outline";
  EXPECT_FALSE(blue(right_edge + 1.5)) << "not blue-grey 1.5 px outside its right outline";
}

TEST(GlRender, LatticeAsPointsAndPngFile) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_lattice(6, 5, 4);
  gl::Renderer r(m, {200, 160, gl::RenderOptions::Mode::points});
  r.draw(rest_state(m));
  const Coverage c = coverage(r.pixels(), 200, 160);
  EXPECT_GT(c.pixels, 100);
  EXPECT_LE(c.x0, 100);
  EXPECT_GE(c.x1, 100);
  const auto file = std::filesystem::temp_directory_path() / ("deformlab-gl-test-" + std::to_string(::getpid()) + ".png");
  r.write_png(file);
  std::ifstream in(file, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");
  std::filesystem::remove(file);
}

TEST(GlRender, FrameWriterWritesEveryNthAndTheFinalFrame) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(8, 8);
  const Params p = small_params();
  auto pipe = make_gl("glsl-tf", {m, p, Integrator::verlet});
  const auto dir = std::filesystem::temp_directory_path() / ("deformlab-frames-" + std::to_string(::getpid()));
  {
    gl::FrameWriter w(m, dir, 4, {64, 64});
    for (int s = 1; s <= 10; ++s) {
      pipe->step();
      w.after_step(*pipe, s);
    }
    w.finish(*pipe, 10);
    EXPECT_EQ(w.manifest()["frames"], 3);
  }
  for (const char* f : {"frame_000004.png", "frame_000008.png", "frame_000010.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace deformlab::test
