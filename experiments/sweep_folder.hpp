// A results folder's earlier runs of a sweep and what a new run may do with them: which cells
// were measured as this run would measure them, whether its frames show this run's scene, and
// what in the folder is not the experiment's to replace.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "experiment.hpp"
#include "sweep.hpp"

namespace deformlab {

// What a cell's result depends on beyond the cell itself: the experiment's scene as resolved
// (after its base) and the sweep's method (warmup, steps, repetitions, cell_limit_s, time).
// The manifest records it as "measurement"; each cell records cell_measurement(), which adds
// a mesh model's JSON for that model's cells.
nlohmann::json measurement(const Experiment& x, const Sweep& s);
nlohmann::json cell_measurement(const nlohmann::json& measurement, const Sweep& s, const std::string& model);
// Whether cell result `cell` was measured as `measurement` (a manifest's) says; a cell that
// records none predates the record and counts as measured so.
bool measured_as(const nlohmann::json& cell, const nlohmann::json& measurement, const Sweep& s);

// What the frames show: the experiment's scene and integrator, and how many the sweep asks for.
nlohmann::json frames_measurement(const Experiment& x, const Sweep& s);
// Whether the frames in `dir` that its earlier manifest `old` records are this sweep's.
bool frames_kept(const std::filesystem::path& dir, const nlohmann::json& old, const Experiment& x, const Sweep& s);

// Gives each cell in `dir` that records no measurement the one its manifest `old` implies:
// this sweep's where that manifest's experiment is this one's JSON, else a mark of the earlier
// experiment, so that neither this run nor its report takes it for one of this scene's.
void record_earlier_measurements(const std::filesystem::path& dir, const nlohmann::json& old, const Experiment& x,
                                 const Sweep& s);

// Throws std::invalid_argument, before sweep `s` runs into `dir`, where it would write over or
// remove what no experiment wrote: in a folder that holds no experiment's results (its manifest
// names none), a report, plot, manifest.json or frames/ of its own, or a file in cells/ that is
// not a cell result; in one that does, a file in cells/ that is neither a cell result nor named
// as one of the sweep's cells, or, where the frames are to be rendered again, an entry of
// frames/ that no run writes; in either, what is not a file where a cell's file, the report, a
// plot or manifest.json goes.
void require_sweep_folder(const std::filesystem::path& dir, const Experiment& x, const Sweep& s);
// Throws std::invalid_argument where `dir` holds something other than a file (a folder, say) in
// the place of its report, a plot or manifest.json (require_sweep_folder checks it too; so does
// --report-only, which writes only those).
void require_report_targets(const std::filesystem::path& dir);

}  // namespace deformlab
