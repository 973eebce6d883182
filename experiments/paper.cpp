#include "paper.hpp"

#include <iomanip>
#include <map>
#include <sstream>

namespace deformlab::paper {

namespace {

struct Table {
  std::vector<Column> columns;
  std::map<int, std::vector<double>> rows;  // size -> one figure per column, < 0: n/a
  std::vector<Ratio> ratios;
};

const std::map<std::string, Table>& tables() {
  static const std::map<std::string, Table> t = {
      {"table1",
       {{{"cpu", "explicit-euler", "paper unoptimised"}, {"omp", "explicit-euler", "paper OpenMP"}},
        {{64, {1408.45, 99.90}},
         {128, {5263.16, 368.83}},
         {256, {16666.67, 1515.15}},
         {512, {-1, 5000.04}},
         {1024, {-1, 200000.00}}},
        {{"cpu", "omp", "cpu/omp"}}}},
      {"table2",
       {{{"omp", "explicit-euler", "paper (a) CPU"},
         {"cuda-naive", "explicit-euler", "paper (b) CUDA"},
         {"cuda-tiled", "explicit-euler", "paper (c) CUDA shared"},
         {"glsl-tf", "explicit-euler", "paper (d) TF"}},
        {{64, {99.90, 4.05, 2.557, 1.07}},
         {128, {396.82, 4.92, 3.126, 1.47}},
         {256, {1515.15, 6.99, 5.742, 3.34}},
         {512, {5000.00, 31.06, 9.861, 11.65}},
         {1024, {200000.00, 133.69, 38.957, 54.76}},
         {2048, {-1, 699.31, 172.408, 265.25}}},
        {{"omp", "glsl-tf", "a/d"}, {"cuda-naive", "glsl-tf", "b/d"}, {"cuda-tiled", "glsl-tf", "c/d"}}}},
      {"table3",
       {{{"glsl-tf", "explicit-euler", "paper explicit Euler"},
         {"glsl-tf", "semi-implicit-euler", "paper \"implicit\" Euler"},
         {"glsl-tf", "midpoint", "paper midpoint"},
         {"glsl-tf", "rk4", "paper \"RK4\""},
         {"glsl-tf", "verlet", "paper Verlet"}},
        {{64, {1.07, 0.867, 0.905, 1.151, 0.853}},
         {128, {1.47, 1.817, 1.806, 1.895, 1.793}},
         {256, {3.34, 3.409, 3.464, 3.678, 3.107}},
         {512, {11.65, 11.588, 11.088, 11.957, 11.027}},
         {1024, {54.76, 54.288, 54.436, 55.157, 53.705}},
         {2048, {265.25, 274.725, 271.739, 327.868, 258.397}}},
        {}}},
  };
  return t;
}

}  // namespace

const std::vector<Column>& columns(const std::string& table) {
  static const std::vector<Column> none;
  const auto it = tables().find(table);
  return it == tables().end() ? none : it->second.columns;
}

std::optional<double> figure(const std::string& table, const Column& c, int size) {
  const auto it = tables().find(table);
  if (it == tables().end()) return std::nullopt;
  const auto row = it->second.rows.find(size);
  if (row == it->second.rows.end()) return std::nullopt;
  const auto& cols = it->second.columns;
  for (std::size_t k = 0; k < cols.size(); ++k)
    if (cols[k].pipeline == c.pipeline && cols[k].integrator == c.integrator)
      return row->second[k] < 0 ? std::nullopt : std::optional<double>(row->second[k]);
  return std::nullopt;
}

const std::vector<Ratio>& ratios(const std::string& table) {
  static const std::vector<Ratio> none;
  const auto it = tables().find(table);
  return it == tables().end() ? none : it->second.ratios;
}

std::string note(const std::string& table) {
  if (table != "table1" && table != "table2") return "";
  // The same OpenMP CPU: Table 1's second column and Table 2's first.
  const auto& one = tables().at("table1").rows;
  const auto& two = tables().at("table2").rows;
  std::ostringstream sizes;
  sizes << std::fixed << std::setprecision(2);  // as the paper prints them
  for (const auto& [n, figures] : one)
    if (const auto it = two.find(n); it != two.end() && figures[1] > 0 && it->second[0] > 0 && figures[1] != it->second[0])
      sizes << (sizes.tellp() > 0 ? ", " : "") << n << "² (" << figures[1] << " against " << it->second[0] << " ms)";
  if (sizes.tellp() == 0) return "";
  return "The paper prints its OpenMP CPU's times differently in Table 1 and in Table 2's column (a) at " +
         sizes.str() + "; each table's figures are given here as printed.";
}

}  // namespace deformlab::paper
