#include <algorithm>
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "core/interrupt.hpp"
#include "run_input.hpp"
#include "core/number_text.hpp"
#include "core/one_line.hpp"
#include "experiments/ceilings.hpp"
#include "experiments/experiment.hpp"
#include "experiments/output.hpp"
#include "experiments/pipelines.hpp"
#include "experiments/report.hpp"
#include "experiments/sweep.hpp"
#include "experiments/sweep_folder.hpp"
#include "experiments/sweep_models.hpp"

namespace deformlab::app {
namespace {

// Whether a pipeline of the sweep runs on the GPU: a calibration's ceilings are the GPU's.
bool sweeps_a_gpu(const Sweep& s) {
  return std::any_of(s.pipelines.begin(), s.pipelines.end(), [](const std::string& name) {
    const PipelineEntry* e = pipelines().find(name);
    return e && on_gpu(*e);
  });
}

}  // namespace

int experiment_command(const ExperimentArgs& a) {
  Experiment x;
  std::optional<Sweep> sweep;
  try {
    x = load_experiment_by_name(a.file);
    sweep = parse_sweep(x.raw, a.file);
    if (!sweep) throw std::invalid_argument(a.file + ": has no \"sweep\" (run it with `deformlab run --experiment`)");
    // A results folder is told apart from another experiment's by the name its manifest records.
    if (x.name.empty())
      throw std::invalid_argument(a.file + ": has no \"name\", and its file name is not one (" + kPlainName +
                                  "): give it a \"name\"");
    if (!sweep->sizes.empty() && x.scene.model.topology == Topology::general)
      throw std::invalid_argument(a.file + ".sweep.sizes: the scene's model is a mesh, whose file or \"generate\" gives its size (sweep \"models\")");
    if (a.max_size && !sweep->models.empty()) throw std::invalid_argument("--max-size: this sweep has models, not grid sizes");
    if (a.max_size && a.report_only) throw std::invalid_argument("--max-size limits the cells a run measures; --report-only measures none");
    if (!a.report_only) require_size_grids(x, *sweep);  // a report is written of the cells there are
    if (a.max_size) {
      std::erase_if(sweep->sizes, [&](int n) { return n > *a.max_size; });
      if (sweep->sizes.empty()) throw std::invalid_argument("--max-size leaves no grid size to run");
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
    return 2;
  }
  const std::filesystem::path dir = a.out ? *a.out : "runs/" + x.name;
  nlohmann::json calibration;
  try {
    require_folder_or_nothing(dir);
    if (!a.report_only) require_writable(dir);
    require_holds_nothing_but(dir, Holds::experiment);
    require_same_experiment(dir, x.name);
    if (!a.report_only) require_sweep_folder(dir, x, *sweep);
    else require_report_targets(dir);
    if (!a.report_only) require_frames_fit(x, *sweep, dir, a.max_size);
    if (a.calibration) calibration = read_calibration(*a.calibration);
  } catch (const std::invalid_argument& e) {
    std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
    return 2;
  }
  return report_errors([&] {
    if (!a.report_only) {  // builds the models: out of memory is bad input
      require_model_files(x, *sweep);
      require_size_scenes(x, *sweep);
    }
    if (a.report_only && !calibration.is_null()) {
      // Records the calibration given in the folder's manifest; the cells stay as they are.
      nlohmann::json manifest = read_manifest(dir);
      if (!manifest.is_object()) throw std::invalid_argument("no manifest.json in " + dir.string());
      manifest["calibration"] = calibration;
      write_atomically(dir / "manifest.json", manifest.dump(2) + "\n");
    }
    if (!a.report_only) {
      const InterruptCatcher signals;  // while calibrating, and between cells: the cells done stay
      const nlohmann::json earlier = read_manifest(dir);
      if (calibration.is_null() && sweeps_a_gpu(*sweep) &&
          !(earlier.is_object() && earlier.value("calibration", nlohmann::json()).is_object())) {
        // Measured once per results folder, where this machine can (CUDA and GL together).
        try {
          std::cout << "calibrating this device (`deformlab calibrate`)" << std::endl;
          calibration = measure_calibration(a.argv);
        } catch (const std::invalid_argument& e) {
          std::cout << "no calibration: " << e.what() << "\n";
        }
        if (const int sig = InterruptCatcher::caught())
          throw Interrupted(sig, signal_name(sig) + " while calibrating: the experiment stopped before its cells");
      }
      std::cout << "deformlab experiment " << x.name << ": " << cells(*sweep).size() << " cells into "
                << dir.string() << " (cells already there are kept, but for those of another scene or method)\n";
      SweepOptions o;
      o.calibration = calibration;
      o.max_size = a.max_size;
      o.on_cell = [lattice = sweep->lattice](const Cell& c, const nlohmann::json& r, const SweepProgress& p) {
        const int ran = p.done - p.skipped;
        std::cout << "[" << p.done << "/" << p.total << "] " << c.pipeline << " " << c.integrator << " "
                  << c.label(lattice);
        for (const auto& [k, v] : c.options) std::cout << " " << k << "=" << v;
        if (r["status"] == "ok")
          std::cout << ": " << significant(r["median_ms"].get<double>(), 4) << " ms/step ("
                    << r.value("step_clock", std::string("clock not recorded")) << ")"
                    << (p.kept ? " (kept)" : p.remeasured ? " (measured again: the scene or the sweep's method changed)" : "");
        else
          std::cout << ": n/a (" << r["reason"].get<std::string>() << ")"
                    << (p.remeasured ? " (measured again: the scene or the sweep's method changed)" : "");
        std::cout << "  [" << duration_text(p.elapsed_s);
        // The time left at the rate of the cells run so far: none to go by while only kept cells came.
        if (p.done < p.total && ran > 0)
          std::cout << ", about " << duration_text(p.elapsed_s / ran * (p.total - p.done)) << " left";
        std::cout << "]" << std::endl;
      };
      nlohmann::json command = a.argv;
      const int ran = run_sweep(x, *sweep, dir, o, command);
      std::cout << "ran " << ran << " cells, kept " << int(cells(*sweep).size()) - ran << "\n";
    }
    std::filesystem::path report;
    try {
      report = write_report(dir);
    } catch (const nlohmann::json::exception& e) {  // a cell is checked as it is read: the manifest
      std::string why = e.what();
      if (const auto end = why.find("] "); why.starts_with("[json.exception.") && end != std::string::npos) why.erase(0, end + 2);
      throw std::invalid_argument("a results file in " + dir.string() + " (its manifest.json, or a cell) holds a value of another kind "
                                  "than the report reads (" + why + "): a damaged or edited file; run the experiment into another folder");
    }
    std::cout << "report: " << report.string() << "\n";
    return 0;
  });
}

}  // namespace deformlab::app
