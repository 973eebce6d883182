// The Markdown report of a sweep's results folder: a table per integrator (or, for the
// paper's Table 3, per pipeline) with the paper's figures and ratio columns beside ours,
// log-log plots as SVG files, and a short reading of which of the paper's orderings hold.
#pragma once
#include <filesystem>

namespace deformlab {

// Reads `dir`/manifest.json and `dir`/cells/*.json; writes `dir`/report.md and its plots.
// Returns the report's path.
std::filesystem::path write_report(const std::filesystem::path& dir);

}  // namespace deformlab
