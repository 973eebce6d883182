#include "output.hpp"

#include <fcntl.h>
#include <sys/utsname.h>
#include <signal.h>
#include <unistd.h>

#include <linux/limits.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <Eigen/Core>
#include <fstream>
#include <sstream>
#include <string_view>
#include <stdexcept>
#include <thread>

#include "build_info.hpp"
#include "core/frame_files.hpp"
#include "core/json_file.hpp"
#include "core/write_error.hpp"
#include "mesh/load.hpp"

namespace deformlab {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::string_view kTemporaryTag = ".deformlab-tmp-", kStagingTag = ".deformlab-staging-";

void require_name_lengths(const fs::path& path, const std::string& what, std::size_t inside) {
  std::error_code ec;
  const std::string full = fs::absolute(path, ec).string();
  const std::string most = std::to_string(PATH_MAX - 1);
  if (full.size() + inside >= PATH_MAX)
    throw std::invalid_argument(what + " '" + path.string() + "': a path of " + std::to_string(full.size()) +
                                " bytes, " +
                                (inside ? "which leaves less than the " + std::to_string(inside) +
                                              " its files' paths may need within the " + most + " a path may be"
                                        : "longer than a path may be (" + most + ")"));
  // The last name keeps room for the suffix of its temporary (temporary(): the tag and a pid).
  const std::size_t last = NAME_MAX - kTemporaryTag.size() - 10;
  for (auto part = path.begin(); part != path.end(); ++part) {
    const std::size_t bytes = part->string().size(), most = std::next(part) == path.end() ? last : NAME_MAX;
    if (bytes > most)
      throw std::invalid_argument(what + " '" + path.string() + "': a name of " + std::to_string(bytes) +
                                  " bytes, longer than " + std::to_string(most) +
                                  (most < NAME_MAX ? " (" + std::to_string(NAME_MAX) +
                                                         ", the most a file name takes, less room for its temporary's "
                                                         "suffix)"
                                                   : ", the most a file name takes"));
  }
}

void require_folder_or_nothing(const fs::path& dir) {
  // What a command writes inside the folder takes up to 256 bytes more path: a run's staging
  // folder and frames, an experiment's cell files (names of up to 200 bytes), each with its
  // temporary's suffix.
  require_name_lengths(dir, "output folder", 256);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw std::invalid_argument("output path '" + dir.string() + "' exists and is not a folder");
}

json read_manifest(const fs::path& dir) {
  try {
    return read_json_file((dir / "manifest.json").string(), "manifest");  // with its checks (nesting, size)
  } catch (const std::invalid_argument&) {
    return nullptr;
  }
}

namespace {

// What `dir` holds by its manifest alone. `written`: only a manifest as deformlab writes it, with
// the build and the machine that wrote it (a folder above an output may hold another tool's).
Holds manifest_holds(const fs::path& dir, bool written = false) {
  const json m = read_manifest(dir);
  if (!m.is_object() || !m.contains("experiment")) return Holds::nothing;
  if (written && !(m.value("build", json()).is_object() && m.value("machine", json()).is_object())) return Holds::nothing;
  return m["experiment"].is_object() ? Holds::experiment : Holds::run;
}

// The folders that creating `dir` makes, as absolute paths through the links that exist now,
// the deepest first.
std::vector<fs::path> folders_to_make(const fs::path& dir) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(dir, ec), ec);
  if (!p.has_filename()) p = p.parent_path();
  std::vector<fs::path> made;
  for (; !ec && p.has_relative_path() && !fs::exists(p, ec); p = p.parent_path()) made.push_back(p);
  return made;
}

}  // namespace

Holds folder_holds(const fs::path& dir) {
  std::error_code ec;
  if (const Holds h = manifest_holds(dir); h != Holds::nothing) return h;
  return fs::is_directory(dir / "cells", ec) ? Holds::experiment : Holds::nothing;
}

