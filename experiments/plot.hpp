// Plots written as SVG files (any browser or image viewer opens them; no dependencies).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace deformlab::plot {

struct Series {
  std::string label;
  std::vector<double> x, y;  // points with y > 0; others are gaps
  bool dashed = false;
};

// A log-log line plot, one line per series.
void loglog(const std::filesystem::path& file, const std::string& title, const std::string& xlabel,
            const std::string& ylabel, const std::vector<Series>& series);

// Stacked bars: one bar per category, one stack segment per part (values >= 0).
struct Stack {
  std::string category;
  std::vector<double> parts;
};
void stacked_bars(const std::filesystem::path& file, const std::string& title, const std::string& ylabel,
                  const std::vector<std::string>& part_names, const std::vector<Stack>& bars);

// The step between the gridlines of a linear axis from 0 past `top` (> 0): the largest of 1,
// 2, 2.5 and 5 times a power of ten that is at most top / 4, so 4 to 8 steps reach it.
double tick_step(double top);

}  // namespace deformlab::plot
