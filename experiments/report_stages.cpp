// The report's sections on ceilings and stages (report_parts.hpp).
#include <algorithm>
#include <optional>

#include "core/profiler.hpp"
#include "pipelines.hpp"
#include "plot.hpp"
#include "report.hpp"
#include "report_parts.hpp"

namespace deformlab::report {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// A sweep's pipelines are known names (parse_sweep checks them).
const PipelineTraits& traits_of(const std::string& pipeline) { return pipelines().find(pipeline)->traits; }

std::optional<Bound> step_ceiling(const Ceilings& ceil, const Column& c, std::int64_t nodes) {
  return stage_ceiling(ceil, traits_of(c.pipeline), span::step, nodes, *parse_integrator(c.integrator));
}

// The columns with a ceiling and a measurement, and what bounds which of them.
struct Bounded {
  std::vector<const Column*> columns;
  std::vector<std::pair<std::string, std::vector<std::string>>> by_bound;  // what bounds, column labels
};

Bounded bounded_columns(const std::vector<Column>& columns, const Results& results, const Ceilings& ceil) {
  Bounded out;
  for (const auto& c : columns) {
    const auto b = step_ceiling(ceil, c, 1);
    const bool measured = std::any_of(results.sizes().begin(), results.sizes().end(), [&](int n) {
      return results.ok(c.pipeline, c.integrator, c.options, n) != nullptr;
    });
    if (!b || !measured) continue;
    out.columns.push_back(&c);
    auto it = std::find_if(out.by_bound.begin(), out.by_bound.end(), [&](const auto& e) { return e.first == b->what; });
    if (it == out.by_bound.end()) out.by_bound.push_back({b->what, {c.label}});
    else it->second.push_back(c.label);
  }
  return out;
}

// The pipelines, integrators and option sets whose cells timed their stages, with those
// cells by size and their stages by the clock that timed them.
struct Group {
  std::string label, pipeline, integrator;
  std::vector<const json*> rows;
  std::vector<std::string> gpu_stages, host_stages;
  bool lattice = false;  // its grid cells are lattices
};

Group group_of(const Cell& c, const std::vector<json>& cells, bool lattice) {
  std::string label = c.pipeline + " " + c.integrator;
  if (!c.options.empty()) label += " [" + options_label(json(c.options)) + "]";
  Group g{label, c.pipeline, c.integrator, {}, {}, {}, lattice};
  for (const auto& r : cells)
    if (r["status"] == "ok" && r.contains("stages") && r["pipeline"] == c.pipeline && r["integrator"] == c.integrator &&
        r["options"] == json(c.options))
      g.rows.push_back(&r);
  std::stable_sort(g.rows.begin(), g.rows.end(),
            [](const json* a, const json* b) { return (*a)["size"].get<int>() < (*b)["size"].get<int>(); });
  for (const json* r : g.rows)
    for (const auto& st : (*r)["stages"]) {
      auto& list = st["clock"] == "host clock" ? g.host_stages : g.gpu_stages;
      if (std::find(list.begin(), list.end(), st["name"]) == list.end()) list.push_back(st["name"]);
    }
  return g;
}

std::vector<Group> stage_groups(const Sweep& sweep, const std::vector<json>& cells) {
  std::vector<Group> groups;
  for (const auto& c : deformlab::cells(sweep)) {
    Group g = group_of(c, cells, sweep.lattice);
    const bool seen = std::any_of(groups.begin(), groups.end(), [&](const Group& e) { return e.label == g.label; });
    if (!seen && !g.rows.empty()) groups.push_back(std::move(g));
  }
  return groups;
}

void write_stage_head(std::ostringstream& md, const Group& g, bool hands_off, const Ceilings& ceil) {
  md << "### " << g.label << "\n\n| " << (g.rows.front()->contains("model") ? "model" : "grid") << " | step ms |";
  for (const auto& st : g.gpu_stages) md << " " << st << " ms |";
  md << " rest ms |";
  for (const auto& st : g.host_stages) md << " " << st << " (CPU) ms |";
  if (hands_off) md << " rest per hand-off µs |" << (ceil.floor_us > 0 ? " x floor |" : "");
  md << "\n|---|---|";
  const std::size_t ncols =
      g.gpu_stages.size() + 1 + g.host_stages.size() + (hands_off ? (ceil.floor_us > 0 ? 2 : 1) : 0);
  for (std::size_t k = 0; k < ncols; ++k) md << "---|";
  md << "\n";
}

// One cell's row of its group's table; returns its bar (% of the step per GPU stage, rest). A
// rest per hand-off under the floor is marked, and the cell and its rest's share of the step
// added to `under_floor`.
plot::Stack write_stage_row(std::ostringstream& md, const Group& g, const json& r, const Ceilings& ceil,
                            std::vector<std::string>& under_floor) {
  const PipelineTraits& traits = traits_of(g.pipeline);
  const Integrator integ = *parse_integrator(g.integrator);
  const double step = r["median_ms"].get<double>();
  auto stage_ms = [&](const std::string& st) -> std::optional<double> {
    for (const auto& e : r["stages"])
      if (e["name"] == st) return e["median_ms"].get<double>();
    return std::nullopt;
  };
  md << "| " << cell_label(r, g.lattice) << " | " << fmt(step) << " |";
  plot::Stack bar{cell_label(r, g.lattice) + " " + fmt(step) + " ms", {}};
  const double adjacency_b = r.contains("model") ? mesh_adjacency_bytes(r["nodes"], r["springs"]) : 0;
  double gpu = 0;
  for (const auto& st : g.gpu_stages) {
    const auto v = stage_ms(st);
    bar.parts.push_back(v ? 100 * *v / step : 0);
    if (!v) {
      md << " - |";
      continue;
    }
    gpu += *v;
    md << " " << fmt(*v);
    if (const auto b = stage_ceiling(ceil, traits, st, r["nodes"].get<std::int64_t>(), integ, adjacency_b))
      md << " (" << percent(100 * b->ms / *v) << ")";
    md << " |";
  }
  const double rest = std::max(0.0, step - gpu);
  md << " " << fmt(rest) << " |";
  bar.parts.push_back(100 * rest / step);
  for (const auto& st : g.host_stages) {
    const auto v = stage_ms(st);
    md << " " << (v ? fmt(*v) : "-") << " |";
  }
  if (traits.hands_off()) {
    const double per = rest / (2.0 * info(integ).force_passes) * 1e3;
    md << " " << fmt(per) << " |";
    if (ceil.floor_us > 0) {
      const bool under = per < ceil.floor_us;
      md << " " << fmt(per / ceil.floor_us) << (under ? " \\*" : "") << " |";
      if (under) under_floor.push_back(cell_label(r, g.lattice) + ": rest " + percent(100 * rest / step) + " of the step");
    }
  }
  md << "\n";
  return bar;
}

void write_stage_group(std::ostringstream& md, const fs::path& dir, const std::string& name, const Group& g,
                       const Ceilings& ceil) {
  write_stage_head(md, g, traits_of(g.pipeline).hands_off(), ceil);
  std::vector<plot::Stack> bars;
  std::vector<std::string> under_floor;
  for (const json* r : g.rows) bars.push_back(write_stage_row(md, g, *r, ceil, under_floor));
  if (!under_floor.empty()) {
    md << "\n\\* Under the floor: the rest is the timed step less stages profiled in another batch (one launch "
          "at a time), set against a floor calibrated apart, so a rest under it comes from the differences "
          "between those measurements, not from faster hand-offs (";
    for (std::size_t k = 0; k < under_floor.size(); ++k) md << (k ? "; " : "") << under_floor[k];
    md << ").\n";
  }
  std::vector<std::string> parts = g.gpu_stages;
  parts.push_back("rest");
  std::string file = stages_file(g.label);
  for (char& ch : file)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '.') ch = '_';
  plot::stacked_bars(dir / file, name + ": " + g.label, "% of the timed step (stages profiled apart)", parts, bars);
  md << "\n![" << g.label << " stages](" << file << ")\n\n";
}

}  // namespace

