#include "report.hpp"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>

#include "core/clock_watch.hpp"
#include "output.hpp"
#include "paper.hpp"
#include "plot.hpp"
#include "report_parts.hpp"
#include "sweep_folder.hpp"

namespace deformlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using namespace report;

// One results table: rows are sizes, columns ours (then the paper's), grouped by one key.
struct Table {
  std::string title;
  std::vector<Column> columns;
};

// What the report's sections share while it is written.
struct Report {
  fs::path dir;
  json manifest;
  Sweep sweep;
  std::vector<json> cells;
  Results results{cells};
  std::string name;
  bool by_pipeline = false;  // the paper's Table 3: a table per pipeline, not per integrator
  Ceilings ceil;
  Notes notes;
  std::vector<std::string> reading;  // the paper's orderings, held or reversed
  std::ostringstream md;
};

// Columns in sweep order, grouped into tables.
std::vector<Table> tables_of(const Sweep& sweep, bool by_pipeline) {
  std::vector<Table> tables;
  for (const auto& c : cells(sweep)) {
    const std::string title = by_pipeline ? c.pipeline : c.integrator;
    auto t = std::find_if(tables.begin(), tables.end(), [&](const Table& e) { return e.title == title; });
    if (t == tables.end()) t = tables.insert(tables.end(), {title, {}});
    const json o = c.options;
    std::string label = by_pipeline ? c.integrator : c.pipeline;
    if (!o.empty()) label += " [" + options_label(o) + "]";
    const bool seen = std::any_of(t->columns.begin(), t->columns.end(), [&](const Column& e) { return e.label == label; });
    if (!seen) t->columns.push_back({label, c.pipeline, c.integrator, o});
  }
  return tables;
}

// Where the compute-shader copy ran, as calibrations since the GL pipelines' memory option record
// it: " on memory=cuda (N GB/s on GL's buffers)", or nothing.
std::string compute_copy_memory(const json& calibration) {
  const json copy = calibration.value("compute_copy", json::object());
  if (!copy.contains("memory")) return "";
  std::string s = " on memory=" + copy["memory"].get<std::string>();
  const json gl = calibration.value("compute_copy_gl_buffers", json::object());
  if (gl.contains("GB_per_s")) s += " (" + fmt(gl["GB_per_s"].get<double>()) + " GB/s on GL's buffers)";
  return s;
}

void write_setup(Report& r) {
  const json& xj = r.manifest["experiment"];
  r.md << "# " << r.name << "\n\n" << xj.value("description", std::string()) << "\n\n";
  const json m = r.manifest.value("machine", json::object());
  const json build = r.manifest.value("build", json::object());
  r.md << "- Machine: " << m.value("cpu", std::string("?")) << ", " << m.value("hardware_threads", 0)
       << " hardware threads, " << m.value("os", std::string("?")) << "\n";
  r.md << "- Build: deformlab " << build.value("deformlab", std::string()) << " (" << build.value("git", std::string())
       << "), " << build.value("compiler", std::string()) << ", CUDA " << build.value("cuda", std::string()) << "\n";
  // A resumed sweep may hold cells of several builds; the manifest names the last run's.
  std::map<std::string, int> builds;
  for (const auto& c : r.cells)
    if (c["status"] == "ok") ++builds[c.value("build", std::string("not recorded"))];
  if (builds.size() > 1 || (builds.size() == 1 && builds.begin()->first != build.value("git", std::string()))) {
    r.md << "- Measured cells by build:";
    for (const auto& [git, n] : builds) r.md << (git == builds.begin()->first ? " " : ", ") << git << " (" << n << ")";
    r.md << "\n";
  }
  const json calibration = r.manifest.value("calibration", json());
  if (r.ceil.any()) {
    r.md << "- Calibration (`deformlab calibrate`, " << r.ceil.device << "): CUDA copy "
         << fmt(r.ceil.copy_gb_s) << " GB/s, compute-shader copy " << fmt(r.ceil.compute_copy_gb_s) << " GB/s"
         << compute_copy_memory(calibration) << ", transform feedback " << fmt(r.ceil.tf_vertices_s * 1e-6)
         << " M vertices/s, GL <-> CUDA hand-off floor " << fmt(r.ceil.floor_us) << " µs\n";
  } else {
    r.md << "- No calibration recorded: times are not shown against ceilings\n";
  }
  const json availability = r.manifest.value("pipelines", json::object());
  for (const auto& [p, status] : availability.items())
    if (status != "available") r.md << "- `" << p << "` not available: " << status.get<std::string>() << "\n";
  // Grid sizes of the sweep without a cell yet (left out by --max-size, or not reached).
  std::set<int> measured;
  for (const auto& c : r.cells)
    if (c.contains("size") && c["size"].is_number_integer()) measured.insert(c["size"].get<int>());
  std::string missing;
  for (const auto& n : xj.value("sweep", json::object()).value("sizes", json::array()))
    if (n.is_number_integer() && !measured.count(n.get<int>()))
      missing += (missing.empty() ? "" : ", ") + size_label(n.get<int>(), r.sweep.lattice);
  if (!missing.empty())
    r.md << "- Not measured yet: " << missing << " (left out by --max-size, or not reached; `deformlab experiment` "
         << "on this folder again runs them and keeps the cells it has)\n";
}