void require_holds_nothing_but(const fs::path& dir, Holds want) {
  std::error_code ec;
  const fs::path at = fs::weakly_canonical(fs::absolute(dir, ec), ec);
  for (fs::path up = at.parent_path(); !ec && up.has_relative_path(); up = up.parent_path())
    if (const Holds outer = manifest_holds(up, true); outer != Holds::nothing)
      throw std::invalid_argument("output folder '" + dir.string() + "' lies inside '" + up.string() + "', which holds " +
                                  (outer == Holds::run ? "a run's outputs" : "an experiment's results") +
                                  ": give this " + (want == Holds::run ? "run" : "experiment") + " another --out");
  // A manifest that cannot be read would leave the folder taken for another kind, or for none.
  try {
    if (fs::exists(fs::symlink_status(dir / "manifest.json", ec)))
      read_json_file((dir / "manifest.json").string(), "its manifest");
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("output folder '" + dir.string() + "': " + e.what() + ": move it or give another --out");
  }
  const Holds has = folder_holds(dir);
  if (has == Holds::nothing || has == want) return;
  throw std::invalid_argument("output folder '" + dir.string() + "' holds " +
                              (has == Holds::run ? "a run's outputs" : "an experiment's results") +
                              ": give this " + (want == Holds::run ? "run" : "experiment") + " another --out");
}

std::string foreign_frames_entry(const fs::path& frames) {
  std::error_code ec;
  if (!fs::is_directory(frames, ec)) return "";
  for (const auto& e : fs::directory_iterator(frames, ec)) {
    const std::string name = e.path().filename().string();
    if (!is_frames_file(name) || !e.is_regular_file(ec)) return name;
  }
  return "";
}

fs::path temporary(const fs::path& name) { return name.string().append(kTemporaryTag) + std::to_string(::getpid()); }

void require_file_target(const std::string& file, const std::string& what) {
  std::error_code ec;
  if (file.empty()) throw std::invalid_argument(what + ": an empty file name");
  require_name_lengths(file, what);
  if (fs::is_directory(file, ec)) throw std::invalid_argument(what + " '" + file + "' is a folder");
  if (!fs::path(file).has_filename())
    throw std::invalid_argument(what + " '" + file + "' names a folder (it ends in '/'), not a file");
  require_file_can_be_made(file, what);
}

void require_file_can_be_made(const std::string& file, const std::string& what) {
  std::error_code ec;
  if (fs::exists(file, ec) && !fs::is_regular_file(file, ec)) return;  // a pipe, a device: written to as it is
  // Its folders are made as it is written: the nearest that is there must be a folder.
  fs::path folder = fs::path(file).parent_path();
  while (!folder.empty() && !fs::exists(fs::symlink_status(folder, ec)) && folder.has_relative_path())
    folder = folder.parent_path();
  if (!folder.empty() && !fs::is_directory(folder, ec))
    throw std::invalid_argument(what + " '" + file + "': '" + folder.string() + "' is not a folder");
  // A temporary of its name in that folder, made and removed again.
  const fs::path probe = temporary(folder / fs::path(file).filename());
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0)
    throw std::invalid_argument(what + " '" + file + "': no file can be made there (" + std::strerror(errno) + ")");
  ::close(fd);
  fs::remove(probe, ec);
}

std::vector<fs::path> make_folders_for(const fs::path& file) {
  const fs::path dir = file.parent_path();
  const std::vector<fs::path> made = folders_to_make(dir);
  std::error_code ec;
  if (made.empty() && !dir.empty() && !fs::is_directory(dir, ec)) throw write_error(file.string(), ec ? ec.value() : ENOTDIR);
  if (!made.empty() && (fs::create_directories(dir, ec), ec)) {
    const int error = ec.value();
    remove_made_folders(made);
    throw write_error(file.string(), error);
  }
  return made;
}

