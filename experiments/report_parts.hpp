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
                         const Ceilings& ceil);

// "Where a step's time goes": per pipeline, integrator and option set whose cells timed
// their stages, each stage per step against its ceiling, the rest of the step (per hand-off
// against the floor where the pipeline hands off), and stacked bars of the split drawn
// into `dir`.
void write_stages(std::ostringstream& md, const std::filesystem::path& dir, const std::string& name,
                  const Sweep& sweep, const std::vector<nlohmann::json>& cells, const Ceilings& ceil);

}  // namespace deformlab::report