// The GPU's clock over the cells' timed batches (cells with `sm_clock`).
void write_clocks(Report& r) {
  ClockTally tally;
  for (const auto& c : r.cells)
    if (c["status"] == "ok" && c.contains("sm_clock")) tally.add(c["id"].get<std::string>(), clock_summary(c["sm_clock"]));
  if (!tally.empty())
    r.md << "- GPU clock over the timed batches (NVML, sampled every " << ClockWatch::kPeriodMs
         << " ms): " << tally.describe("cell") << "\n";
}

// The options pipelines chose for the machine where the experiment gave none (the hybrids'
// interop mode), each with the pipelines that chose it.
void write_chosen_options(Report& r) {
  std::map<std::string, std::set<std::string>> chosen;
  for (const auto& c : r.cells)
    if (c.contains("chosen_options"))
      for (const auto& [name, value] : c["chosen_options"].items())
        chosen[name + "=" + value.get<std::string>()].insert(c["pipeline"].get<std::string>());
  if (chosen.empty()) return;
  r.md << "- Options chosen for this machine where none was given:";
  bool first = true;
  for (const auto& [option, pipelines] : chosen) {
    r.md << (std::exchange(first, false) ? " " : "; ") << option << " (";
    bool first_pipeline = true;
    for (const auto& p : pipelines) r.md << (std::exchange(first_pipeline, false) ? "" : ", ") << p;
    r.md << ")";
  }
  r.md << "\n";
}

// How the cells were timed, as the first measured cell says, and each step clock with the
// pipelines it times.
void write_method(Report& r) {
  std::vector<std::pair<std::string, std::vector<std::string>>> clocks;
  std::string method;
  for (const auto& c : r.cells) {
    if (c["status"] != "ok") continue;
    if (method.empty()) method = c["method"].get<std::string>();
    if (!c.contains("step_clock")) continue;
    const std::string clock = c["step_clock"].get<std::string>(), p = c["pipeline"].get<std::string>();
    auto it = std::find_if(clocks.begin(), clocks.end(), [&](const auto& e) { return e.first == clock; });
    if (it == clocks.end()) it = clocks.insert(clocks.end(), {clock, {}});
    if (std::find(it->second.begin(), it->second.end(), p) == it->second.end()) it->second.push_back(p);
  }
  if (method.empty()) return;
  r.md << "- Method: " << method << ". "
       << (r.sweep.time == "frame" ? "Times are milliseconds per frame (update and a 1024 x 1024 draw), as the paper's.\n"
                                   : "Times are milliseconds per simulation step (no rendering); the paper's are "
                                     "milliseconds per frame, update and rendering.\n");
  if (!clocks.empty()) {
    r.md << "- Step clocks:";
    for (std::size_t k = 0; k < clocks.size(); ++k) {
      r.md << (k ? ";" : "") << " " << clocks[k].first << " (";
      for (std::size_t j = 0; j < clocks[k].second.size(); ++j) r.md << (j ? ", " : "") << clocks[k].second[j];
      r.md << ")";
    }
    r.md << "\n";
  }
  write_chosen_options(r);
  write_clocks(r);
  r.md << "\n";
}