void remove_made_folders(const std::vector<fs::path>& made) {
  std::error_code ec;
  for (const fs::path& p : made) {
    if (!fs::exists(p, ec)) continue;  // not made: making the folders stopped above it
    if (!fs::is_empty(p, ec) || !fs::remove(p, ec)) return;
  }
}

void write_atomically(const fs::path& file, const std::string& text) {
  auto write = [&](const fs::path& to) { write_file(to.string(), [&](std::ostream& out) { out << text; }, true); };
  std::error_code ec;
  if (fs::exists(file, ec) && !fs::is_regular_file(file, ec)) return write(file);  // a pipe, a device: written to
  const fs::path tmp = temporary(file);
  const std::vector<fs::path> made = make_folders_for(file);
  auto unmake = [&] { remove_made_folders(made); };
  try {
    write(tmp);
  } catch (const std::runtime_error& e) {  // named as the file asked for
    fs::remove(tmp, ec);
    unmake();
    std::string what = e.what();
    if (const auto at = what.find(tmp.string()); at != std::string::npos) what.replace(at, tmp.string().size(), file.string());
    throw std::runtime_error(what);
  }
  if (std::rename(tmp.c_str(), file.c_str()) != 0) {
    const int error = errno;
    fs::remove(tmp, ec);
    unmake();
    throw write_error(file.string(), error);
  }
}

bool is_temporary(const std::string& name) { return name.find(kTemporaryTag) != std::string::npos; }

namespace {

// Whether `name` is a temporary or a staging folder of this process or of one that is gone.
bool reclaimable(const std::string& name) {
  std::size_t at = name.rfind(kTemporaryTag);
  std::size_t len = kTemporaryTag.size();
  if (name.starts_with(kStagingTag)) at = 0, len = kStagingTag.size();
  if (at == std::string::npos) return false;
  const std::string digits = name.substr(at + len);
  if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) return false;
  const pid_t pid = pid_t(std::stol(digits));
  return pid == ::getpid() || (::kill(pid, 0) == -1 && errno == ESRCH);
}

// A commit stopped between its renames (its process gone) left the folder without a manifest,
// some of its outputs moved in and the rest, with its manifest, in its staging folder: this
// moves those in, the manifest last, so that the folder holds that run's complete outputs.
void finish_stopped_commit(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir / "manifest.json", ec)) return;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (!name.starts_with(kStagingTag) || !reclaimable(name) || folder_holds(e.path()) != Holds::run) continue;
    for (const auto& f : fs::directory_iterator(e.path())) {
      if (f.path().filename() == "manifest.json") continue;
      const fs::path target = dir / f.path().filename();
      fs::remove_all(target);
      fs::rename(f.path(), target);
    }
    fs::rename(e.path() / "manifest.json", dir / "manifest.json");
    return;
  }
}

}  // namespace

void reclaim_temporaries(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (reclaimable(e.path().filename().string())) fs::remove_all(e.path(), ec);
}

namespace {

// The output's name without the '/' that marks a folder.
fs::path entry_name(const std::string& output) {
  return output.ends_with('/') ? output.substr(0, output.size() - 1) : output;
}

}  // namespace

void OutputDir::require_replaceable(const std::vector<std::string>& names) const {
  std::error_code ec;
  for (const auto& name : names) {
    const fs::path target = dir_ / entry_name(name);
    const auto status = fs::symlink_status(target, ec);
    if (!fs::exists(status) || fs::is_directory(status) == name.ends_with('/')) continue;
    throw std::invalid_argument("output folder '" + dir_.string() + "' holds " +
                                (fs::is_directory(status) ? "a folder" : "a file") + " named '" +
                                entry_name(name).string() + "' where this output writes " +
                                (name.ends_with('/') ? "a folder" : "a file") + ": move it or give another --out");
  }
}

