// The viewer's simulation without a window: pipelines replaced mid-run with the state carried
// over, the drag handle of picking, pins toggled, reset; picking and the camera's moves; the
// script file's events read as typed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/run.hpp"
#include "experiments/pipelines.hpp"
#include "gl/context.hpp"
#include "gl/render.hpp"
#include "tests/support/test_states.hpp"
#include "viewer/orbit.hpp"
#include "viewer/script.hpp"
#include "viewer/session.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

using viewer::Session;

Session cloth_session(const std::string& pipeline, int side = 12, Integrator i = Integrator::semi_implicit_euler) {
  Model m = small_cloth(side, side);
  m.damping = {0.02f, 0.02f, 0.01f};
  return Session({std::move(m), small_params(), pipelines().find(pipeline), i, {}});
}

TEST(ViewerSession, ReplacedPipelineContinuesTheTrajectory) {
  // cpu -> omp -> cpu, with a dt change on the way: omp is bitwise cpu, so the result equals
  // cpu run all along with the same dt change.
  Session s = cloth_session("cpu"), plain = cloth_session("cpu");
  s.step(10);
  plain.step(10);
  ASSERT_EQ(s.replace(*pipelines().find("omp"), Integrator::semi_implicit_euler, {}, 0.002f), "");
  EXPECT_TRUE(s.carried_exactly());
  EXPECT_EQ(s.entry().name, "omp");
  ASSERT_EQ(plain.replace(*pipelines().find("cpu"), Integrator::semi_implicit_euler, {}, 0.002f), "");
  s.step(10);
  plain.step(10);
  ASSERT_EQ(s.replace(*pipelines().find("cpu"), Integrator::semi_implicit_euler, {}, 0.002f), "");
  s.step(5);
  plain.step(5);
  EXPECT_TRUE(bitwise_equal(s.pipeline().state(), plain.pipeline().state()));
  EXPECT_EQ(s.steps(), 25);
  EXPECT_NEAR(s.time(), 10 * 0.001 + 15 * 0.002, 1e-8);
}

TEST(ViewerSession, VerletKeepsItsHalfStepVelocityOnlyAtItsOwnStep) {
  const Integrator verlet = Integrator::verlet;
  Session s = cloth_session("cpu", 12, verlet), plain = cloth_session("cpu", 12, verlet);
  s.step(10);
  plain.step(10);
  // The same rule and step: the half-step velocity goes along and the run goes on as if uninterrupted.
  ASSERT_EQ(s.replace(*pipelines().find("omp"), verlet, {}, s.params().dt), "");
  s.step(10);
  plain.step(10);
  EXPECT_TRUE(bitwise_equal(s.pipeline().state(), plain.pipeline().state()));
  // Another step: it belongs to the old one, so Verlet starts again from (x, v).
  const State at = s.pipeline().state();
  ASSERT_TRUE(at.half_step);
  const float dt = 2 * s.params().dt;
  ASSERT_EQ(s.replace(*pipelines().find("cpu"), verlet, {}, dt), "");
  s.step(10);
  Params p = small_params();
  p.dt = dt;
  auto again = [&](bool half_step) {
    auto pipe = pipelines().find("cpu")->make({s.model(), p, verlet, {}});
    State from = at;
    from.half_step = half_step;
    pipe->set_state(from);
    for (int k = 0; k < 10; ++k) pipe->step();
    return pipe->state();
  };
  EXPECT_TRUE(bitwise_equal(s.pipeline().state(), again(false)));
  EXPECT_FALSE(bitwise_equal(s.pipeline().state(), again(true))) << "a whole first kick would differ";
}

TEST(ViewerSession, EveryAvailablePipelineTakesTheStateExactly) {
  Session s = cloth_session("cpu");
  s.step(7);
  for (const PipelineEntry& e : pipelines().all()) {
    if (!e.unavailable().empty()) continue;
    const State before = s.pipeline().state();
    ASSERT_EQ(s.replace(e, Integrator::semi_implicit_euler, {}, s.params().dt), "") << e.name;
    EXPECT_TRUE(s.carried_exactly()) << e.name;
    EXPECT_TRUE(bitwise_equal(s.pipeline().state(), before)) << e.name;
    s.step(3);
  }
}

TEST(ViewerSession, AReplacementThatCannotBeMadeKeepsThePipeline) {
  Session s = cloth_session("cpu");
  s.step(3);
  const State before = s.pipeline().state();
  const std::string why = s.replace(*pipelines().find("omp"), Integrator::semi_implicit_euler, {}, -1.f);
  EXPECT_NE(why.find("dt"), std::string::npos) << why;
  EXPECT_EQ(s.entry().name, "cpu");
  EXPECT_TRUE(bitwise_equal(s.pipeline().state(), before));
  // Options are checked as `run` checks them: a name the pipeline does not read, a value it cannot.
  EXPECT_EQ(s.replace(*pipelines().find("omp"), Integrator::semi_implicit_euler, {{"bogus", "1"}}, 1e-3f),
            "option 'bogus' is not an option of omp (it has none)");
  const PipelineEntry& compute = *pipelines().find("glsl-compute");
  if (compute.read_options && compute.unavailable().empty()) {
    EXPECT_EQ(s.replace(compute, Integrator::semi_implicit_euler, {{"math", "slow"}}, 1e-3f),
              "glsl-compute: option math 'slow' is not exact or fast");
  }
  EXPECT_EQ(s.entry().name, "cpu");
}