// Our cells of size `n` in table `t`, each also a point of its column's series.
void write_our_cells(Report& r, const Table& t, int n, std::vector<plot::Series>& series) {
  for (std::size_t k = 0; k < t.columns.size(); ++k) {
    const auto& c = t.columns[k];
    const json* cell = r.results.find(c.pipeline, c.integrator, c.options, n);
    if (!cell) {
      r.md << " - |";
      continue;
    }
    const std::string where = c.label + " " + size_label(n, r.sweep.lattice);
    if ((*cell)["status"] != "ok") {
      r.md << " n/a [" << r.notes.add((*cell)["reason"], where) << "] |";
      continue;
    }
    r.md << " " << fmt((*cell)["median_ms"]);
    if (!cell->value("stable", true))
      r.md << " [" << r.notes.add("the state was not finite after the timed steps: the time of a wrong result", where)
           << "]";
    r.md << " |";
    series[k].x.push_back((*cell)["nodes"].get<double>());
    series[k].y.push_back((*cell)["median_ms"].get<double>());
  }
}

// The paper's column for `pipeline` with integrator `integrator`, if it has one.
std::optional<paper::Column> paper_column(const Report& r, const std::string& pipeline, const std::string& integrator) {
  for (const auto& pc : paper::columns(r.sweep.paper_table))
    if (pc.pipeline == pipeline && pc.integrator == integrator) return pc;
  return std::nullopt;
}

// The paper's figure for `pipeline` in table `t` (an integrator's) at size `n`, if it has one.
std::optional<double> paper_figure(const Report& r, const Table& t, const std::string& pipeline, int n) {
  const std::optional<paper::Column> pc = paper_column(r, pipeline, t.title);
  return pc ? paper::figure(r.sweep.paper_table, *pc, n) : std::nullopt;
}

// Our ratio beside the paper's at size `n`, and where both exist, whether its ordering holds.
void write_ratio_cells(Report& r, const Table& t, const std::vector<paper::Ratio>& rats, int n) {
  for (const auto& ra : rats) {
    // A time of a state that went non-finite is the time of a wrong result: not compared.
    auto stable = [&](const std::string& p) {
      const json* c = r.results.ok(p, t.title, json::object(), n);
      return c && c->value("stable", true) ? c : nullptr;
    };
    const json *a = stable(ra.num), *b = stable(ra.den);
    const std::optional<double> pa = paper_figure(r, t, ra.num, n), pb = paper_figure(r, t, ra.den, n);
    const bool here = a && b, there = pa && pb;
    const double q = here ? (*a)["median_ms"].get<double>() / (*b)["median_ms"].get<double>() : 0;
    const double pq = there ? *pa / *pb : 0;
    r.md << " " << (here ? fmt(q) : "n/a") << " | " << (there ? fmt(pq) : "n/a") << " |";
    if (!here || !there) continue;
    const std::string faster = q > 1 ? ra.den + " is faster here" : ra.num + " is faster here";
    r.reading.push_back(ra.label + " (" + ra.num + " / " + ra.den + ") at " + size_label(n, r.sweep.lattice) + ": paper " +
                        fmt(pq) + ", here " + fmt(q) + ": " +
                        ((pq > 1) == (q > 1) ? "the paper's ordering holds" : "the ordering reverses (" + faster + ")"));
  }
}