void OutputDir::require_ours(const std::vector<std::string>& writes) const {
  std::error_code ec;
  for (const auto& name : writes)
    if (fs::exists(fs::symlink_status(dir_ / entry_name(name), ec)) && !earlier_.count(name))
      throw std::invalid_argument("output folder '" + dir_.string() + "' holds '" + name +
                                  "', which no earlier run's manifest there names (not a deformlab output): move it "
                                  "or give another --out");
  // The earlier run's frames are replaced or removed as a whole.
  if (const std::string e = earlier_.count("frames/") ? foreign_frames_entry(dir_ / "frames") : ""; !e.empty())
    throw std::invalid_argument("output folder '" + dir_.string() + "' holds 'frames/" + e +
                                "', which no run writes there: move it or give another --out");
}

OutputDir::OutputDir(const fs::path& dir, std::vector<std::string> outputs, const std::vector<std::string>& writes)
    : dir_(dir), outputs_(std::move(outputs)) {
  std::error_code ec;
  require_folder_or_nothing(dir_);
  if (fs::exists(dir_, ec)) finish_stopped_commit(dir_);
  require_replaceable(outputs_);
  require_replaceable({"manifest.json"});
  // The earlier run's outputs, by its manifest ("files"; one without the list predates it and
  // takes them all, and one from before "frames/" was listed names its frames as "frames").
  if (const json old = read_manifest(dir_); folder_holds(dir_) == Holds::run) {
    for (const auto& name : outputs_)
      if (!old.contains("files") || old["files"].contains(name) || (name == "frames/" && old.contains("frames")))
        earlier_.insert(name);
  } else if (fs::exists(fs::symlink_status(dir_ / "manifest.json", ec))) {
    throw std::invalid_argument("output folder '" + dir_.string() +
                                "' holds a manifest.json that is no deformlab run's: move it or give another --out");
  }
  require_ours(writes);
  created_ = folders_to_make(dir_);
  fs::create_directories(dir_, ec);
  if (ec) {
    remove_made_folders(created_);
    throw std::invalid_argument("cannot create output folder '" + dir_.string() + "': " + ec.message());
  }
  reclaim_temporaries(dir_);
  staging_ = dir_ / (std::string(kStagingTag) + std::to_string(::getpid()));
  fs::create_directory(staging_, ec);
  if (ec) {
    remove_made_folders(created_);
    throw std::invalid_argument("cannot write into output folder '" + dir_.string() + "': " + ec.message());
  }
}

OutputDir::~OutputDir() {
  std::error_code ec;
  if (!keep_staging_) fs::remove_all(staging_, ec);
  remove_made_folders(created_);
}