// A script's events are read as typed: each mistyped value or unknown key name is refused with
// the file and the event's index; an event file written back reads the same.
TEST(ViewerScript, MistypedEventsAreRefusedByIndex) {
  const auto file = std::filesystem::temp_directory_path() / ("deformlab-script-" + std::to_string(::getpid()) + ".json");
  auto refusal = [&](const std::string& event) {
    std::ofstream(file) << R"({"events": [{"frame": 0, "event": "quit"}, )" + event + "]}";
    try {
      viewer::read_script(file.string());
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string at = "script file " + file.string() + ", event 1: ";
  EXPECT_EQ(refusal(R"({"frame": "x", "event": "quit"})"), at + "frame must be a whole number >= 0");
  EXPECT_EQ(refusal(R"({"frame": 1.5, "event": "quit"})"), at + "frame must be a whole number >= 0");
  EXPECT_EQ(refusal(R"({"frame": -1, "event": "quit"})"), at + "frame must be a whole number >= 0");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "key", "key": "zz"})"),
            at + "key 'zz' is not a key the viewer acts on (space, backspace, c, m, n, p, r, v, w)");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "key", "key": "z"})"),
            at + "key 'z' is not a key the viewer acts on (space, backspace, c, m, n, p, r, v, w)");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set"})"), at + "a set event needs one of pipeline, integrator, dt and options");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "screenshot", "file": "shot.jpg"})"),
            at + "screenshot 'shot.jpg': expected a file name ending in .png (screenshots are PNG)");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "move", "x": "left"})"), at + "x must be a number within ±1e6");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "move", "x": 1, "y": 1e300})"), at + "y must be a number within ±1e6");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set", "dt": 1e-40})"),
            at + "dt must be a number of seconds > 0 within float's normal range");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set", "pipeline": "foo"})").rfind(at + "unknown pipeline 'foo' (valid: ", 0), 0u);
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set", "integrator": "rk5"})").rfind(at + "unknown integrator 'rk5'", 0), 0u);
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set", "dt": "0.0005"})"), "") << "a saved script's dt is text";
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set", "dt": "abc"})"), "") << "as typed into the panel: refused when replayed";
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "press", "shift": 1})"), at + "shift must be true or false");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "screenshot", "file": 3})"), at + "file must be a string");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "key"})"), at + "a key event needs a key");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "quit", "button": "left"})"), at + "unknown key 'button' of a quit event");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set", "pipeline": 3})"), at + "pipeline must be a string");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "set", "dt": 0.001, "options": "math=fast"})"), "");
  EXPECT_EQ(refusal(R"({"frame": 1, "event": "key", "key": "w"})"), "");
  const std::vector<viewer::Event> events = viewer::read_script(file.string());
  viewer::write_script(file.string(), events);
  ASSERT_EQ(viewer::read_script(file.string()).size(), 2u);
  EXPECT_EQ(viewer::to_json(viewer::read_script(file.string())[1]), viewer::to_json(events[1]));
  std::filesystem::remove(file);
}

TEST(ViewerSession, DraggedNodeSitsOnItsTargetAndMovesOnceReleased) {
  Session s = cloth_session("cpu");
  const int node = 6 * 12 + 6;
  const Vec3f target = s.model().rest_position[node] + Vec3f{0.05f, 0.1f, 0.f};
  s.drag(node, target);
  s.step(5);
  EXPECT_EQ(s.pipeline().state().x[node], target);
  EXPECT_EQ(s.dragged(), node);
  s.release();
  s.step(5);
  EXPECT_LT(s.pipeline().state().x[node].y, target.y) << "released, it falls";
  EXPECT_EQ(s.dragged(), -1);
}

TEST(ViewerSession, PinsHoldAndFreeNodesAndResetRestoresTheScene) {
  Session s = cloth_session("cpu");
  const int node = 5 * 12 + 4;
  s.step(5);
  const Vec3f held = s.pipeline().state().x[node];
  s.toggle_pin(node);
  EXPECT_TRUE(s.model().pinned(node));
  s.step(20);
  EXPECT_EQ(s.pipeline().state().x[node], held);
  s.toggle_pin(node);
  EXPECT_FALSE(s.model().pinned(node));
  s.step(20);
  EXPECT_NE(s.pipeline().state().x[node], held);
  s.toggle_pin(0);  // a corner the scene pins: freed with the free nodes' mean inverse mass
  EXPECT_FALSE(s.model().pinned(0));
  s.step(5);
  EXPECT_NE(s.pipeline().state().x[0], s.model().rest_position[0]);
  s.reset();
  EXPECT_TRUE(s.model().pinned(0));
  EXPECT_EQ(s.steps(), 0);
  EXPECT_TRUE(bitwise_equal(s.pipeline().state(), rest_state(s.model())));
}

