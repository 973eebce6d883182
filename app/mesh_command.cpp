// `deformlab mesh`: the mesh a scene generates or fills with Gmsh, written to a .msh file that a
// scene can name as its model's "file", so that runs share one mesh.
#include <chrono>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "core/number_text.hpp"
#include "core/one_line.hpp"
#include "experiments/output.hpp"
#include "experiments/sweep_models.hpp"
#include "mesh/load.hpp"
#include "mesh/scene_model.hpp"

namespace deformlab::app {
namespace {

// Whether Gmsh makes the model's mesh: a shape it generates or a surface it fills.
bool makes_mesh(const ModelSpec& m) {
  return m.topology == Topology::general && (m.mesh.generate || m.mesh.fill);
}

// The experiment's scene, with --scene and, for a sweep of mesh models, the --model named.
Scene chosen_scene(const MeshArgs& a) {
  Experiment x = a.experiment ? load_experiment_by_name(*a.experiment) : default_experiment();
  if (a.scene) x.scene = load_scene(*a.scene);
  const auto sweep = parse_sweep(x.raw, x.name);
  std::string names;
  for (const auto& m : sweep ? sweep->models : std::vector<SweepModel>{}) {
    if (a.model && m.name == *a.model) return model_cell_scene(x, *sweep, Cell{.model = m.name});
    names += (names.empty() ? "" : ", ") + m.name;
  }
  const std::string whose = "experiment '" + x.name + "'";
  if (!a.model) {
    if (!names.empty())
      throw std::invalid_argument(whose + " sweeps mesh models: name one with --model (" + names + ")");
    return x.scene;
  }
  if (names.empty()) throw std::invalid_argument("--model '" + *a.model + "': " + whose + " sweeps no mesh models");
  throw std::invalid_argument("--model '" + *a.model + "': " + whose + " has no such model (its models: " + names + ")");
}

// A file already at `out` is replaced only where it is a Gmsh mesh and not the one the model
// is filled from.
void require_replaceable_mesh(const std::string& out, const MeshSpec& ms) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  if (!ms.file.empty() && fs::equivalent(out, ms.file, ec))
    throw std::invalid_argument("--out '" + out + "' is the mesh file the model is filled from (model.file): name "
                                "another file");
  // (A pipe would block the reading of its start; the written mesh is renamed over what is there.)
  if (!fs::is_regular_file(out, ec))
    throw std::invalid_argument("--out '" + out + "' is not a regular file, which this would replace: remove it or "
                                "name another file");
  if (!starts_as_gmsh_mesh(out))
    throw std::invalid_argument("--out '" + out + "' holds a file that is not a Gmsh mesh (it does not start with "
                                "$MeshFormat or another section Gmsh reads as a mesh), which this would replace: "
                                "remove it or name another file");
}

// The scene as it names the written mesh, in place of "generate" or of the fill and placement
// already applied.
Scene on_written_mesh(Scene s, const std::string& out) {
  MeshSpec& ms = s.model.mesh;
  if (ms.fill) ms = MeshSpec{.density = ms.density, .order = ms.order, .seed = ms.seed};
  ms.generate.reset();
  ms.file = out;
  return s;
}

}  // namespace

int mesh_command(const MeshArgs& a) {
  return report_errors([&] {
    namespace fs = std::filesystem;
    if (fs::path(a.out).extension() != ".msh")
      throw std::invalid_argument("--out '" + a.out + "': expected a file name ending in .msh");
    require_file_target(a.out, "--out");
    Scene scene = chosen_scene(a);
    scene.model.mesh.order = NodeOrder::file;  // written as Gmsh makes it: a run orders the nodes it reads
    const MeshSpec& ms = scene.model.mesh;
    if (!makes_mesh(scene.model))
      throw std::invalid_argument("the scene's model (" + describe(scene.model) +
                                  ") is neither generated nor filled: only a model's \"generate\" or \"fill\" "
                                  "makes a mesh to write");
    require_replaceable_mesh(a.out, ms);
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh m = ms.generate ? generated_mesh(*ms.generate, a.out) : filled_mesh(ms, a.out);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const char* naming = ms.generate ? "before the model's scale and transform): name it as the model's \"file\" in "
                                       "place of \"generate\""
                                     : "after the model's scale and transform): name it as the model's \"file\" with "
                                       "no fill, scale or transform (\"fill\": \"none\", \"scale\": 1, "
                                       "\"transform\": {} where the scene sets them)";
    std::cout << "deformlab mesh: " << (ms.generate ? describe(*ms.generate) : describe(scene.model)) << "\n  "
              << counted(std::int64_t(m.position.size()), "node") << ", "
              << (m.volume() ? counted(std::int64_t(m.tetrahedron.size()), "tetrahedron", "tetrahedra")
                             : counted(std::int64_t(m.triangle.size()), "triangle"))
              << ", made and written in " << duration_text(s) << " (host clock)\n"
              << "  wrote " << a.out << " (binary MSH 4.1, " << naming << " and every run reads this mesh\n";
    // The mesh is the command's output whatever the rest of the scene; what a run would refuse is said.
    std::cout << "  reading it back to check the scene's pins and drag on it" << std::endl;
    const auto t1 = std::chrono::steady_clock::now();
    try {
      check_mesh_file(on_written_mesh(scene, a.out));
      std::cout << "  checked in "
                << duration_text(std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count())
                << " (host clock)\n";
    } catch (const std::invalid_argument& e) {
      std::cerr << "deformlab: note: a run of this scene on the mesh would refuse it: " << one_line(e.what()) << "\n";
    }
    return 0;
  });
}

}  // namespace deformlab::app
