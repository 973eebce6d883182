#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "ceilings.hpp"
#include "core/profiler.hpp"
#include "paper.hpp"
#include "pipelines.hpp"
#include "plot.hpp"
#include "sweep.hpp"

namespace deformlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string fmt(double v) {
  std::ostringstream os;
  if (v >= 100) os << std::fixed << std::setprecision(1) << v;
  else if (v >= 1) os << std::fixed << std::setprecision(3) << v;
  else os << std::setprecision(3) << v;
  return os.str();
}

std::string percent(double v) {
  std::ostringstream os;
  if (v >= 10) os << std::lround(v);
  else if (v >= 1) os << std::fixed << std::setprecision(1) << v;
  else os << std::setprecision(2) << v;
  return os.str() + "%";
}

std::string options_label(const json& o) {
  std::string s;
  for (const auto& [k, v] : o.items()) s += (s.empty() ? "" : ", ") + k + "=" + v.get<std::string>();
  return s;
}

// A sweep's pipelines are known names (parse_sweep checks them).
const PipelineTraits& traits_of(const std::string& pipeline) { return pipelines().find(pipeline)->traits; }

struct Column {
  std::string label, pipeline, integrator;
  json options;
};

// One table: rows are sizes, columns ours (then the paper's), grouped by one key.
struct Table {
  std::string title;
  std::vector<Column> columns;
};

// Each measured step as a fraction of its ceiling (ceilings.hpp): ceiling / measured.
template <class Ours>
void write_ceiling_table(std::ostringstream& md, const std::vector<Column>& columns, const std::set<int>& sizes,
                         const Ceilings& ceil, const Ours& ours) {
  std::vector<const Column*> cols;
  std::vector<std::pair<std::string, std::vector<std::string>>> bounds;  // what bounds which columns
  for (const auto& c : columns) {
    const auto b = stage_ceiling(ceil, traits_of(c.pipeline), span::step, 1, *parse_integrator(c.integrator));
    const bool measured = std::any_of(sizes.begin(), sizes.end(),
                                      [&](int n) { return ours(c.pipeline, c.integrator, c.options, n) != nullptr; });
    if (!b || !measured) continue;
    cols.push_back(&c);
    auto it = std::find_if(bounds.begin(), bounds.end(), [&](const auto& e) { return e.first == b->what; });
    if (it == bounds.end()) bounds.push_back({b->what, {c.label}});
    else it->second.push_back(c.label);
  }
  if (cols.empty()) return;
  md << "Against this device's ceilings: the least time a step could take (ms) and the measured step's fraction "
        "of it (ceiling / measured; 100% = at the ceiling).\n\n| grid |";
  for (const Column* c : cols) md << " " << c->label << " |";
  md << "\n|---|";
  for (std::size_t k = 0; k < cols.size(); ++k) md << "---|";
  md << "\n";
  for (int n : sizes) {
    md << "| " << n << "² |";
    for (const Column* c : cols) {
      const json* r = ours(c->pipeline, c->integrator, c->options, n);
      if (!r) {
        md << " - |";
        continue;
      }
      const auto b = stage_ceiling(ceil, traits_of(c->pipeline), span::step, (*r)["nodes"].get<std::int64_t>(),
                                   *parse_integrator(c->integrator));
      md << " " << fmt(b->ms) << " (" << percent(100 * b->ms / (*r)["median_ms"].get<double>()) << ") |";
    }
    md << "\n";
  }
  md << "\nCeilings:";
  for (const auto& [what, labels] : bounds) {
    md << "\n- ";
    for (std::size_t k = 0; k < labels.size(); ++k) md << (k ? ", " : "") << labels[k];
    md << ": " << what;
  }
  md << "\n\n";
}