void OutputDir::commit(const std::function<void(const fs::path&)>& moved) {
  std::vector<std::string> staged;
  for (const auto& e : fs::directory_iterator(staging_))
    staged.push_back(e.path().filename().string() + (e.is_directory() ? "/" : ""));
  // Until the old manifest is gone the folder holds the earlier run: on a failure here it is put
  // back as it was, and this run's outputs are kept under a name the next run leaves alone. The
  // earlier run's outputs that this one does not write go aside first, into a temporary folder
  // that this commit or the next run here removes, so that a commit stopped after the old
  // manifest is gone leaves none of them in the folder, unlisted, for the next run to refuse.
  const fs::path aside = temporary(dir_ / "stale");
  std::vector<fs::path> moved_aside;
  std::string why;
  try {
    require_replaceable(staged);  // an entry put in the way during the run
    for (const auto& name : earlier_) {
      const fs::path entry = entry_name(name);
      std::error_code ec;
      if (fs::exists(staging_ / entry) || !fs::exists(fs::symlink_status(dir_ / entry, ec))) continue;
      fs::create_directory(aside);
      fs::rename(dir_ / entry, aside / entry);
      moved_aside.push_back(entry);
      if (moved) moved(aside / entry);
    }
    fs::remove(dir_ / "manifest.json");
  } catch (const std::invalid_argument& e) {
    why = e.what();
  } catch (const fs::filesystem_error& e) {
    why = e.path1().filename() == "manifest.json"
              ? "cannot remove the manifest of output folder '" + dir_.string() + "' (" + e.code().message() + ")"
              : "cannot move the earlier run's '" + e.path1().filename().string() + "' out of output folder '" +
                    dir_.string() + "' (" + e.code().message() + ")";
  }
  if (!why.empty()) {
    std::error_code ec;
    for (const fs::path& entry : moved_aside) fs::rename(aside / entry, dir_ / entry, ec);
    fs::remove(aside, ec);
    const fs::path kept = dir_ / ("unsaved-run-" + std::to_string(::getpid()));
    fs::rename(staging_, kept, ec);
    keep_staging_ = bool(ec);  // where they could not be moved aside, they stay where they are
    throw std::runtime_error(why + "; this run's outputs are in '" + (ec ? staging_ : kept).string() + "'");
  }
  // From here until the last rename the folder is incomplete. Where a step fails, the staging
  // folder stays for the next run here to finish the commit, as after a process stopped here.
  keep_staging_ = true;
  try {
    for (const auto& e : fs::directory_iterator(staging_)) {
      if (e.path().filename() == "manifest.json") continue;
      const fs::path target = dir_ / e.path().filename();
      if (fs::is_directory(e.path()) && fs::exists(target)) fs::remove_all(target);
      fs::rename(e.path(), target);
      if (moved) moved(target);
    }
    if (fs::exists(staging_ / "manifest.json")) fs::rename(staging_ / "manifest.json", dir_ / "manifest.json");
    std::error_code ec;
    fs::remove_all(aside, ec);
  } catch (const fs::filesystem_error& e) {
    throw std::runtime_error("cannot finish moving this run's outputs into '" + dir_.string() + "' (" +
                             e.code().message() + "): the rest are in '" + staging_.string() +
                             "', and the next run with this output folder moves them in first");
  }
  keep_staging_ = false;
}

namespace {

bool ply_grid_faces(const Model& m) { return m.topology == Topology::cloth_grid && m.nx > 1 && m.ny > 1; }
std::int64_t ply_face_count(const Model& m) {
  return ply_grid_faces(m) ? 2 * std::int64_t(m.nx - 1) * (m.ny - 1) : std::int64_t(m.triangle.size() / 3);
}

void put_ply(std::ostream& out, const Model& m, const State& s) {
  const bool grid_faces = ply_grid_faces(m);
  const std::int64_t nf = ply_face_count(m);
  out << "ply\nformat binary_little_endian 1.0\n"
      << "comment deformlab state at t = " << s.t << " s; positions in m, velocities in m/s\n"
      << "element vertex " << s.x.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property float vx\nproperty float vy\nproperty float vz\n";
  if (nf) out << "element face " << nf << "\nproperty list uchar int vertex_indices\n";
  out << "end_header\n";
  // Vertices in the mesh file's order (model node at file position f: at[f]), then faces made
  // as they are written: a chunk of records at a time.
  std::vector<std::int32_t> at;
  if (!m.file_node.empty()) {
    at.resize(m.file_node.size());
    for (std::size_t v = 0; v < at.size(); ++v) at[m.file_node[v]] = std::int32_t(v);
  }
  std::vector<char> buf;
  auto flush = [&](bool last) {
    if (buf.size() < (std::size_t(1) << 24) && !last) return;
    out.write(buf.data(), std::streamsize(buf.size()));
    buf.clear();
  };
  auto put = [&](const void* p, std::size_t bytes) {
    buf.insert(buf.end(), static_cast<const char*>(p), static_cast<const char*>(p) + bytes);
  };
  auto face = [&](const std::int32_t (&t)[3]) {
    const unsigned char three = 3;
    put(&three, 1);
    put(t, sizeof t);
    flush(false);
  };
  for (std::size_t f = 0; f < s.x.size(); ++f) {
    const std::size_t i = at.empty() ? f : std::size_t(at[f]);
    const float v[6] = {s.x[i].x, s.x[i].y, s.x[i].z, s.v[i].x, s.v[i].y, s.v[i].z};
    put(v, sizeof v);
    flush(false);
  }
  for (int j = 0; grid_faces && j + 1 < m.ny; ++j)
    for (int i = 0; i + 1 < m.nx; ++i) {
      const std::int32_t a = j * m.nx + i, b = a + 1, c = a + m.nx, d = c + 1;
      face({a, c, b});
      face({b, c, d});
    }
  for (std::size_t t = 0; !grid_faces && t + 2 < m.triangle.size(); t += 3)
    face({m.file_index(m.triangle[t]), m.file_index(m.triangle[t + 1]), m.file_index(m.triangle[t + 2])});
  flush(true);
}

}  // namespace

