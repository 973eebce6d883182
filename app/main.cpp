// deformlab: GPU mass-spring deformation pipelines, measured against a CPU reference.
#include <CLI/CLI.hpp>
#include <iostream>

#include "commands.hpp"
#include "core/interrupt.hpp"
#include "core/one_line.hpp"
#include "command_line.hpp"
#include "experiments/experiment.hpp"

namespace deformlab::app {

int report_errors(const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::invalid_argument& e) {
    std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
    return 2;
  } catch (const Interrupted& e) {
    std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
    return 128 + e.signal;
  } catch (const std::bad_alloc&) {  // a size the checks before allocating did not refuse
    std::cerr << "deformlab: error: out of memory (host or device): the model or its outputs do not fit this machine\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
    return 1;
  }
}

}  // namespace deformlab::app

int main(int argc, char** argv) {
  using deformlab::app::RunArgs;
  CLI::App cli{"deformlab: mass-spring deformation on CPU, CUDA and GLSL pipelines", "deformlab"};
  cli.require_subcommand(1);
  RunArgs a;
  for (int i = 0; i < argc; ++i) a.argv.emplace_back(argv[i]);

  auto* run = cli.add_subcommand("run", "Run an experiment (with no options: the paper's drag experiment)");
  run->add_option("--experiment", a.experiment, "Experiment file or built-in name, e.g. table2 (default: paper-drag)");
  run->add_option("--scene", a.scene, "Scene file in place of the experiment's scene (absent keys: the defaults)");
  run->add_option("--pipeline,-p", a.pipeline, "Pipeline name ('deformlab list'), or 'best'");
  run->add_option("--integrator,-i", a.integrator, "Integrator name ('deformlab list')");
  auto* grid = run->add_option("--grid", a.grid, "Cloth grid size WxH, e.g. 128x128");
  run->add_option("--lattice", a.lattice, "Lattice size WxHxD, e.g. 8x8x8")->excludes(grid);
  run->add_option("--steps", a.steps, "Number of steps (with --until-converged: the most steps)");
  run->add_flag("--until-converged", a.until_converged, "Stop once no node moves more than the threshold in a step");
  run->add_option("--dt", a.dt, "Time step, s");
  run->add_option("--threshold", a.threshold, "Convergence threshold, m per step");
  run->add_option("--check-every", a.check_every, "Steps between convergence and divergence checks");
  run->add_option("--option", a.options, "Pipeline option NAME=VALUE (repeatable; 'deformlab list' names them)");
  run->add_option("--compare", a.compare, "Also run the double-precision pipeline 'reference' and report the error");
  run->add_option("--out,-o", a.out, "Output folder (default: runs/<experiment name>)");
  run->add_option("--frames", a.frames, "Write a PNG frame every N steps and the final one into DIR/frames (OpenGL)");
  run->add_option("--energy", a.energy,
                  "Write the state's energies at the start, every N steps and the last into DIR/energy.csv (each "
                  "read back from the device)")
      ->check(deformlab::app::whole_in(1, std::numeric_limits<int>::max()));
  run->add_option("--gl-device", a.gl_device, "EGL device index for OpenGL (default: the first CUDA-capable one)")
      ->check(deformlab::app::whole_in(0, 1023));
  run->add_flag("--trace", a.trace, "Also write trace.json: the steps' stages as a Chrome trace (open in Perfetto)");
  run->add_option("--warmup-ms", a.warmup_ms,
                  "Untimed steps from rest for at least this long before the run, which then starts from rest "
                  "(default: 1000 on pipelines with a GPU pass, 0 on CPU ones)");
  run->add_flag("--no-state", a.no_state, "Leave out state.ply (50 bytes a node: 13 GB for a 16384x16384 cloth)");

  deformlab::app::ExperimentArgs ex;
  ex.argv = a.argv;
  auto* experiment = cli.add_subcommand("experiment", "Run an experiment's sweep (resumable) and write its report");
  const std::string sweeps = deformlab::builtin_experiment_names(deformlab::Builtins::sweeps);
  experiment->add_option("file", ex.file, "Experiment file, or a built-in name (" + sweeps + ")")->required();
  experiment->add_option("--out,-o", ex.out, "Results folder (default: runs/<experiment name>)");
  experiment->add_option("--max-size", ex.max_size, "Leave out grid sizes above this for now (cells resume later)")
      ->check(deformlab::app::whole_in(1, 1 << 20));
  experiment->add_flag("--report-only", ex.report_only, "Only rewrite the report from the results folder");
  experiment->add_option("--calibration", ex.calibration,
                         "Calibration JSON (from `deformlab calibrate --out`) to record in the manifest and show "
                         "stages against (default: the folder's, else measured now where CUDA and OpenGL are both "
                         "available)");

  auto* list = cli.add_subcommand("list", "List pipelines and integrators, and which run here");

  deformlab::app::ViewArgs v;
  v.run.argv = a.argv;
  auto* view = cli.add_subcommand("view", "Open the simulation in a window: pick and drag nodes, switch stages live");
  view->add_option("--experiment", v.run.experiment, "Experiment file or built-in name (default: paper-drag)");
  view->add_option("--scene", v.run.scene, "Scene file in place of the experiment's scene (absent keys: the defaults)");
  view->add_option("--pipeline,-p", v.run.pipeline, "Pipeline name ('deformlab list'), or 'best'");
  view->add_option("--integrator,-i", v.run.integrator, "Integrator name ('deformlab list')");
  auto* view_grid = view->add_option("--grid", v.run.grid, "Cloth grid size WxH, e.g. 128x128");
  view->add_option("--lattice", v.run.lattice, "Lattice size WxHxD, e.g. 8x8x8")->excludes(view_grid);
  view->add_option("--dt", v.run.dt, "Time step, s");
  view->add_option("--option", v.run.options, "Pipeline option NAME=VALUE (repeatable)");
  view->add_option("--steps-per-frame", v.steps_per_frame, "Steps between drawn frames (default 10)");
  view->add_option("--size", v.size, "Size of the 3D view WxH in pixels (the panel adds its width; default 1280x800)");
  view->add_option("--script", v.script, "Replay the input events of a script file (see --save-script)");
  view->add_option("--save-script", v.save_script, "Save this session's input events as a script file at the end");
  view->add_option("--record", v.record, "Record the window as an MP4 (H.264, 30 frames a second, one per frame drawn)");
  view->add_option("--seconds", v.seconds, "With --record: record this many seconds of video, then quit");
  view->add_option("--max-frames", v.max_frames, "Quit after this many frames");
  view->add_option("--summary", v.summary, "Write a JSON summary of the session (drags, switches, screenshots) at the end");

  deformlab::app::CalibrateArgs cal;
  cal.argv = a.argv;
  auto* calibrate = cli.add_subcommand(
      "calibrate", "Measure this device's ceilings (copy, transform feedback, compute, interop hand-offs) as JSON; "
                   "needs CUDA and OpenGL on one GPU");
  calibrate->add_option("--out,-o", cal.out, "JSON file to write (default: standard output)");

  deformlab::app::MeshArgs mesh_args;
  auto* mesh = cli.add_subcommand("mesh", "Write the mesh a scene generates or fills (its model's \"generate\" or \"fill\") to a Gmsh .msh file");
  mesh->add_option("--experiment", mesh_args.experiment, "Experiment file or built-in name (default: paper-drag)");
  mesh->add_option("--scene", mesh_args.scene, "Scene file in place of the experiment's scene (absent keys: the defaults)");
  mesh->add_option("--model", mesh_args.model, "One of the mesh models the experiment's sweep names");
  mesh->add_option("--out,-o", mesh_args.out, "The .msh file to write")->required();

  deformlab::app::decimal_numbers_only(cli);
  if (argc > 1 && std::string(argv[1]) == "help") {
    std::cout << cli.help();
    return deformlab::app::flush_output("deformlab", 0);
  }
  if (const int code = deformlab::app::parse_command_line(cli, argc, argv); code >= 0)
    return deformlab::app::flush_output("deformlab", code);  // help, or a parse error
  deformlab::app::cap_openmp_threads("deformlab");
  int code = 2;
  if (*run) code = deformlab::app::run_command(a);
  else if (*experiment) code = deformlab::app::experiment_command(ex);
  else if (*list) code = deformlab::app::list_command();
  else if (*calibrate) code = deformlab::app::calibrate_command(cal);
  else if (*view) code = deformlab::app::view_command(v);
  else if (*mesh) code = deformlab::app::mesh_command(mesh_args);
  return deformlab::app::flush_output("deformlab", code);
}
