// The report's tables of a model sweep (report_parts.hpp): mesh models x node orders.
#include <algorithm>
#include <map>
#include <optional>

#include "report_parts.hpp"

namespace deformlab::report {

using nlohmann::json;

namespace {

// A row of a model table: a pipeline and option set.
struct Row {
  std::string label, pipeline;
  json options;
};

// The sweep's cells of one integrator by (model, order the sweep names or "", row label).
class ModelResults {
 public:
  ModelResults(const Sweep& s, const std::vector<json>& cells, const std::string& integrator) {
    for (const auto& c : cells)
      if (c.contains("model") && c["integrator"] == integrator) {
        const std::string order = s.orders.empty() ? "" : c.value("order", std::string());
        at_[key(c["model"], order, label(c["pipeline"], c["options"]))] = &c;
      }
  }
  const json* find(const std::string& model, const std::string& order, const std::string& row) const {
    const auto it = at_.find(key(model, order, row));
    return it == at_.end() ? nullptr : it->second;
  }
  std::optional<double> ms(const std::string& model, const std::string& order, const std::string& row) const {
    const json* c = find(model, order, row);
    if (!c || (*c)["status"] != "ok") return std::nullopt;
    return (*c)["median_ms"].get<double>();
  }
  static std::string label(const std::string& pipeline, const json& options) {
    return options.empty() ? pipeline : pipeline + " [" + options_label(options) + "]";
  }