// The paper's ratios whose two pipelines are columns of `t` and of the paper's table for its
// integrator (per-integrator tables only).
std::vector<paper::Ratio> ratios_in(const Report& r, const Table& t) {
  auto has_col = [&](const std::string& p) {
    return paper_column(r, p, t.title) && std::any_of(t.columns.begin(), t.columns.end(), [&](const Column& c) {
             return c.pipeline == p && c.options.empty();
           });
  };
  std::vector<paper::Ratio> rats;
  for (const auto& ra : paper::ratios(r.sweep.paper_table))
    if (!r.by_pipeline && has_col(ra.num) && has_col(ra.den)) rats.push_back(ra);
  return rats;
}

void write_table(Report& r, const Table& t) {
  r.md << "## " << (r.by_pipeline ? "Pipeline " : "Integrator ") << "`" << t.title << "`\n\n";
  std::vector<paper::Column> pcols;
  for (const auto& pc : paper::columns(r.sweep.paper_table))
    if ((r.by_pipeline ? pc.pipeline : pc.integrator) == t.title) pcols.push_back(pc);
  const std::vector<paper::Ratio> rats = ratios_in(r, t);
  r.md << "| grid | nodes |";
  for (const auto& c : t.columns) r.md << " " << c.label << " |";
  for (const auto& pc : pcols) r.md << " " << pc.label << " |";
  for (const auto& ra : rats) r.md << " " << ra.label << " | paper " << ra.label << " |";
  r.md << "\n|---|---|";
  for (std::size_t k = 0; k < t.columns.size() + pcols.size() + 2 * rats.size(); ++k) r.md << "---|";
  r.md << "\n";
  std::vector<plot::Series> series;
  for (const auto& c : t.columns) series.push_back({c.label, {}, {}, false});
  for (const auto& pc : pcols) series.push_back({pc.label, {}, {}, true});
  for (int n : r.results.sizes()) {
    const std::int64_t nodes = r.results.nodes(n);
    r.md << "| " << size_label(n, r.sweep.lattice) << " | " << (nodes > 0 ? std::to_string(nodes) : "-") << " |";
    write_our_cells(r, t, n, series);
    for (std::size_t k = 0; k < pcols.size(); ++k) {
      const auto f = paper::figure(r.sweep.paper_table, pcols[k], n);
      r.md << " " << (f ? fmt(*f) : "n/a") << " |";
      if (!f) continue;
      series[t.columns.size() + k].x.push_back(double(nodes));
      series[t.columns.size() + k].y.push_back(*f);
    }
    write_ratio_cells(r, t, rats, n);
    r.md << "\n";
  }
  const std::string svg = plot_file(t.title);
  std::erase_if(series, [](const plot::Series& s) { return s.x.empty(); });  // no cell measured: no legend entry
  const bool paper = std::any_of(series.begin(), series.end(), [](const plot::Series& s) { return s.dashed; });
  const std::string y = (r.sweep.time == "frame" ? std::string("ms per frame (update and a 1024 x 1024 draw)")
                                                : std::string("ms per step, each on its pipeline's step clock")) +
                        (paper ? " (dashed: paper, ms per frame)" : "");
  plot::loglog(r.dir / svg, r.name + ": " + t.title, "nodes", y, series);
  r.md << "\n![" << t.title << "](" << svg << ")\n\n";
  if (const std::string note = paper::note(r.sweep.paper_table); !note.empty() && !pcols.empty()) r.md << note << "\n\n";
  if (r.ceil.any() && r.sweep.time == "update")
    write_ceiling_table(r.md, t.columns, r.results, r.ceil, r.sweep.lattice);
}

