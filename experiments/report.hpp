// The Markdown report of a sweep's results folder: a table per integrator (or, for the
// paper's Table 3, per pipeline) with the paper's figures and ratio columns beside ours,
// log-log plots as SVG files, and a short reading of which of the paper's orderings hold.
#pragma once
#include <filesystem>
#include <string>

namespace deformlab {

// Reads `dir`/manifest.json and `dir`/cells/*.json; writes `dir`/report.md and its plots.
// Returns the report's path.
std::filesystem::path write_report(const std::filesystem::path& dir);

// The files write_report writes: report.md, plot-TITLE.svg and stages-LABEL.svg.
inline constexpr const char* kReportFile = "report.md";
inline std::string plot_file(const std::string& title) { return std::string("plot-").append(title).append(".svg"); }
inline std::string stages_file(const std::string& label) { return std::string("stages-").append(label).append(".svg"); }
inline bool is_report_file(const std::string& name) {
  return name == kReportFile || (name.ends_with(".svg") && (name.starts_with("plot-") || name.starts_with("stages-")));
}

}  // namespace deformlab
