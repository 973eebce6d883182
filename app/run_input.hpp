// `deformlab run`'s input: everything read and checked before anything is written.
#pragma once
#include <filesystem>

#include "commands.hpp"
#include "core/model.hpp"
#include "core/params.hpp"
#include "core/pipeline.hpp"
#include "experiments/experiment.hpp"

namespace deformlab::app {

struct RunInput {
  Experiment x;
  const PipelineEntry* entry = nullptr;
  Integrator integ{};
  PipelineOptions options;
  bool until_converged = false;
  Model model;
  Params params;
  double build_s = 0.0;  // building the model, host clock
  std::filesystem::path out;  // `run`'s output folder: --out, else runs/<experiment> (runs/<experiment>-run
                              // for an experiment with a sweep, whose folder is `experiment`'s)
};

// "128x96" -> {128, 96}: `dims` positive integers; throws std::invalid_argument naming `flag`.
std::vector<int> parse_size(const std::string& s, int dims, const char* flag);

// Reads the experiment or scene, applies the flags and builds the model; bad input
// (unknown names, bad sizes or numbers, a model too large for memory) throws
// std::invalid_argument with one line saying what is wrong.
// The flags' own values (sizes, dt, steps, ...), checked with no experiment read and no GL
// context made: `view` checks them before it opens its window.
void check_run_flags(const RunArgs& a);
// Refuses an output folder (of a run or an experiment) that is an empty path, lies on one of
// the kernel's own file systems (proc, sysfs, ...), which hold no files of ours, or where this
// process may not write (the nearest folder above it that exists, where it does not).
void require_writable(const std::filesystem::path& out);
// `run`'s output folder is checked first, before the model is built.
RunInput read_run_input(const RunArgs& a);
// `view`'s two halves of read_run_input, which writes no folder, the first before its window opens, so that
// bad input is named on a machine without a display too: read_run_model makes every check and
// builds the model, but leaves the pipeline unchosen where choosing it needs a GL context (`best`)
// and does not ask whether it runs here; resolve_pipeline, in the window's context, does both.
RunInput read_run_model(const RunArgs& a);
void resolve_pipeline(const RunArgs& a, RunInput& in);
// When a convergence run's stop rule starts (first_stop_step), in words.
std::string stop_rule_start(const Params& p);

}  // namespace deformlab::app