void write_ceiling_table(std::ostringstream& md, const std::vector<Column>& columns, const Results& results,
                         const Ceilings& ceil, bool lattice) {
  const Bounded b = bounded_columns(columns, results, ceil);
  if (b.columns.empty()) return;
  md << "Against the ceilings calibrated on " << ceil.device
     << " (cells measured on another device do not compare): the least time a step could take (ms) and the "
        "measured step's fraction of it (ceiling / measured; 100% = at the ceiling).\n\n| grid |";
  for (const Column* c : b.columns) md << " " << c->label << " |";
  md << "\n|---|";
  for (std::size_t k = 0; k < b.columns.size(); ++k) md << "---|";
  md << "\n";
  for (int n : results.sizes()) {
    md << "| " << size_label(n, lattice) << " |";
    for (const Column* c : b.columns) {
      const json* r = results.ok(c->pipeline, c->integrator, c->options, n);
      if (!r) {
        md << " - |";
        continue;
      }
      const auto bound = step_ceiling(ceil, *c, (*r)["nodes"].get<std::int64_t>());
      md << " " << fmt(bound->ms) << " (" << percent(100 * bound->ms / (*r)["median_ms"].get<double>()) << ") |";
    }
    md << "\n";
  }
  md << "\nCeilings:";
  for (const auto& [what, labels] : b.by_bound) {
    md << "\n- ";
    for (std::size_t k = 0; k < labels.size(); ++k) md << (k ? ", " : "") << labels[k];
    md << ": " << what;
  }
  md << "\n\n";
}

void write_stages(std::ostringstream& md, const fs::path& dir, const std::string& name, const Sweep& sweep,
                  const std::vector<json>& cells, const Ceilings& ceil) {
  const std::vector<Group> groups = stage_groups(sweep, cells);
  if (groups.empty()) return;
  md << "## Where a step's time goes\n\n"
        "Stage times are medians per step over one more batch run with the profiler attached, each by the "
        "clock its pipeline times stages with (CUDA events; GL timer queries, or the host clock after glFinish "
        "on a software renderer, whose timer queries mean nothing); \"rest\" is the timed step less its GPU "
        "stages: hand-offs, "
        "waits and launch gaps. Host-clock columns are CPU time inside those calls. The stages run one launch "
        "at a time there, where the timed steps may replay a graph, so at small sizes they can add up to more "
        "than the step (bars past 100%).";
  if (ceil.any()) md << " In brackets: the stage's ceiling / its time (ceilings.hpp; 100% = at the ceiling).";
  md << "\n\n";
  for (const Group& g : groups) write_stage_group(md, dir, name, g, ceil);
}

}  // namespace deformlab::report
