// The parts of a sweep's report (report.cpp): number formats, the cells' results, and the
// sections on ceilings and stages (report_stages.cpp).
#pragma once
#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "ceilings.hpp"
#include "sweep.hpp"

namespace deformlab::report {

std::string fmt(double v);      // about 3 significant digits
std::string percent(double v);  // "41%", "2.6%", "0.25%"
std::string options_label(const nlohmann::json& options);  // "name=value, ..."

// Footnotes for cells not measured, one per distinct reason, listing where it applies.
class Notes {
 public:
  // The reason's footnote number.
  std::size_t add(const std::string& reason, const std::string& where) {
    for (std::size_t k = 0; k < notes_.size(); ++k)
      if (notes_[k].first == reason) {
        notes_[k].second.push_back(where);
        return k + 1;
      }
    notes_.push_back({reason, {where}});
    return notes_.size();
  }
  void write(std::ostringstream& md) const {
    if (notes_.empty()) return;
    md << "## Notes on cells\n\n";
    for (std::size_t k = 0; k < notes_.size(); ++k) {
      md << "[" << k + 1 << "] " << notes_[k].first << " (";
      for (std::size_t w = 0; w < notes_[k].second.size(); ++w) md << (w ? ", " : "") << notes_[k].second[w];
      md << ")\n\n";
    }
  }

 private:
  std::vector<std::pair<std::string, std::vector<std::string>>> notes_;
};

// "64²" for a grid cell's result ("16³" on a lattice), "sheet-1m rcm" for a mesh model's.
std::string cell_label(const nlohmann::json& cell, bool lattice);

// The cells' results by (pipeline, integrator, options, size); a later cell of the same key
// replaces an earlier one.
class Results {
 public:
  explicit Results(const std::vector<nlohmann::json>& cells);
  // The cell of that key, whatever its status; null when there is none.
  const nlohmann::json* find(const std::string& pipeline, const std::string& integrator,
                             const nlohmann::json& options, int size) const;
  // The same, only when it was measured.
  const nlohmann::json* ok(const std::string& pipeline, const std::string& integrator, const nlohmann::json& options,
                           int size) const;
  const std::set<int>& sizes() const { return sizes_; }
  std::int64_t nodes(int size) const;  // as the cells of that size record it; 0 when none does

 private:
  std::map<std::string, const nlohmann::json*> at_;
  std::set<int> sizes_;
  std::map<int, std::int64_t> nodes_at_;
};

// One column of a results table: a pipeline, integrator and option set.
struct Column {
  std::string label, pipeline, integrator;
  nlohmann::json options;
};

// Each measured step of `columns` against its ceiling (ceiling / measured); nothing when no
// column has a ceiling and a measurement.
void write_ceiling_table(std::ostringstream& md, const std::vector<Column>& columns, const Results& results,
                         const Ceilings& ceil, bool lattice);

// "Where a step's time goes": per pipeline, integrator and option set whose cells timed
// their stages, each stage per step against its ceiling, the rest of the step (per hand-off
// against the floor where the pipeline hands off), and stacked bars of the split drawn
// into `dir`.
void write_stages(std::ostringstream& md, const std::filesystem::path& dir, const std::string& name,
                  const Sweep& sweep, const std::vector<nlohmann::json>& cells, const Ceilings& ceil);

// Model sweeps: per integrator and mesh model, a table of pipelines (rows) by node order
// (columns) in ms per step, each against the memory floor of a mesh step; the order, force
// variant and hybrid ratios; and a reading of them appended to `reading`.
void write_model_tables(std::ostringstream& md, const Sweep& sweep, const std::vector<nlohmann::json>& cells,
                        const Ceilings& ceil, Notes& notes, std::vector<std::string>& reading);

}  // namespace deformlab::report
