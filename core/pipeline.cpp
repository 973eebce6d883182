#include "pipeline.hpp"

#include <stdexcept>

namespace deformlab {

void PipelineRegistry::add(PipelineEntry e) {
  if (find(e.name)) throw std::logic_error("pipeline registered twice: " + e.name);
  entries_.push_back(std::move(e));
}

const PipelineEntry* PipelineRegistry::find(const std::string& name) const {
  for (const auto& e : entries_)
    if (e.name == name) return &e;
  return nullptr;
}

std::string PipelineRegistry::names() const {
  std::string s;
  for (const auto& e : entries_) s += (s.empty() ? "" : ", ") + e.name;
  return s;
}

}  // namespace deformlab
