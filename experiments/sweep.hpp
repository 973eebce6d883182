// Sweeps: an experiment file's "sweep" names grid sizes x pipelines x integrators x
// pipeline option sets (tile shapes, interop modes, force/update backends). The runner
// times every cell, skips cells already done, bounds each cell's time, records "n/a" with
// the reason where a cell is cut or cannot run, and writes each result atomically.
#pragma once
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/pipeline.hpp"
#include "experiment.hpp"

namespace deformlab {

struct Sweep {
  std::vector<int> sizes;                     // n for an n x n cloth (or n^3 lattice)
  std::vector<std::string> pipelines;
  std::vector<std::string> integrators;       // default: the experiment's integrator
  std::vector<PipelineOptions> option_sets;   // each pipeline runs those whose names it reads
  int warmup = 5;                             // untimed steps per cell
  int steps = 10;                             // steps per timed batch
  int repetitions = 5;                        // timed batches; the cell reports their median
  double cell_limit_s = 120;                  // a cell expected to take longer is cut (n/a)
  std::string time = "update";                // "update", or "frame": update + render
  std::string paper_table;                    // "table1", "table2", "table3" or "" (report)
  int frames = 4;                             // frames of the experiment's scene for the report (0: none)
};

struct Cell {
  int size = 0;
  std::string pipeline, integrator;
  PipelineOptions options;
  std::string id() const;  // file-name safe, unique within a sweep
};

std::optional<Sweep> parse_sweep(const nlohmann::json& experiment, const std::string& where);
std::vector<Cell> cells(const Sweep& s);

struct SweepProgress {
  int done = 0, total = 0, skipped = 0;
  double elapsed_s = 0;
};

struct SweepOptions {
  std::function<void(const Cell&, const nlohmann::json& result, const SweepProgress&)> on_cell;
  // This device's ceilings (`deformlab calibrate`'s JSON) for the manifest and the report;
  // null keeps the calibration the folder's manifest already has.
  nlohmann::json calibration;
};

// Runs every cell not yet measured in `dir`/cells/ (n/a cells are tried again) and returns
// the number it ran. Writes `dir`/manifest.json (experiment, build, machine, calibration) first;
// then, unless `dir`/frames/ exists, renders the sweep's frames there (render_frames) and
// records them, or why there are none, as the manifest's "frames".
int run_sweep(const Experiment& x, const Sweep& s, const std::filesystem::path& dir, const SweepOptions& o,
              const nlohmann::json& command);

// The last model built, reused by the next cell of the same size.
struct ModelCache {
  int size = 0;
  std::unique_ptr<Model> model;
};

// One cell's result: {"status": "ok", "median_ms", ..., "stages": [{"name", "median_ms",
// "clock", "per_step"}] for pipelines that time their stages} or {"status": "n/a", "reason"}.
nlohmann::json run_cell(const Experiment& x, const Sweep& s, const Cell& c, ModelCache& cache);

// Frames of the experiment's own scene (its model, not a sweep size) on the best pipeline
// here, `s.frames` of them spread over the drag (or min_steps), drawn at 512 x 512 into
// `dir`/frames/ (written to a temporary folder, then renamed). Returns what was rendered,
// or {"unavailable": why} (no OpenGL, a run that failed).
nlohmann::json render_frames(const Experiment& x, const Sweep& s, const std::filesystem::path& dir);

// Reads every cell result in `dir`/cells/.
std::vector<nlohmann::json> load_cells(const std::filesystem::path& dir);

// `dir`/manifest.json, or null when there is none or it is not JSON.
nlohmann::json read_manifest(const std::filesystem::path& dir);
// Throws std::invalid_argument when `dir` holds the results of another experiment than `name`.
void require_same_experiment(const std::filesystem::path& dir, const std::string& name);

// Writes `text` to `file` through a temporary file and a rename.
void write_atomically(const std::filesystem::path& file, const std::string& text);

}  // namespace deformlab