TEST(ViewerSession, DivergenceIsReportedNotCrashed) {
  Model m = small_cloth(8, 8);
  Params p = small_params();
  p.dt = 0.05f;  // far beyond the explicit bound of these springs
  Session s({std::move(m), p, pipelines().find("cpu"), Integrator::explicit_euler, {}});
  try {
    for (int k = 0; k < 200; ++k) s.step(10);
    FAIL() << "did not diverge";
  } catch (const DivergenceError& e) {
    EXPECT_NE(std::string(e.what()).find("diverged at step"), std::string::npos) << e.what();
  }
}

TEST(ViewerPicking, FindsTheNodeNearestTheCursorOnScreen) {
  const Model m = small_cloth(10, 10);
  const gl::Camera c = gl::framing(m, std::nullopt);
  const int w = 640, h = 480;
  auto pixel = [&](Vec3f x) { return c.pixel(x, w, h); };
  for (int node : {0, 37, 55, 99}) {
    const auto p = pixel(m.rest_position[node]);
    EXPECT_EQ(viewer::pick_node(m.rest_position, p[0] + 1, p[1] - 1, 4.0, pixel), node);
  }
  EXPECT_EQ(viewer::pick_node(m.rest_position, 2, 2, 4.0, pixel), -1) << "nothing in the corner";
  EXPECT_EQ(viewer::nearest_node(m.rest_position, m.rest_position[42] + Vec3f{0.01f, 0.f, -0.01f}), 42);
}

// The depth under the cursor gives the point of the surface there, on the node drawn there.
TEST(ViewerPicking, SurfaceUnderTheCursorIsWhereTheNodeIs) {
  DEFORMLAB_SKIP_IF_UNAVAILABLE(gl::unavailable_reason());
  const Model m = small_cloth(20, 20);
  gl::Renderer r(m, {.width = 400, .height = 300});
  r.draw(rest_state(m));
  const gl::Camera& c = r.camera();
  for (int node : {20 * 10 + 10, 20 * 3 + 15, 20 * 16 + 4}) {
    const Vec3f x = m.rest_position[node];
    const auto p = c.pixel(x, 400, 300);
    const std::optional<Vec3f> at = r.surface_at(p[0], p[1]);
    ASSERT_TRUE(at) << node;
    EXPECT_LT(norm(*at - x), 0.01f) << node << ": depth quantisation and the pixel's centre, 0.05 m spacing";
    EXPECT_EQ(viewer::nearest_node(m.rest_position, *at), node);
  }
  EXPECT_FALSE(r.surface_at(2, 2)) << "background";
}

TEST(ViewerCamera, RaysAndPixelsAgreeAndMovesKeepTheirShape) {
  const Model m = small_cloth(10, 10);
  gl::Camera c = gl::framing(m, std::nullopt);
  const int w = 800, h = 600;
  const auto [o, d] = c.ray(123.5, 456.25, w, h);
  const auto p = c.pixel(o + d * 1.7f, w, h);
  EXPECT_NEAR(p[0], 123.5, 1e-3);
  EXPECT_NEAR(p[1], 456.25, 1e-3);
  EXPECT_TRUE(std::isnan(c.pixel(o - d, w, h)[0])) << "behind the eye";

  const float dist = norm(c.eye - c.target);
  viewer::orbit(c, 0.7f, 0.3f);
  EXPECT_NEAR(norm(c.eye - c.target), dist, 1e-5 * dist);
  viewer::orbit(c, 0.f, 10.f);  // stops short of the pole
  EXPECT_GT(norm(cross(c.eye - c.target, c.up)), 0.01f * dist);
  const Vec3f target = c.target;
  const auto before = c.pixel(target, w, h);
  viewer::pan(c, 40.f, -25.f, h);
  const auto after = c.pixel(target, w, h);  // the old target follows the cursor
  EXPECT_NEAR(after[0] - before[0], 40.0, 1e-2);
  EXPECT_NEAR(after[1] - before[1], -25.0, 1e-2);
  viewer::zoom(c, 0.5f);
  EXPECT_NEAR(norm(c.eye - c.target), 0.5f * dist, 1e-5 * dist);
}

TEST(ViewerPlane, RayMeetsThePlaneOnIt) {
  const Vec3f hit = viewer::on_plane({0, 0, 5}, {0, 0.6f, -0.8f}, {1, 2, 1}, {0, 0, 1});
  EXPECT_NEAR(hit.z, 1.f, 1e-6f);
  EXPECT_NEAR(hit.y, 3.f, 1e-6f);
  const Vec3f along = viewer::on_plane({0, 0, 5}, {1, 0, 0}, {1, 2, 1}, {0, 0, 1});
  EXPECT_EQ(along, (Vec3f{1, 2, 1})) << "a ray along the plane keeps the point";
}

}  // namespace
}  // namespace deformlab::test
