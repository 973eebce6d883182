// Sweeps: an experiment file's "sweep" names grid sizes (or mesh models x node orders) x
// pipelines x integrators x pipeline option sets (tile shapes, interop modes, force/update backends). The runner
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
#include "core/scene.hpp"
#include "experiment.hpp"

namespace deformlab {

// A cell's first two steps, the second timed, bound its time before it is measured (the first
// carries one-time costs: shader compiles, first touches of the buffers); a sweep's warm-up
// counts them.
constexpr int kBoundingSteps = 2;

// A mesh model of a sweep: a scene "model" object applied over the experiment's model.
struct SweepModel {
  std::string name;  // letters, digits, '-', '_' and '.'
  nlohmann::json model;
};

struct Sweep {
  std::vector<int> sizes;                     // n for an n x n cloth (or n^3 lattice)
  bool lattice = false;                       // the experiment's model is a lattice (its "scene")
  std::vector<SweepModel> models;             // or mesh models (exactly one of the two)
  std::vector<std::string> orders;            // node orders of the models (empty: each model's own)
  std::vector<std::string> pipelines;
  std::vector<std::string> integrators;       // default: the experiment's integrator
  std::vector<PipelineOptions> option_sets;   // each pipeline runs those whose names it reads
  int warmup = 5;                             // untimed steps per cell, the kBoundingSteps among them
  int steps = 10;                             // steps per timed batch
  int repetitions = 5;                        // timed batches; the cell reports their median
  double cell_limit_s = 120;                  // a cell expected to take longer is cut (n/a)
  std::string time = "update";                // "update", or "frame": update + render
  std::string paper_table;                    // "table1", "table2", "table3" or "" (report)
  int frames = 4;                             // frames of the experiment's scene for the report (0: none)
  std::string where;                          // the experiment as named (file or built-in): errors' key paths
};

struct Cell {
  int size = 0;  // a grid size, or 0 for a mesh model
  std::string pipeline, integrator;
  PipelineOptions options;
  std::string model;  // a mesh model's name
  std::string order;  // its node order ("": the model's own)
  std::string id() const;     // file-name safe, unique within a sweep
  std::string label(bool lattice) const;  // "64²" ("16³" on a lattice), "sheet-1m rcm"
};

// Grid size n as a label: "n²" for a cloth, "n³" for a lattice.
std::string size_label(int n, bool lattice);

// Sizes `ms`, a grid or lattice, to the cell size n (n x n, or n^3).
void size_model(ModelSpec& ms, int n);

std::optional<Sweep> parse_sweep(const nlohmann::json& experiment, const std::string& where);
// Throws std::invalid_argument naming the first grid size whose spacing or float resolution is
// bad input (grid_spacing, from the spec: no model built), or the experiment's own scene where
// the sweep draws its frames; for every size, before the sizes are cut to --max-size.
void require_size_grids(const Experiment& x, const Sweep& s);
// Throws std::invalid_argument naming the first grid size on which the experiment's scene is bad
// input (a pin or drag node outside or on each other, a node deep in a collider: resolve_params),
// checked before the first cell on every size of up to kCheckedNodes nodes (built for it).
constexpr std::int64_t kCheckedNodes = std::int64_t(1) << 22;
void require_size_scenes(const Experiment& x, const Sweep& s);
// The key path of a grid size, for errors: "x.json.sweep.sizes[k]: size 64²".
std::string size_key(const Sweep& s, int size);
std::vector<Cell> cells(const Sweep& s);

struct SweepProgress {
  int done = 0, total = 0, skipped = 0;
  double elapsed_s = 0;
  bool kept = false;  // this cell was measured before and kept, not run
  bool remeasured = false;  // this cell was measured before, with another scene or method, and ran again
};

struct SweepOptions {
  std::function<void(const Cell&, const nlohmann::json& result, const SweepProgress&)> on_cell;
  // This device's ceilings (`deformlab calibrate`'s JSON) for the manifest and the report;
  // null keeps the calibration the folder's manifest already has.
  nlohmann::json calibration;
  // --max-size: the experiment's own grid or lattice larger than this along an axis leaves
  // its frames to a later run, as the sweep's larger sizes are.
  std::optional<int> max_size;
};

// Throws std::invalid_argument where the experiment's own grid, whose frames sweep `s` would draw
// into `dir` after its cells (with OpenGL, under --max-size, none kept there), does not fit this
// host's memory; a mesh is counted once read, its frames then unavailable.
void require_frames_fit(const Experiment& x, const Sweep& s, const std::filesystem::path& dir,
                        std::optional<int> max_size);

// Runs every cell not yet measured in `dir`/cells/ (n/a cells are tried again, and so are
// cells measured with another scene or sweep method: sweep_folder.hpp) and returns the number
// it ran. Writes `dir`/manifest.json (experiment, build, machine, calibration) first;
// then, unless `dir`/frames/ exists, renders the sweep's frames there (render_frames) and
// records them, or why there are none (for now, under `o.max_size`), as the manifest's "frames".
int run_sweep(const Experiment& x, const Sweep& s, const std::filesystem::path& dir, const SweepOptions& o,
              const nlohmann::json& command);

// The models of the cells at hand, each built once and freed when the sweep moves on: a grid
// per size; a mesh read or generated once per model name (kept in its file's order while that
// model's cells run) and ordered once per (name, order). At most two models are held: the
// file's order and one other.
class ModelCache {
 public:
  // The model of `c`, whose scene is `scene`.
  const Model& model(const Scene& scene, const Cell& c);
  int meshes_built() const { return bases_; }   // grids or meshes in the file's order
  int models_built() const { return models_; }  // distinct (size or name, order) models handed out

 private:
  std::string base_key_, order_key_;
  std::unique_ptr<Model> base_, ordered_;
  int bases_ = 0, models_ = 0;
};

// One cell's result: {"status": "ok", "median_ms", ..., "stages": [{"name", "median_ms",
// "clock", "per_step"}] for pipelines that time their stages} or {"status": "n/a", "reason"};
// "nodes", "springs", "model_build_s" (0: a model built for an earlier cell) and, for mesh
// models, "model", "order", "mesh" ("surface" or "volume") and "bandwidth". Throws
// std::invalid_argument where the cell's model or scene is bad input (a model generated or
// filled, or the pins, drag node and colliders of a grid over kCheckedNodes, are checked only
// here): the sweep stops.
nlohmann::json run_cell(const Experiment& x, const Sweep& s, const Cell& c, ModelCache& cache);

// Frames of the experiment's own scene (its model, not a sweep size) on the best pipeline
// here, `s.frames` of them spread over the drag (or min_steps), drawn at 512 x 512 into
// `dir`/frames/ (written to a temporary folder, then renamed). Returns what was rendered,
// or {"unavailable": why} (no OpenGL, a run that failed).
nlohmann::json render_frames(const Experiment& x, const Sweep& s, const std::filesystem::path& dir);

// Reads every cell result in `dir`/cells/.
std::vector<nlohmann::json> load_cells(const std::filesystem::path& dir);

// Throws std::invalid_argument when `dir` holds the results of another experiment than `name`.
void require_same_experiment(const std::filesystem::path& dir, const std::string& name);
// A cell file's result, or null when the file is not a cell result (damaged, edited).
nlohmann::json read_cell(const std::filesystem::path& file);


}  // namespace deformlab
