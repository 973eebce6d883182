// Scene and experiment files: every key read, unknown keys and bad values named.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "core/json_file.hpp"
#include "core/scene.hpp"
#include "experiments/experiment.hpp"
#include "mesh/scene_model.hpp"

namespace deformlab {
namespace {

using nlohmann::json;

std::string error_of(const std::string& text) {
  try {
    parse_experiment(text, "x.json");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, BuiltInExperimentIsThePapersDrag) {
  const Experiment x = default_experiment();
  EXPECT_EQ(x.name, "paper-drag");
  EXPECT_EQ(x.scene.model.nx, 128);
  EXPECT_EQ(x.scene.model.ny, 128);
  EXPECT_EQ(x.scene.model.pins, PinSet::top_corners);
  EXPECT_FLOAT_EQ(x.scene.params.threshold, 0.001f);
  EXPECT_TRUE(x.until_converged);
  const Model m = build_model(x.scene);
  const Params p = resolve_params(x.scene, m);
  EXPECT_EQ(p.drag.node, 64 * 128 + 64);
  // Offsets in the file become positions relative to the node's rest position.
  EXPECT_EQ(p.drag.path.back().position, m.rest_position[p.drag.node]);
  EXPECT_TRUE(m.pinned(0) && m.pinned(127));
  // The file's first key is at 0.5 s, 0.2 m down: the handle starts at the node's rest position
  // and gets there linearly, so the node does not jump at the first step.
  ASSERT_EQ(p.drag.path.size(), 5u);
  EXPECT_EQ(p.drag.path[0].t, 0.f);
  EXPECT_EQ(p.drag.target(0.0), m.rest_position[p.drag.node]);
  EXPECT_NEAR(p.drag.target(0.25).y, m.rest_position[p.drag.node].y - 0.1f, 1e-6f);
  EXPECT_NEAR(p.drag.target(0.5).y, m.rest_position[p.drag.node].y - 0.2f, 1e-6f);
}

TEST(Scene, ReadsEveryKeyAndRoundTrips) {
  Scene s;
  apply_json(s, json::parse(R"({
    "model": {"type": "lattice", "size": [4, 5, 6], "spacing": 0.1, "node_mass": 0.02,
              "stiffness": {"structural": 10, "shear": 20, "flexion": 30}, "damping": 0.5, "pins": [1, 2]},
    "dt": 0.004, "gravity": [0, -1, 0], "damping": 0.3, "wind": [1, 0, 0], "ground": -2,
    "spheres": [{"center": [0, 1, 0], "radius": 0.5}],
    "drag": {"node": 7, "mode": "spring", "stiffness": 50, "path_is": "position", "path": [[0, 1, 2, 3]]},
    "threshold": 0.01, "min_steps": 3, "max_steps": 99, "check_every": 4, "runaway_factor": 2})"), "s");
  EXPECT_EQ(s.model.topology, Topology::lattice);
  EXPECT_EQ(s.model.nz, 6);
  EXPECT_EQ(s.model.material.stiffness[2], 30.f);
  EXPECT_EQ(s.model.material.damping[1], 0.5f);
  ASSERT_EQ(s.model.pin_list.size(), 2u);
  EXPECT_EQ(s.model.pin_list[1].index, 2);
  EXPECT_EQ(*s.params.ground, -2.f);
  EXPECT_TRUE(s.params.drag.as_spring);
  EXPECT_EQ(s.params.check_every, 4);
  // Written as the floats' shortest decimals, as the file gave them, where those read back as
  // the same floats: 7.0385307e-26's, 7.038531e-26, read as a double, does not.
  EXPECT_EQ(to_json(s)["dt"].get<double>(), 0.004);
  EXPECT_EQ(to_json(s)["model"]["node_mass"].get<double>(), 0.02);
  Scene w;
  apply_json(w, json::parse(R"({"wind": [7.0385307e-26, 0, 0]})"), "w");
  EXPECT_EQ(float(to_json(w)["wind"][0].get<double>()), w.params.wind.x);
  Scene t;
  apply_json(t, to_json(s), "t");
  EXPECT_EQ(to_json(t), to_json(s));
  const Model m = build_model(t);
  EXPECT_TRUE(m.pinned(1) && m.pinned(2) && !m.pinned(0));
  EXPECT_EQ(resolve_params(t, m).drag.path[0].position, (Vec3f{1, 2, 3}));
}

// A layer gives a grid's spacing or its width and replaces the other; the scene as recorded
// names the one that sets the spacing.
TEST(Scene, ALayersSpacingOrWidthReplacesTheOther) {
  Scene s;
  apply_json(s, json::parse(R"({"model": {"size": [5, 3], "spacing": 0.1}})"), "a");
  EXPECT_NEAR(build_model(s).rest_position[4].x - build_model(s).rest_position[0].x, 0.4f, 1e-6f);
  EXPECT_EQ(to_json(s)["model"].count("width"), 0u);
  apply_json(s, json::parse(R"({"model": {"width": 2}})"), "b");
  EXPECT_NEAR(build_model(s).rest_position[4].x - build_model(s).rest_position[0].x, 2.f, 1e-6f);
  EXPECT_EQ(to_json(s)["model"].count("spacing"), 0u);
  apply_json(s, json::parse(R"({"model": {"spacing": 0.25}})"), "c");
  EXPECT_NEAR(build_model(s).rest_position[4].x - build_model(s).rest_position[0].x, 1.f, 1e-6f);
  Scene t;
  apply_json(t, to_json(s), "t");
  EXPECT_EQ(to_json(t), to_json(s));
}

// A layer that makes the model a lattice without a size takes the default cube, not the cloth's
// rows with one layer; a lattice's own size stays through a later layer that names the type again.
TEST(Scene, ALatticeWithoutASizeIsTheDefaultCube) {
  Scene s;
  apply_json(s, json::parse(R"({"model": {"type": "lattice"}})"), "a");
  EXPECT_EQ(s.model.nx, kDefaultLatticeSide);
  EXPECT_EQ(s.model.ny, kDefaultLatticeSide);
  EXPECT_EQ(s.model.nz, kDefaultLatticeSide);
  apply_json(s, json::parse(R"({"model": {"type": "lattice", "size": [4, 5, 6]}})"), "b");
  apply_json(s, json::parse(R"({"model": {"type": "lattice"}})"), "c");
  EXPECT_EQ(std::tuple(s.model.nx, s.model.ny, s.model.nz), std::tuple(4, 5, 6));
}

// A mesh's masses come from density or node_mass: a later layer's replaces the earlier's, and
// the scene as JSON reads back the same.
TEST(Scene, ALayersDensityOrNodeMassReplacesTheOther) {
  Scene s;
  apply_json(s, json::parse(R"({"model": {"type": "mesh", "file": "m.obj", "density": 1000}})"), "a");
  EXPECT_EQ(s.model.mesh.density, 1000.f);
  EXPECT_EQ(to_json(s)["model"].count("node_mass"), 0u);
  Scene t;
  apply_json(t, to_json(s), "t");
  EXPECT_EQ(to_json(t), to_json(s));
  apply_json(s, json::parse(R"({"model": {"node_mass": 0.02}})"), "b");
  EXPECT_EQ(s.model.mesh.density, 0.f);
  EXPECT_EQ(s.model.material.node_mass, 0.02f);
  EXPECT_EQ(to_json(s)["model"].count("density"), 0u);
}

// A max_steps alone below the min_steps a scene takes is taken (a fixed-step run does not
// use min_steps; a convergence run says its stop rule starts too late); an object that gives
// both the wrong way round is refused, whatever the keys' order.
TEST(Scene, MinStepsAboveMaxStepsOnlyWhereOneObjectGivesBoth) {
  Scene s;
  apply_json(s, json::parse(R"({"max_steps": 50})"), "a");
  EXPECT_EQ(s.params.min_steps, 100);
  EXPECT_EQ(s.params.max_steps, 50);
  EXPECT_THROW(apply_json(s, json::parse(R"({"max_steps": 40, "min_steps": 60})"), "c"), std::invalid_argument);
  apply_json(s, json::parse(R"({"min_steps": 20, "max_steps": 40})"), "d");
  EXPECT_EQ(s.params.min_steps, 20);
}

// A grid one node wide spans `width` along its next axis with more than one node, as a wider
// one does along x: a 1 x 64 cloth is 1 m long, as a 64 x 1 one is 1 m wide.
TEST(Scene, AGridOneNodeWideSpansItsWidthAlongItsLength) {
  for (const auto& [size, axis] : {std::pair{"[64, 1]", 0}, std::pair{"[1, 64]", 2}}) {
    Scene s;
    apply_json(s, json::parse(std::string(R"({"model": {"width": 1, "size": )") + size + "}}"), "a");
    const Model m = build_model(s);
    const auto& p = m.rest_position;
    EXPECT_NEAR(std::fabs(p.back()[axis] - p.front()[axis]), 1.f, 1e-6f) << size;
  }
  Scene lattice;
  apply_json(lattice, json::parse(R"({"model": {"type": "lattice", "width": 1, "size": [1, 5, 3]}})"), "b");
  const Model m = build_model(lattice);
  EXPECT_NEAR(m.rest_position.back()[1] - m.rest_position.front()[1], 1.f, 1e-6f) << "along y";
}

// "fill": "none" fills nothing: a generated mesh takes it (it may undo a base's fill).
TEST(Scene, AGeneratedMeshTakesFillNone) {
  Scene s;
  apply_json(s, json::parse(R"({"model": {"type": "mesh", "pins": "none", "fill": "none",
                                "generate": {"shape": "sheet", "size": [1, 1], "cell_size": 0.25}}})"), "a");
  EXPECT_FALSE(s.model.mesh.fill);
  EXPECT_TRUE(s.model.mesh.generate.has_value());
}

// The paper's largest cloth (16384 nodes across 1 m, at 1 m) keeps floats within a hundredth of
// its spacing (0.2%): built here as a strip of that spacing. Lifted to 1e4 m it is refused.
TEST(Scene, FloatsResolveThePapersLargestClothButNotOneFarAway) {
  Scene s = default_experiment().scene;
  s.model.nx = 16384;
  s.model.ny = 2;
  s.model.pins = PinSet::none;
  EXPECT_NO_THROW(build_model(s));
  s.model.height = 1e4f;
  try {
    build_model(s);
    ADD_FAILURE() << "built";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("it lies up to 1e+04 m from the origin, where floats are 0.000977 m apart"),
              std::string::npos) << e.what();
  }
}

// A JSON file is read up to its cap whatever its size says: one of the cap's bytes is read, one
// byte more is refused.
TEST(Scene, AJsonFileOverTheCapIsRefused) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / ("deformlab-cap-" + std::to_string(::getpid()) + ".json");
  std::string text(std::size_t(kMaxJsonFileBytes), ' ');
  text.front() = '1';
  std::ofstream(file, std::ios::binary) << text;
  EXPECT_EQ(read_json_file(file.string(), "scene file"), 1);
  std::ofstream(file, std::ios::binary | std::ios::app) << ' ';
  try {
    read_json_file(file.string(), "scene file");
    ADD_FAILURE() << "read";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "scene file '" + file.string() + "' holds more than the 16 MiB a JSON file may have");
  }
  fs::remove(file);
}