// Cells that timed their stages (a profiled batch apart from the timed ones): each stage's
// GPU time per step and its fraction of its ceiling, what the GPU stages leave of the
// step (hand-offs, waits, launches), and for the hybrids the time per hand-off against the
// floor; stacked bars of each pipeline's split by size.
void write_stages(std::ostringstream& md, const fs::path& dir, const std::string& name, const Sweep& sweep,
                  const std::vector<json>& cells, const Ceilings& ceil) {
  struct Group {
    std::string label, pipeline, integrator;
    std::vector<const json*> rows;
    std::vector<std::string> gpu_stages, host_stages;
  };
  std::vector<Group> groups;
  for (const auto& c : deformlab::cells(sweep)) {
    std::string label = c.pipeline + " " + c.integrator;
    if (!c.options.empty()) label += " [" + options_label(json(c.options)) + "]";
    Group g{label, c.pipeline, c.integrator, {}, {}, {}};
    bool seen = false;
    for (const auto& e : groups) seen |= e.label == label;
    if (seen) continue;
    for (const auto& r : cells)
      if (r["status"] == "ok" && r.contains("stages") && r["pipeline"] == c.pipeline &&
          r["integrator"] == c.integrator && r["options"] == json(c.options))
        g.rows.push_back(&r);
    if (g.rows.empty()) continue;
    std::sort(g.rows.begin(), g.rows.end(),
              [](const json* a, const json* b) { return (*a)["size"].get<int>() < (*b)["size"].get<int>(); });
    for (const json* r : g.rows)
      for (const auto& st : (*r)["stages"]) {
        auto& list = st["clock"] == "host clock" ? g.host_stages : g.gpu_stages;
        if (std::find(list.begin(), list.end(), st["name"]) == list.end()) list.push_back(st["name"]);
      }
    groups.push_back(std::move(g));
  }
  if (groups.empty()) return;
  md << "## Where a step's time goes\n\n"
        "Stage times are medians per step over one more batch run with the profiler attached, each by its own "
        "clock (CUDA events, GL timer queries); \"rest\" is the timed step less its GPU stages: hand-offs, "
        "waits and launch gaps. Host-clock columns are CPU time inside those calls.";
  if (ceil.any()) md << " In brackets: the stage's ceiling / its time (ceilings.hpp; 100% = at the ceiling).";
  md << "\n\n";
  for (const Group& g : groups) {
    const Integrator integ = *parse_integrator(g.integrator);
    const PipelineTraits& traits = traits_of(g.pipeline);
    const bool hybrid = traits.hands_off();
    const double hand_offs = 2.0 * info(integ).force_passes;
    md << "### " << g.label << "\n\n| grid | step ms |";
    for (const auto& st : g.gpu_stages) md << " " << st << " ms |";
    md << " rest ms |";
    for (const auto& st : g.host_stages) md << " " << st << " (CPU) ms |";
    if (hybrid) md << " rest per hand-off µs |" << (ceil.floor_us > 0 ? " x floor |" : "");
    md << "\n|---|---|";
    const std::size_t ncols = g.gpu_stages.size() + 1 + g.host_stages.size() + (hybrid ? (ceil.floor_us > 0 ? 2 : 1) : 0);
    for (std::size_t k = 0; k < ncols; ++k) md << "---|";
    md << "\n";
    std::vector<plot::Stack> bars;
    for (const json* r : g.rows) {
      const double step = (*r)["median_ms"].get<double>();
      const std::int64_t nodes = (*r)["nodes"].get<std::int64_t>();
      auto stage_ms = [&](const std::string& st) -> std::optional<double> {
        for (const auto& e : (*r)["stages"])
          if (e["name"] == st) return e["median_ms"].get<double>();
        return std::nullopt;
      };
      md << "| " << (*r)["size"].get<int>() << "² | " << fmt(step) << " |";
      plot::Stack bar{std::to_string((*r)["size"].get<int>()) + "² " + fmt(step) + " ms", {}};
      double gpu = 0;
      for (const auto& st : g.gpu_stages) {
        const auto v = stage_ms(st);
        if (!v) {
          md << " - |";
          bar.parts.push_back(0);
          continue;
        }
        gpu += *v;
        md << " " << fmt(*v);
        if (const auto b = stage_ceiling(ceil, traits, st, nodes, integ)) md << " (" << percent(100 * b->ms / *v) << ")";
        md << " |";
        bar.parts.push_back(100 * *v / step);
      }
      const double rest = std::max(0.0, step - gpu);
      md << " " << fmt(rest) << " |";
      bar.parts.push_back(100 * rest / step);
      for (const auto& st : g.host_stages) {
        const auto v = stage_ms(st);
        md << " " << (v ? fmt(*v) : "-") << " |";
      }
      if (hybrid) {
        const double per = rest / hand_offs * 1e3;
        md << " " << fmt(per) << " |";
        if (ceil.floor_us > 0) md << " " << fmt(per / ceil.floor_us) << " |";
      }
      md << "\n";
      bars.push_back(std::move(bar));
    }
    std::vector<std::string> parts = g.gpu_stages;
    parts.push_back("rest");
    std::string file = "stages-" + g.label + ".svg";
    for (char& ch : file)
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '.') ch = '_';
    plot::stacked_bars(dir / file, name + ": " + g.label, "% of the step", parts, bars);
    md << "\n![" << g.label << " stages](" << file << ")\n\n";
  }
}

}  // namespace