void write_frames(Report& r) {
  const json frames = r.manifest.value("frames", json());
  if (!frames.is_object()) return;
  r.md << "## Frames of the drag\n\n";
  if (!frames.contains("files")) {
    r.md << "None: " << frames.value("unavailable", std::string("?")) << "\n\n";
    return;
  }
  const json size = frames.value("size", json());
  if (!size.is_array() || size.size() != 2 || !size[0].is_number_unsigned() || !size[1].is_number_unsigned())
    throw std::invalid_argument((r.dir / "manifest.json").string() +
                                ": frames.size: expected [width, height], as the experiment writes it");
  r.md << "The experiment's own scene (" << frames.value("nodes", 0) << " nodes) on `"
       << frames.value("pipeline", std::string()) << "`, " << frames.value("integrator", std::string()) << ", a "
       << size[0] << " x " << size[1] << " frame every " << frames.value("every_steps", 0) << " steps of "
       << frames.value("steps", 0);
  // The frames cover 1.25 x the drag path, as far as the scene's max_steps lets them.
  const double shown = frames.value("steps", 0) * frames.value("dt_s", 0.0), drag = frames.value("drag_end_s", 0.0);
  if (shown > 0 && drag > shown)
    r.md << " (" << fmt(shown) << " s: the scene's max_steps cuts the " << fmt(drag) << " s drag path short)";
  r.md << "; the camera frames the rest pose.\n\n";
  for (const auto& f : frames["files"]) r.md << "![" << f.get<std::string>() << "](" << f.get<std::string>() << ") ";
  r.md << "\n\n";
}

void write_reading(Report& r) {
  if (r.reading.empty()) return;
  r.md << (r.sweep.models.empty() ? "## Reading against the paper\n\n" : "## Reading\n\n");
  for (const auto& line : r.reading) r.md << "- " << line << "\n";
  r.md << "\n";
}

// The sweep the folder's manifest records; throws when there is none.
Sweep sweep_of(const fs::path& dir, const json& manifest) {
  if (!manifest.is_object() || !manifest.contains("experiment"))
    throw std::invalid_argument("no sweep manifest.json in " + dir.string());
  std::optional<Sweep> s = parse_sweep(manifest["experiment"], "manifest.experiment");
  if (!s) throw std::invalid_argument(dir.string() + ": its experiment has no sweep");
  return *s;
}

}  // namespace

fs::path write_report(const fs::path& dir) {
  const json manifest = read_manifest(dir);
  const Sweep sweep = sweep_of(dir, manifest);
  std::vector<json> cells = load_cells(dir);
  // Cells of another scene or method than the manifest's (a run stopped, or under --max-size,
  // before it measured them again) are not this experiment's results yet, and cells its sweep
  // no longer has are not its results at all.
  std::set<std::string> ids;
  for (const Cell& c : deformlab::cells(sweep)) ids.insert(c.id());
  std::erase_if(cells, [&](const json& c) {
    // A mesh cell records the order its model took; it is part of the cell's name only where the sweep names orders.
    const std::string order = sweep.orders.empty() ? "" : c.value("order", std::string());
    const Cell of{c.value("size", 0), c.value("pipeline", std::string()), c.value("integrator", std::string()),
                  c.value("options", PipelineOptions{}), c.value("model", std::string()), order};
    return !ids.count(of.id()) || (manifest.contains("measurement") && !measured_as(c, manifest["measurement"], sweep));
  });
  Report r{.dir = dir,
           .manifest = manifest,
           .sweep = sweep,
           .cells = std::move(cells),
           .ceil = ceilings_of(manifest.value("calibration", json()))};
  r.name = manifest["experiment"].value("name", std::string("experiment"));
  r.by_pipeline = r.sweep.paper_table == "table3";
  write_setup(r);
  write_method(r);
  if (r.sweep.models.empty())
    for (const Table& t : tables_of(r.sweep, r.by_pipeline)) write_table(r, t);
  else
    write_model_tables(r.md, r.sweep, r.cells, r.ceil, r.notes, r.reading);
  write_stages(r.md, dir, r.name, r.sweep, r.cells, r.ceil);
  write_frames(r);
  r.notes.write(r.md);
  write_reading(r);
  write_atomically(dir / kReportFile, r.md.str());
  return dir / kReportFile;
}

}  // namespace deformlab