std::int64_t ply_bytes(const Model& m) {
  return 512 + 24 * std::int64_t(m.node_count()) + 13 * ply_face_count(m);  // the header is under 512 bytes
}

void write_ply(const fs::path& file, const Model& m, const State& s) {
  write_file(file.string(), [&](std::ostream& out) { put_ply(out, m, s); }, true);
}

void write_energy_csv(const fs::path& file, const std::vector<EnergySample>& samples) {
  write_file(file.string(), [&](std::ostream& out) {
    out << "step,t_s,kinetic_J,spring_J,field_J,total_J\n";
    out.precision(12);
    for (const EnergySample& s : samples)
      out << s.step << ',' << s.t << ',' << s.e.kinetic << ',' << s.e.spring << ',' << s.e.field << ','
          << s.e.total() << '\n';
  });
}

void write_timings_csv(const fs::path& file, const RunResult& r) {
  write_file(file.string(), [&](std::ostream& out) {
    out << "step,t_s,step_ms,queue_ms,max_displacement_m\n";
    out.precision(9);
    for (const auto& rec : r.records) {
      out << rec.step << ',' << rec.t << ',' << rec.ms << ',' << rec.queue_ms << ',';
      if (rec.max_displacement == rec.max_displacement) out << rec.max_displacement;
      out << '\n';
    }
  });
}

void write_json(const fs::path& file, const nlohmann::json& j) {
  write_file(file.string(), [&](std::ostream& out) { out << j.dump(2) << '\n'; });
}

nlohmann::json machine_info() {
  nlohmann::json j;
  utsname u{};
  if (uname(&u) == 0) j["os"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      j["cpu"] = line.substr(line.find(':') + 2);
      break;
    }
  j["hardware_threads"] = std::thread::hardware_concurrency();
  if (const auto limit = host_memory_limit()) {
    j["memory_available_bytes"] = limit->bytes;
    j["memory_limit"] = limit->name;
  }
  return j;
}

nlohmann::json build_info() {
  return {{"deformlab", DEFORMLAB_VERSION},
          {"git", DEFORMLAB_GIT},
          {"compiler", DEFORMLAB_COMPILER},
          {"build_type", DEFORMLAB_BUILD_TYPE},
          {"cuda", DEFORMLAB_CUDA_VERSION},
          {"gl", DEFORMLAB_GL_BUILT},
          {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                        std::to_string(EIGEN_MINOR_VERSION)},
          {"nlohmann_json", std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
                                std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
                                std::to_string(NLOHMANN_JSON_VERSION_PATCH)},
          {"mesh_libraries", mesh_library_versions()}};
}

ModelSize model_size(const ModelSpec& ms) {
  if (ms.topology == Topology::general) throw std::invalid_argument("a mesh's size is known once its file is read");
  check_node_count(double(ms.nx) * ms.ny * ms.nz);
  const auto k = ms.topology == Topology::lattice ? lattice_spring_counts(ms.nx, ms.ny, ms.nz)
                                                  : cloth_spring_counts(ms.nx, ms.ny);
  return {std::int64_t(ms.nx) * ms.ny * ms.nz, k[0] + k[1] + k[2], true};
}

}  // namespace deformlab