fs::path write_report(const fs::path& dir) {
  const json manifest = read_manifest(dir);
  if (!manifest.is_object() || !manifest.contains("experiment"))
    throw std::invalid_argument("no sweep manifest.json in " + dir.string());
  const json& xj = manifest["experiment"];
  const std::optional<Sweep> parsed = parse_sweep(xj, "manifest.experiment");
  if (!parsed) throw std::invalid_argument(dir.string() + ": its experiment has no sweep");
  const Sweep& sweep = *parsed;
  const auto cells = load_cells(dir);
  const std::string table = sweep.paper_table;
  const bool by_pipeline = table == "table3";

  // Results indexed by (pipeline, integrator, options, size).
  std::map<std::string, const json*> at;
  auto key = [](const std::string& p, const std::string& i, const json& o, int n) {
    return p + "|" + i + "|" + o.dump() + "|" + std::to_string(n);
  };
  std::set<int> sizes;
  std::map<int, std::int64_t> nodes_at;  // as the cells of each size record it
  for (const auto& c : cells) {
    at[key(c["pipeline"], c["integrator"], c["options"], c["size"])] = &c;
    sizes.insert(c["size"].get<int>());
    if (c.contains("nodes")) nodes_at[c["size"].get<int>()] = c["nodes"].get<std::int64_t>();
  }

  // Columns in sweep order, grouped.
  std::vector<Table> tables;
  auto table_for = [&](const std::string& title) -> Table& {
    for (auto& t : tables)
      if (t.title == title) return t;
    tables.push_back({title, {}});
    return tables.back();
  };
  for (const auto& c : deformlab::cells(sweep)) {
    Table& t = table_for(by_pipeline ? c.pipeline : c.integrator);
    const json o = c.options;
    std::string label = by_pipeline ? c.integrator : c.pipeline;
    if (!o.empty()) label += " [" + options_label(o) + "]";
    bool seen = false;
    for (const auto& col : t.columns) seen |= col.label == label;
    if (!seen) t.columns.push_back({label, c.pipeline, c.integrator, o});
  }

  std::ostringstream md;
  const std::string name = xj.value("name", std::string("experiment"));
  md << "# " << name << "\n\n" << xj.value("description", std::string()) << "\n\n";
  const json m = manifest.value("machine", json::object());
  const json build = manifest.value("build", json::object());
  md << "- Machine: " << m.value("cpu", std::string("?")) << ", " << m.value("hardware_threads", 0)
     << " hardware threads, " << m.value("os", std::string("?")) << "\n";
  md << "- Build: deformlab " << build.value("deformlab", std::string()) << " (" << build.value("git", std::string())
     << "), " << build.value("compiler", std::string()) << ", CUDA " << build.value("cuda", std::string()) << "\n";
  const json calibration = manifest.value("calibration", json());
  const Ceilings ceil = ceilings_of(calibration);
  if (ceil.any()) {
    md << "- Calibration (`deformlab calibrate`, " << calibration.value("device", json::object()).value("name", std::string("?"))
       << "): CUDA copy " << fmt(ceil.copy_gb_s) << " GB/s, compute-shader copy " << fmt(ceil.compute_copy_gb_s)
       << " GB/s, transform feedback " << fmt(ceil.tf_vertices_s * 1e-6) << " M vertices/s, GL <-> CUDA hand-off floor "
       << fmt(ceil.floor_us) << " µs\n";
  } else {
    md << "- No calibration recorded: times are not shown against ceilings\n";
  }
  const json availability = manifest.value("pipelines", json::object());
  for (const auto& [p, status] : availability.items())
    if (status != "available") md << "- `" << p << "` not available: " << status.get<std::string>() << "\n";
  md << "- Method: ";
  for (const auto& c : cells)
    if (c["status"] == "ok") {
      md << c["method"].get<std::string>() << ". "
         << (sweep.time == "frame" ? "Times are milliseconds per frame (update and a 1024 x 1024 draw), as the paper's.\n"
                                   : "Times are milliseconds per simulation step (update only); the paper's are "
                                     "milliseconds per frame, update and rendering.\n");
      break;
    }
  md << "\n";

  // Footnotes for cells not measured, one per distinct reason, listing where it applies.
  std::vector<std::pair<std::string, std::vector<std::string>>> notes;
  auto note = [&](const std::string& reason, const std::string& where) {
    for (std::size_t k = 0; k < notes.size(); ++k)
      if (notes[k].first == reason) {
        notes[k].second.push_back(where);
        return k + 1;
      }
    notes.push_back({reason, {where}});
    return notes.size();
  };
  std::vector<std::string> reading;
  for (const auto& t : tables) {
    md << "## " << (by_pipeline ? "Pipeline " : "Integrator ") << "`" << t.title << "`\n\n";
    std::vector<paper::Column> pcols;
    for (const auto& pc : paper::columns(table))
      if ((by_pipeline ? pc.pipeline : pc.integrator) == t.title) pcols.push_back(pc);
    std::vector<paper::Ratio> rats;
    auto ours = [&](const std::string& pipe, const std::string& integ, const json& o, int n) -> const json* {
      const auto it = at.find(key(pipe, integ, o, n));
      return it == at.end() || (*it->second)["status"] != "ok" ? nullptr : it->second;
    };
    auto has_col = [&](const std::string& p) {
      for (const auto& c : t.columns)
        if (c.pipeline == p && c.options.empty()) return true;
      return false;
    };
    for (const auto& r : paper::ratios(table))
      if (!by_pipeline && has_col(r.num) && has_col(r.den)) rats.push_back(r);

    md << "| grid | nodes |";
    for (const auto& c : t.columns) md << " " << c.label << " |";
    for (const auto& pc : pcols) md << " " << pc.label << " |";
    for (const auto& r : rats) md << " " << r.label << " | paper " << r.label << " |";
    md << "\n|---|---|";
    for (std::size_t k = 0; k < t.columns.size() + pcols.size() + 2 * rats.size(); ++k) md << "---|";
    md << "\n";
    std::vector<plot::Series> series;
    for (const auto& c : t.columns) series.push_back({c.label, {}, {}, false});
    for (const auto& pc : pcols) series.push_back({pc.label, {}, {}, true});
    for (int n : sizes) {
      const auto counted = nodes_at.find(n);
      const double nodes = counted == nodes_at.end() ? 0 : double(counted->second);
      md << "| " << n << "² | " << (nodes > 0 ? std::to_string(counted->second) : "-") << " |";
      for (std::size_t k = 0; k < t.columns.size(); ++k) {
        const auto& c = t.columns[k];
        const auto it = at.find(key(c.pipeline, c.integrator, c.options, n));
        if (it == at.end()) {
          md << " - |";
          continue;
        }
        const json& r = *it->second;
        if (r["status"] == "ok") {
          md << " " << fmt(r["median_ms"]);
          if (!r.value("stable", true))
            md << " [" << note("the state was not finite after the timed steps: the time of a wrong result", c.label + " " + std::to_string(n) + "²") << "]";
          md << " |";
          series[k].x.push_back(r["nodes"].get<double>());
          series[k].y.push_back(r["median_ms"].get<double>());
        } else {
          md << " n/a [" << note(r["reason"], c.label + " " + std::to_string(n) + "²") << "] |";
        }
      }
      for (std::size_t k = 0; k < pcols.size(); ++k) {
        const auto f = paper::figure(table, pcols[k], n);
        md << " " << (f ? fmt(*f) : "n/a") << " |";
        if (f) {
          series[t.columns.size() + k].x.push_back(nodes);
          series[t.columns.size() + k].y.push_back(*f);
        }
      }
      for (const auto& r : rats) {
        const json* a = ours(r.num, t.title, json::object(), n);
        const json* b = ours(r.den, t.title, json::object(), n);
        std::optional<double> pa, pb;
        for (const auto& pc : paper::columns(table)) {
          if (pc.pipeline == r.num) pa = paper::figure(table, pc, n);
          if (pc.pipeline == r.den) pb = paper::figure(table, pc, n);
        }
        const bool here = a && b, there = pa && pb;
        const double q = here ? (*a)["median_ms"].get<double>() / (*b)["median_ms"].get<double>() : 0;
        const double pq = there ? *pa / *pb : 0;
        md << " " << (here ? fmt(q) : "n/a") << " | " << (there ? fmt(pq) : "n/a") << " |";
        if (here && there)
          reading.push_back(r.label + " (" + r.num + " / " + r.den + ") at " + std::to_string(n) + "²: paper " + fmt(pq) +
                            ", here " + fmt(q) + ": " +
                            ((pq > 1) == (q > 1) ? "the paper's ordering holds"
                                                 : "the ordering reverses (" +
                                                       (q > 1 ? r.den + " is faster here" : r.num + " is faster here") + ")"));
      }
      md << "\n";
    }
    const std::string svg = "plot-" + t.title + ".svg";
    plot::loglog(dir / svg, name + ": " + t.title, "nodes", "ms per step (dashed: paper, ms per frame)", series);
    md << "\n![" << t.title << "](" << svg << ")\n\n";
    if (ceil.any() && sweep.time == "update") write_ceiling_table(md, t.columns, sizes, ceil, ours);
  }
  write_stages(md, dir, name, sweep, cells, ceil);
  if (const json frames = manifest.value("frames", json()); frames.is_object()) {
    md << "## Frames of the drag\n\n";
    if (frames.contains("files")) {
      md << "The experiment's own scene (" << frames.value("nodes", 0) << " nodes) on `"
         << frames.value("pipeline", std::string()) << "`, " << frames.value("integrator", std::string()) << ", a "
         << frames.value("size", json::array({0, 0}))[0] << " x " << frames.value("size", json::array({0, 0}))[1]
         << " frame every " << frames.value("every_steps", 0) << " steps of " << frames.value("steps", 0)
         << "; the camera frames the rest pose.\n\n";
      for (const auto& f : frames["files"]) md << "![" << f.get<std::string>() << "](" << f.get<std::string>() << ") ";
      md << "\n\n";
    } else {
      md << "None: " << frames.value("unavailable", std::string("?")) << "\n\n";
    }
  }
  if (!notes.empty()) {
    md << "## Notes on cells\n\n";
    for (std::size_t k = 0; k < notes.size(); ++k) {
      md << "[" << k + 1 << "] " << notes[k].first << " (";
      for (std::size_t w = 0; w < notes[k].second.size(); ++w) md << (w ? ", " : "") << notes[k].second[w];
      md << ")\n\n";
    }
  }
  if (!reading.empty()) {
    md << "## Reading against the paper\n\n";
    for (const auto& r : reading) md << "- " << r << "\n";
    md << "\n";
  }
  write_atomically(dir / "report.md", md.str());
  return dir / "report.md";
}

}  // namespace deformlab
