// The deformlab subcommands. Each returns the process exit code: 0 success, 1 a run that
// failed (divergence, a backend error), 2 bad input (nothing written).
#pragma once
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace deformlab::app {

struct RunArgs {
  std::vector<std::string> argv;  // the whole command, for the manifest
  std::optional<std::string> experiment, scene, pipeline, integrator, grid, lattice, compare;
  std::vector<std::string> options;  // pipeline options, NAME=VALUE
  std::optional<int> steps, check_every;
  std::optional<double> dt, threshold;
  bool until_converged = false;
  std::optional<std::string> out;
  std::optional<int> frames;     // render a frame every N steps into DIR/frames (GL builds)
  std::optional<int> energy;     // the state's energies every N steps into DIR/energy.csv
  std::optional<int> gl_device;  // EGL device index for the GL context (GL builds)
  bool trace = false;            // also write trace.json (Chrome trace of the spans)
  bool no_state = false;         // leave out state.ply
  std::optional<double> warmup_ms;  // untimed steps first (default: kGpuWarmUpMs on GPU pipelines)
};

struct ViewArgs {
  RunArgs run;  // the scene, pipeline and stepping flags `run` shares
  int steps_per_frame = 10;
  std::string size = "1280x800";  // the window, WxH
  std::optional<std::string> script, save_script, record, summary;
  std::optional<double> seconds;  // with --record: seconds of video, then quit
  std::optional<int> max_frames;  // quit after this many frames
};

struct CalibrateArgs {
  std::vector<std::string> argv;
  std::optional<std::string> out;  // JSON file (default: stdout)
};

struct MeshArgs {
  std::optional<std::string> experiment, scene, model;  // model: one of the experiment's sweep's mesh models
  std::string out;                                       // a .msh file
};

struct ExperimentArgs {
  std::vector<std::string> argv;
  std::string file;  // a path, or the name of a built-in experiment (table1, quick, ...)
  std::optional<std::string> out;
  bool report_only = false;
  std::optional<int> max_size;  // leave out sizes above this (a later run can add them)
  std::optional<std::string> calibration;  // a `deformlab calibrate` JSON for the manifest
};

// Runs `body`, turning an exception into one line on stderr and an exit code: 2 for
// std::invalid_argument (bad input), 1 for anything else.
int report_errors(const std::function<int()>& body);

int run_command(const RunArgs& a);
int experiment_command(const ExperimentArgs& a);
int list_command();
int calibrate_command(const CalibrateArgs& a);
int mesh_command(const MeshArgs& a);
int view_command(const ViewArgs& a);

// This device's calibration (interop/calibrate.hpp) with the build, machine and `argv`;
// throws std::invalid_argument where it cannot be measured (no CUDA, no GL, ...).
nlohmann::json measure_calibration(const std::vector<std::string>& argv);

}  // namespace deformlab::app