TEST(Scene, ErrorsNameTheKey) {
  EXPECT_NE(error_of(R"({"scene": {"dtt": 1}})").find("x.json.scene.dtt: unknown key"), std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {"dt": "fast"}})").find("x.json.scene.dt: expected a number"), std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {"model": {"size": [0]}}})").find("x.json.scene.model.size"), std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {"model": {"pins": "corners"}}})").find("pins"), std::string::npos);
  EXPECT_NE(error_of(R"({"pipeline": 3})").find("x.json.pipeline: expected a string"), std::string::npos);
  EXPECT_NE(error_of("{not json").find("not valid JSON"), std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {"drag": {"path": [[0, 1, 2]]}}})").find("[t, x, y, z]"), std::string::npos);
  // Past 64 bits: out of range, not wrapped round to a negative count.
  EXPECT_NE(error_of(R"({"scene": {"max_steps": 18446744073709551615}})").find("x.json.scene.max_steps: integer out of range"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {"min_steps": 9223372036854775808}})").find("x.json.scene.min_steps: integer out of range"),
            std::string::npos);
}

// A key that would do nothing where it is given is refused, and the writer leaves it out, so a
// scene as recorded reads back.
TEST(Scene, KeysWithNoEffectAreRefusedAndNotWritten) {
  const std::string mesh = R"("model": {"type": "mesh", "pins": "none", "file": "m.obj")";
  EXPECT_NE(error_of(R"({"scene": {)" + mesh + R"(, "cell_size": 0.1}}})").find("scene.model.cell_size: the cell size of a "
                                                                               "tetrahedral fill"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {)" + mesh + R"(, "order": "rcm", "seed": 3}}})").find("scene.model.seed: seeds the "
                                                                                        "shuffled order"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {)" + mesh + R"(, "stiffness": {"shear": 3}}}})").find("scene.model.stiffness.shear: "
                                                                                        "a mesh has no shear springs"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {)" + mesh + R"(, "damping": {"flexion": 1, "shear": 3}}}})").find("damping.shear"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"scene": {"drag": {"node": 3, "stiffness": 9, "path": [[0, 0, 0, 0]]}}})").find(
                "scene.drag.stiffness: the spring mode's"),
            std::string::npos);
  // Where they act, the same keys are read: a fill's cell size, a shuffle's seed, one number
  // for every kind of spring, a spring handle's stiffness.
  for (const char* ok : {R"(, "fill": "tetrahedra", "cell_size": 0.1)", R"(, "order": "shuffled", "seed": 3)",
                         R"(, "stiffness": 7, "damping": {"structural": 1, "flexion": 2})"})
    EXPECT_EQ(error_of(R"({"scene": {)" + mesh + ok + "}}}"), "") << ok;
  EXPECT_EQ(error_of(R"({"scene": {"drag": {"node": 3, "mode": "spring", "stiffness": 9, "path": [[0, 0, 0, 0]]}}})"), "");
  Scene s;
  apply_json(s, json::parse("{" + mesh + R"(, "stiffness": 7}, "drag": {"node": 3, "path": [[0, 0, 0, 0]]}})"), "s", ".");
  const json j = to_json(s);
  EXPECT_FALSE(j["model"]["stiffness"].contains("shear"));
  EXPECT_FALSE(j["model"].contains("seed") || j["model"].contains("cell_size") || j["drag"].contains("stiffness"));
  Scene t;
  apply_json(t, j, "t", ".");
  EXPECT_EQ(to_json(t), j);
}

TEST(Scene, ResolveRejectsBadValues) {
  Scene s;
  s.model.nx = s.model.ny = 4;
  s.params.dt = -1.f;
  const Model m = build_model(s);
  EXPECT_THROW(resolve_params(s, m), std::invalid_argument);
  s.params.dt = 0.001f;
  apply_json(s, json::parse(R"({"drag": {"node": 99, "path": [[0, 0, 0, 0]]}})"), "s");
  EXPECT_THROW(resolve_params(s, m), std::invalid_argument);
  // Keyframes out of order are refused while reading, with their key path.
  EXPECT_THROW(apply_json(s, json::parse(R"({"drag": {"node": 3, "path": [[1, 0, 0, 0], [0.5, 0, 0, 0]]}})"), "s"),
               std::invalid_argument);
}

}  // namespace
}  // namespace deformlab