 private:
  static std::string key(const std::string& m, const std::string& o, const std::string& r) { return m + "|" + o + "|" + r; }
  std::map<std::string, const json*> at_;
};

std::vector<Row> rows_of(const Sweep& sweep) {
  std::vector<Row> rows;
  for (const auto& c : cells(sweep)) {
    const std::string label = ModelResults::label(c.pipeline, json(c.options));
    if (std::none_of(rows.begin(), rows.end(), [&](const Row& r) { return r.label == label; }))
      rows.push_back({label, c.pipeline, json(c.options)});
  }
  return rows;
}

// The orders of the sweep; "" (each model's own) when it names none.
std::vector<std::string> orders_of(const Sweep& s) { return s.orders.empty() ? std::vector<std::string>{""} : s.orders; }

// What the model's cells recorded (nodes, springs, kind), from the first that has them.
const json* facts(const ModelResults& res, const Sweep& s, const std::string& model, const std::vector<Row>& rows) {
  for (const auto& o : orders_of(s))
    for (const auto& r : rows)
      if (const json* c = res.find(model, o, r.label); c && c->contains("bandwidth")) return c;
  return nullptr;
}

// A ratio of two measured times, or "-".
// A table's header: `first`, then a column per name, and the separator row.
void header(std::ostringstream& md, const std::string& first, const std::vector<std::string>& columns) {
  md << "| " << first << " |";
  for (const auto& c : columns) md << " " << c << " |";
  md << "\n|---|";
  for (std::size_t k = 0; k < columns.size(); ++k) md << "---|";
}

// The order columns' names ("" is the model's own order).
std::vector<std::string> order_names(const std::vector<std::string>& orders) {
  std::vector<std::string> out;
  for (const auto& o : orders) out.push_back(o.empty() ? "own order" : o);
  return out;
}

std::string ratio(std::optional<double> a, std::optional<double> b) { return a && b ? fmt(*a / *b) : "-"; }

// The largest and smallest of `ratios` (label, value) as "r (label)" phrases.
std::string extremes(std::vector<std::pair<std::string, double>> ratios) {
  if (ratios.empty()) return "";
  std::sort(ratios.begin(), ratios.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  const auto& lo = ratios.front();
  const auto& hi = ratios.back();
  if (ratios.size() == 1) return fmt(hi.second) + "x on " + hi.first;
  return fmt(hi.second) + "x on " + hi.first + " (the most) to " + fmt(lo.second) + "x on " + lo.first + " (the least)";
}

struct ModelTable {
  const Sweep& sweep;
  const ModelResults& res;
  const std::vector<Row>& rows;
  const Ceilings& ceil;
  Notes& notes;
  std::vector<std::string>& reading;
  std::string model;
};

void write_times(std::ostringstream& md, ModelTable& t, const json* f) {
  const auto orders = orders_of(t.sweep);
  const std::int64_t n = f ? (*f)["nodes"].get<std::int64_t>() : 0, s = f ? (*f)["springs"].get<std::int64_t>() : 0;
  const double bytes = 64 + mesh_adjacency_bytes(n, s);
  std::optional<double> floor_ms;
  if (f && t.ceil.copy_gb_s > 0) floor_ms = bytes * double(n) / (t.ceil.copy_gb_s * 1e9) * 1e3;
  if (f) {
    md << (*f)["mesh"].get<std::string>() << ", " << n << " nodes, " << s << " springs (" << fmt(2.0 * double(s) / double(n))
       << " spring ends a node). Bytes a mesh step moves per node and force evaluation (a CSR gather): x, v read "
          "and written (64 B), the adjacency offsets (4 B) and a 16-byte link per spring end: 68 + 32 s/n = "
       << fmt(bytes) << " B";
    if (floor_ms) md << "; the floor, those bytes at the CUDA copy bandwidth (" << fmt(t.ceil.copy_gb_s) << " GB/s): " << fmt(*floor_ms) << " ms";
    md << ".\n\n";
  }
  // Each order's bandwidth (the largest index difference of a spring's ends), outside the times.
  std::string widths;
  for (const auto& o : orders) {
    const json* c = nullptr;
    for (const auto& r : t.rows)
      if (const json* e = t.res.find(t.model, o, r.label); e && e->contains("bandwidth")) c = e;
    if (c) widths += (widths.empty() ? "" : ", ") + o + " " + std::to_string((*c)["bandwidth"].get<std::int64_t>());
  }
  if (!widths.empty())
    md << "Node-index bandwidth (the largest difference of a spring's two node indices) by order: " << widths
       << ".\n\n";
  header(md, "pipeline", order_names(orders));
  md << "\n";
  for (const auto& r : t.rows) {
    md << "| " << r.label << " |";
    for (const auto& o : orders) {
      const json* c = t.res.find(t.model, o, r.label);
      if (!c) md << " - |";
      else if ((*c)["status"] != "ok")
        md << " n/a [" << t.notes.add((*c)["reason"], r.label + " " + cell_label(*c, false /* a mesh model's cell */)) << "] |";
      else {
        const double ms = (*c)["median_ms"].get<double>();
        md << " " << fmt(ms);
        if (floor_ms) md << " (" << percent(100 * *floor_ms / ms) << ")";
        md << " |";
      }
    }
    md << "\n";
  }
  md << "\nMs per step on each pipeline's step clock" << (floor_ms ? "; in brackets the floor / the step (100% = at the floor)" : "")
     << ".\n\n";
}

// Ratios against the file's order per row, and what they say.
void write_order_ratios(std::ostringstream& md, ModelTable& t) {
  const auto& orders = t.sweep.orders;
  if (std::find(orders.begin(), orders.end(), "file") == orders.end() || orders.size() < 2) return;
  md << "Node order against the file's (time / file-order time):\n\n";
  std::vector<std::string> others, titles;
  for (const auto& o : orders)
    if (o != "file") others.push_back(o), titles.push_back(o + " / file");
  header(md, "pipeline", titles);
  md << "\n";
  std::map<std::string, std::vector<std::pair<std::string, double>>> by_order;
  for (const auto& r : t.rows) {
    md << "| " << r.label << " |";
    const auto base = t.res.ms(t.model, "file", r.label);
    for (const auto& o : others) {
      const auto v = t.res.ms(t.model, o, r.label);
      md << " " << ratio(v, base) << " |";
      if (v && base) by_order[o].push_back({r.label, *v / *base});
    }
    md << "\n";
  }
  md << "\n";
  for (const auto& [o, list] : by_order)
    t.reading.push_back(t.model + ": " + o + " / file " + extremes(list));
}

// cuda-tiled and cuda-scatter against cuda-naive, the hybrids' force variants against naive,
// and the hybrids against the GL pipelines alone, per order.
void write_variant_ratios(std::ostringstream& md, ModelTable& t) {
  struct Pair {
    std::string num, den;
  };
  std::vector<Pair> pairs;
  auto has = [&](const std::string& label) {
    return std::any_of(t.rows.begin(), t.rows.end(), [&](const Row& r) { return r.label == label; });
  };
  auto add = [&](const std::string& a, const std::string& b) {
    if (has(a) && has(b)) pairs.push_back({a, b});
  };
  for (const char* v : {"tiled", "scatter"}) {
    add(std::string("cuda-") + v, "cuda-naive");
    for (const char* h : {"hybrid", "hybrid-compute"})
      add(std::string(h) + " [force=" + v + "]", std::string(h) + " [force=naive]");
  }
  for (const char* v : {"naive", "tiled", "scatter"}) {
    add(std::string("hybrid [force=") + v + "]", "glsl-tf");
    add(std::string("hybrid-compute [force=") + v + "]", "glsl-compute");
  }
  if (pairs.empty()) return;
  const auto orders = orders_of(t.sweep);
  md << "Force variants and hybrids (time / time; below 1 the first is faster):\n\n";
  header(md, "ratio", order_names(orders));
  md << "\n";
  for (const auto& p : pairs) {
    md << "| " << p.num << " / " << p.den << " |";
    std::vector<std::pair<std::string, double>> list;
    for (const auto& o : orders) {
      const auto a = t.res.ms(t.model, o, p.num), b = t.res.ms(t.model, o, p.den);
      md << " " << ratio(a, b) << " |";
      if (a && b) list.push_back({o.empty() ? "its own order" : o + " order", *a / *b});
    }
    md << "\n";
    if (list.empty()) continue;
    const bool pays = std::any_of(list.begin(), list.end(), [](const auto& e) { return e.second < 1; });
    const bool always = std::all_of(list.begin(), list.end(), [](const auto& e) { return e.second < 1; });
    t.reading.push_back(t.model + ": " + p.num + " / " + p.den + " " + extremes(list) + ": " + p.num +
                        (always ? " is faster in every order measured" : pays ? " is faster in some orders" : " is never faster"));
  }
  md << "\n";
}

// Where a hybrid step beats the GL pipeline it extends (the hybrid premise), over every model
// and order measured.
std::string hybrid_premise(const Sweep& sweep, const ModelResults& res, const std::vector<Row>& rows) {
  std::vector<std::string> holds;
  int compared = 0;
  for (const auto& m : sweep.models)
    for (const auto& o : orders_of(sweep))
      for (const auto& r : rows) {
        const std::string gl = r.pipeline == "hybrid" ? "glsl-tf" : r.pipeline == "hybrid-compute" ? "glsl-compute" : "";
        const auto a = gl.empty() ? std::nullopt : res.ms(m.name, o, r.label);
        const auto b = gl.empty() ? std::nullopt : res.ms(m.name, o, gl);
        if (!a || !b) continue;
        ++compared;
        if (*a < *b) holds.push_back(m.name + (o.empty() ? "" : " " + o) + " " + r.label + " (" + fmt(*a / *b) + "x " + gl + ")");
      }
  if (!compared) return "";
  std::string line = "The hybrid premise (CUDA forces and a GL update beat the GL pipeline alone): ";
  if (holds.empty()) return line + "holds in none of the " + std::to_string(compared) + " pairs measured";
  line += "holds in " + std::to_string(holds.size()) + " of " + std::to_string(compared) + " pairs measured: ";
  for (std::size_t k = 0; k < holds.size(); ++k) line += (k ? ", " : "") + holds[k];
  return line;
}

}  // namespace

void write_model_tables(std::ostringstream& md, const Sweep& sweep, const std::vector<json>& cells, const Ceilings& ceil,
                        Notes& notes, std::vector<std::string>& reading) {
  const std::vector<Row> rows = rows_of(sweep);
  for (const auto& integ : sweep.integrators) {
    const ModelResults res(sweep, cells, integ);
    for (const auto& m : sweep.models) {
      md << "## Model `" << m.name << "`" << (sweep.integrators.size() > 1 ? ", " + integ : "") << "\n\n";
      ModelTable t{sweep, res, rows, ceil, notes, reading, m.name};
      write_times(md, t, facts(res, sweep, m.name, rows));
      write_order_ratios(md, t);
      write_variant_ratios(md, t);
    }
    if (const std::string line = hybrid_premise(sweep, res, rows); !line.empty()) reading.push_back(line);
  }
}

}  // namespace deformlab::report
