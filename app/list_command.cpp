#include <iomanip>
#include <iostream>

#include "commands.hpp"
#include "core/integrator.hpp"
#include "experiments/experiment.hpp"
#include "experiments/pipelines.hpp"

namespace deformlab::app {

int list_command() {
  std::cout << "Pipelines (in order of their step time on a 2048^2 cloth on an H100; 'best' picks the first "
               "available, passing over GL on a software rasteriser):\n";
  for (const auto& e : pipelines().all()) {
    const std::string why = e.unavailable();
    std::cout << "  " << std::left << std::setw(15) << e.name << (why.empty() ? "available    " : "unavailable  ")
              << e.summary << (e.traits.deterministic ? "" : " [not bitwise deterministic]")
              << (on_software_gl(e) ? " [software GL: slower than the CPU pipelines here]" : "") << "\n";
    if (!e.options.empty()) {
      std::cout << "  " << std::setw(15) << "" << "  options:";
      for (const auto& o : e.options) std::cout << " " << o << "=" << option_values(e, o);
      std::cout << "\n";
    }
    if (!why.empty()) {
      std::cout << "  " << std::setw(15) << "" << "  why: " << why << "\n";
      continue;
    }
    for (const auto& i : integrators())
      if (const auto no = e.unsupported(i.id); !no.empty())
        std::cout << "  " << std::setw(15) << "" << "  no " << i.name << ": " << no << "\n";
  }
  const Integrator usual = *parse_integrator(default_experiment().integrator);
  std::cout << "\n'best' here: " << best_pipeline(usual).name << " (for " << info(usual).name
            << ", the main job's integrator)\n";
  std::cout << "\nIntegrators (name, the paper's name also accepted, force passes per step, order):\n";
  for (const auto& i : integrators())
    std::cout << "  " << std::left << std::setw(21) << i.name << std::setw(18)
              << (i.paper_alias.empty() ? "-" : std::string(i.paper_alias)) << std::setw(10)
              << (std::to_string(i.force_passes) + (i.id == Integrator::backward_euler ? " + solve" : "")) << i.order
              << "  " << i.summary << "\n";
  return 0;
}

}  // namespace deformlab::app
