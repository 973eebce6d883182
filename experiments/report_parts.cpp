// Number formats and the cells' results for the report (report_parts.hpp).
#include <cmath>
#include <iomanip>

#include "report_parts.hpp"

#include "core/number_text.hpp"

namespace deformlab::report {

using nlohmann::json;

std::string fmt(double v) {
  std::ostringstream os;
  if (v >= 100) os << std::fixed << std::setprecision(1) << v;
  else if (v >= 1) os << std::fixed << std::setprecision(3) << v;
  else os << significant_trimmed(v, 3);
  return os.str();
}

std::string percent(double v) {
  std::ostringstream os;
  if (v >= 10) os << std::lround(v);
  else if (v >= 1) os << std::fixed << std::setprecision(1) << v;
  else os << significant_trimmed(v, 2);
  return os.str() + "%";
}

std::string options_label(const json& o) {
  std::string s;
  for (const auto& [k, v] : o.items()) s += (s.empty() ? "" : ", ") + k + "=" + v.get<std::string>();
  return s;
}

std::string cell_label(const json& c, bool lattice) {
  std::ostringstream label;  // not string concatenation: GCC 12 warns falsely (-Wrestrict) on that
  if (!c.contains("model")) {
    label << size_label(c["size"].get<int>(), lattice);
  } else {
    label << c["model"].get<std::string>();
    if (c.contains("order")) label << " " << c["order"].get<std::string>();
  }
  return label.str();
}

namespace {

std::string key(const std::string& p, const std::string& i, const json& o, int n) {
  return p + "|" + i + "|" + o.dump() + "|" + std::to_string(n);
}

}  // namespace

Results::Results(const std::vector<json>& cells) {
  for (const auto& c : cells) {
    at_[key(c["pipeline"], c["integrator"], c["options"], c["size"])] = &c;
    sizes_.insert(c["size"].get<int>());
    if (c.contains("nodes")) nodes_at_[c["size"].get<int>()] = c["nodes"].get<std::int64_t>();
  }
}

const json* Results::find(const std::string& p, const std::string& i, const json& o, int n) const {
  const auto it = at_.find(key(p, i, o, n));
  return it == at_.end() ? nullptr : it->second;
}

const json* Results::ok(const std::string& p, const std::string& i, const json& o, int n) const {
  const json* r = find(p, i, o, n);
  return r && (*r)["status"] == "ok" ? r : nullptr;
}

std::int64_t Results::nodes(int size) const {
  const auto it = nodes_at_.find(size);
  return it == nodes_at_.end() ? 0 : it->second;
}

}  // namespace deformlab::report

