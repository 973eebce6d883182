// Run outputs. Files are written into a staging folder inside the output folder and moved
// into place only when the whole run succeeded, so a failed run leaves the folder as it was;
// manifest.json goes first out and last in, so a folder whose outputs are complete is one
// with a manifest. Temporaries of killed processes are reclaimed by the next one.
#pragma once
#include <filesystem>
#include <functional>
#include <set>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/energy.hpp"
#include "core/model.hpp"
#include "core/run.hpp"
#include "core/scene.hpp"
#include "core/state.hpp"

namespace deformlab {

// Throws std::invalid_argument, naming `what`, where `path` holds a name longer than a file
// name may be (NAME_MAX, 255 bytes; the last name 25 less, for its temporary's suffix) or is
// itself longer than a path may be (PATH_MAX), less `inside` bytes for the paths below it.
void require_name_lengths(const std::filesystem::path& path, const std::string& what, std::size_t inside = 0);
// Throws std::invalid_argument when `dir` exists and is not a folder, or its name is too long,
// or its path leaves too little room for the paths of the files written inside it.
void require_folder_or_nothing(const std::filesystem::path& dir);

// `dir`/manifest.json, or null when there is none or it is not JSON.
nlohmann::json read_manifest(const std::filesystem::path& dir);

// What a folder holds, by its manifest: one run's outputs (the manifest names its experiment),
// an experiment's results (the manifest holds the experiment, or a sweep left cells/ before
// writing one), or neither. One folder holds one of them.
enum class Holds { nothing, run, experiment };
Holds folder_holds(const std::filesystem::path& dir);
// Throws std::invalid_argument when `dir` holds the other kind of output than `want`, or lies
// inside a folder whose manifest, as deformlab writes it, says it holds either (a run's frames, an
// experiment's cells).
void require_holds_nothing_but(const std::filesystem::path& dir, Holds want);

// The first entry of the frames folder `frames` that no run writes there (frame_*.png,
// frames.mp4), or "" (also where there is no such folder): a folder that holds one is not
// removed or replaced.
std::string foreign_frames_entry(const std::filesystem::path& frames);

// Throws std::invalid_argument where `file`, named by `what` (a flag), could not be written: an
// empty name, a name too long, a folder in its place, or require_file_can_be_made's causes.
void require_file_target(const std::string& file, const std::string& what);
// Throws std::invalid_argument, naming `what`, where no file can be made in the folder that is to
// hold `file`, or, where that folder is not there yet, in the nearest folder above it that is
// (one the process may not write, a file system that takes none), or where that is a file.
void require_file_can_be_made(const std::string& file, const std::string& what);
// The temporary name of `name` for this process: "<name>.deformlab-tmp-<pid>". The names of
// temporaries and staging folders (".deformlab-staging-<pid>") are ours alone: a folder's other
// files are never taken for them.
std::filesystem::path temporary(const std::filesystem::path& name);
// Writes `file` whole or not at all, making its folders: into its temporary, renamed over it
// once written (on a failure the temporary is removed and write_error's words thrown, naming
// `file`). A file there that is no regular file (a pipe, a device) is written to as it is.
void write_atomically(const std::filesystem::path& file, const std::string& text);
// Makes the folder that is to hold `file`; returns the folders it made, the deepest first, for
// remove_made_folders. Throws write_error's words, naming `file`, where one cannot be made.
std::vector<std::filesystem::path> make_folders_for(const std::filesystem::path& file);
// Removes those of `made` (make_folders_for's) that are empty, from the deepest up to one that
// is not.
void remove_made_folders(const std::vector<std::filesystem::path>& made);
// Whether `name` is a temporary's.
bool is_temporary(const std::string& name);
// Removes the temporaries and staging folders in `dir` whose process is gone.
void reclaim_temporaries(const std::filesystem::path& dir);

class OutputDir {
 public:
  // Creates `dir` if needed (throws std::invalid_argument if it is not a usable folder, holds
  // a file where an output has a folder or the other way round, or a manifest.json that is no
  // run's). A commit that was stopped in `dir` is finished first.
  // `outputs`: every name such an output may hold besides manifest.json, a folder's ending in
  // '/'; those the folder's earlier run wrote (its manifest's "files") and the new one does not
  // write, commit() removes, so that the folder holds one output's files; all else is left
  // alone. `writes`: those of `outputs` this output will write; each that is in the folder
  // already must be the earlier run's, else it is someone else's and std::invalid_argument is
  // thrown rather than replace it.
  OutputDir(const std::filesystem::path& dir, std::vector<std::string> outputs, const std::vector<std::string>& writes);
  // Removes the staging folder (unless a commit failed part way), and the folders the
  // constructor made (the output folder and any above it) that nothing was committed into.
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  // Where to write a file or folder named `name` before commit().
  std::filesystem::path staged(const std::string& name) const { return staging_ / name; }
  // Moves every staged entry into the output folder (replacing entries of the same name):
  // the old output's files the new one lacks are moved aside first (into a temporary folder,
  // removed at the end), then the old manifest.json is removed, and the new manifest is moved in
  // last. Where an entry of the other kind (file or folder) has appeared in the way since, or
  // the old files cannot be moved aside or the old manifest removed, throws std::runtime_error
  // with the folder as it was and the outputs moved to `dir`/unsaved-run-<pid>. Where a removal
  // or rename fails after that, throws std::runtime_error and keeps the staging folder, which
  // the next OutputDir of `dir` moves in.
  // `moved`, where given, is called after each entry but the manifest is moved aside or into
  // place, with its new path (a test stops a commit there).
  void commit(const std::function<void(const std::filesystem::path&)>& moved = {});
  const std::filesystem::path& dir() const { return dir_; }

 private:
  // Throws std::invalid_argument where one of `names` (a folder's ending in '/') is in the
  // output folder as the other kind of entry.
  void require_replaceable(const std::vector<std::string>& names) const;
  void require_ours(const std::vector<std::string>& writes) const;
  std::filesystem::path dir_, staging_;
  bool keep_staging_ = false;  // a commit failed part way: the next run finishes it
  std::vector<std::string> outputs_;
  std::set<std::string> earlier_;  // of `outputs_`, those the folder's earlier run wrote
  std::vector<std::filesystem::path> created_;  // the folders the constructor made, the deepest first
};

// Binary little-endian PLY: vertex x y z vx vy vz (float); cloth grids also get their
// triangles (two per quad) so mesh tools show the surface. numpy reads it via plyfile.
void write_ply(const std::filesystem::path& file, const Model& m, const State& s);
// The bytes write_ply writes for this model, at most.
std::int64_t ply_bytes(const Model& m);
// step,t_s,step_ms (on the run's step clock),queue_ms (host clock around step()),
// max_displacement_m (empty where the step was not checked).
void write_timings_csv(const std::filesystem::path& file, const RunResult& r);
// step,t_s,kinetic_J,spring_J,field_J,total_J: a row a sample.
void write_energy_csv(const std::filesystem::path& file, const std::vector<EnergySample>& samples);
void write_json(const std::filesystem::path& file, const nlohmann::json& j);

// Machine and build facts for manifests.
nlohmann::json machine_info();
nlohmann::json build_info();

// The nodes and springs a model spec builds, counted without building it.
ModelSize model_size(const ModelSpec& ms);

}  // namespace deformlab
