// The paper's measurements (Movania & Feng 2012, Tables 1-3; Quadro FX 5800 and a 2.27 GHz
// Xeon, ms per frame including rendering), keyed by our pipeline and integrator names.
#pragma once
#include <optional>
#include <string>
#include <vector>

namespace deformlab::paper {

struct Column {
  std::string pipeline, integrator, label;  // label: the paper's column heading
};

const std::vector<Column>& columns(const std::string& table);  // empty for an unknown table
// ms per frame in the paper, nullopt where it has none (n/a or not measured).
std::optional<double> figure(const std::string& table, const Column& c, int size);
// The paper's ratio columns: pairs of pipelines (numerator, denominator) with labels.
struct Ratio {
  std::string num, den, label;
};
const std::vector<Ratio>& ratios(const std::string& table);
// What a reader of the table's paper figures should know ("" for none).
std::string note(const std::string& table);

}  // namespace deformlab::paper
