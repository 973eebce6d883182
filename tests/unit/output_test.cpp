// Run outputs (experiments/output.hpp): an entry of the other kind in an output's place is
// refused before anything changes (after the run, with its outputs kept); a commit stopped
// between its renames, or whose rename failed, leaves a folder without a manifest, the mark of
// an incomplete run, and the next run's commit completes it; a commit leaves none of the old
// output's files that the new one lacks, and replaces nothing no run wrote; a folder holds one
// run or one experiment; a failed write says why.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/output.hpp"

namespace deformlab::test {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& f, const std::string& text) { std::ofstream(f) << text; }
// An empty folder of this name in the test's temporary folder.
fs::path fresh(const char* name) {
  const fs::path dir = fs::path(testing::TempDir()) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}
std::string read(const fs::path& f) {
  std::ostringstream os;
  os << std::ifstream(f).rdbuf();
  return os.str();
}

const std::vector<std::string> kOutputs = {"summary.txt", "state.ply", "trace.json", "frames/"};
const std::vector<std::string> kWrites = {"summary.txt", "state.ply"};  // what the tests' outputs write

// A manifest's build names the libraries a result depends on, the mesh libraries among them
// (a mesh read by another assimp or meshed by another Gmsh may have other nodes).
TEST(BuildInfo, NamesTheMeshLibrariesVersions) {
  const std::string libs = build_info()["mesh_libraries"];
  EXPECT_EQ(libs.rfind("assimp ", 0), 0u) << libs;
  const std::size_t gmsh = libs.find(", Gmsh ");
  ASSERT_NE(gmsh, std::string::npos) << libs;
  EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(libs[gmsh + 7]))) << libs;
  EXPECT_EQ(libs.find("0.0.0"), std::string::npos) << libs;
}

TEST(OutputDir, AnEntryInTheWayIsRefusedBeforeAnythingChanges) {
  const fs::path dir = fresh("deformlab-commit-in-the-way");
  fs::create_directories(dir / "state.ply");  // a folder where the output writes a file
  write(dir / "state.ply" / "x", "in the way");
  const std::string old = R"({"experiment": "paper-drag", "files": {}})";  // a run's, that wrote none of them
  write(dir / "manifest.json", old);
  const std::string error = "output folder '" + dir.string() +
                            "' holds a folder named 'state.ply' where this output writes a file: move it or give another --out";
  try {
    OutputDir out(dir, kOutputs, kWrites);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(e.what(), error);
  }
  fs::remove_all(dir / "state.ply");
  write(dir / "frames", "a file where the output has a folder");
  EXPECT_THROW(OutputDir(dir, kOutputs, kWrites), std::invalid_argument);
  fs::remove(dir / "frames");
  {
    OutputDir out(dir, kOutputs, kWrites);  // the entry appears during the run
    write(out.staged("summary.txt"), "new");
    write(out.staged("state.ply"), "new");
    write(out.staged("manifest.json"), "new");
    fs::create_directories(dir / "state.ply");
    const fs::path kept = dir / ("unsaved-run-" + std::to_string(::getpid()));
    try {
      out.commit();
      ADD_FAILURE() << "committed";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(e.what(), error + "; this run's outputs are in '" + kept.string() + "'");
    }
    EXPECT_EQ(read(kept / "state.ply"), "new") << "the run's outputs kept";
  }
  EXPECT_EQ(read(dir / "manifest.json"), old) << "the folder as it was";
  EXPECT_FALSE(fs::exists(dir / "summary.txt"));
  fs::remove_all(dir);
}

TEST(OutputDir, ACommitStoppedBetweenRenamesLeavesNoManifestAndTheNextCompletesIt) {
  const fs::path dir = fresh("deformlab-commit-stopped");
  for (const char* f : {"summary.txt", "state.ply"}) write(dir / f, "old");
  write(dir / "manifest.json", R"({"experiment": "paper-drag"})");  // a run's
  // A process that stops for good after its commit's first rename (as if killed there).
  EXPECT_EXIT(
      {
        OutputDir out(dir, kOutputs, kWrites);
        for (const char* f : {"summary.txt", "state.ply"}) write(out.staged(f), "new");
        write(out.staged("manifest.json"), R"({"experiment": "new"})");
        out.commit([](const fs::path&) { ::_exit(3); });
      },
      testing::ExitedWithCode(3), "");
  EXPECT_EQ(folder_holds(dir), Holds::nothing) << "an incomplete folder has no manifest";
  int moved = 0, staging = 0;
  for (const char* f : {"summary.txt", "state.ply"}) moved += read(dir / f) == "new";
  for (const auto& e : fs::directory_iterator(dir)) staging += e.path().filename().string().starts_with(".deformlab-staging-");
  EXPECT_EQ(moved, 1) << "one output moved in before the stop";
  EXPECT_EQ(staging, 1) << "the stopped process's staging folder";
  {
    OutputDir out(dir, kOutputs, kWrites);  // finishes the stopped commit first
    EXPECT_EQ(read(dir / "manifest.json"), R"({"experiment": "new"})");
    for (const char* f : {"summary.txt", "state.ply"}) EXPECT_EQ(read(dir / f), "new") << f;
    for (const char* f : {"manifest.json", "summary.txt", "state.ply"}) write(out.staged(f), "newer");
    out.commit();
  }
  for (const char* f : {"manifest.json", "summary.txt", "state.ply"}) EXPECT_EQ(read(dir / f), "newer") << f;
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".deformlab-staging-"), std::string::npos) << "staging left behind";
  fs::remove_all(dir);
}

// A rename that fails part way (a full or read-only file system) is not a stopped process: the
// error says where the rest are, and the staging folder stays for the next run to move in.
TEST(OutputDir, ACommitThatFailsPartWayKeepsTheRestForTheNextRun) {
  const fs::path dir = fresh("deformlab-commit-failed");
  write(dir / "manifest.json", R"({"experiment": "paper-drag"})");  // a run's
  fs::path staging;
  {
    OutputDir out(dir, kOutputs, kWrites);
    for (const char* f : {"summary.txt", "state.ply"}) write(out.staged(f), "new");
    write(out.staged("manifest.json"), R"({"experiment": "new"})");
    staging = out.staged("manifest.json").parent_path();
    try {
      out.commit([&](const fs::path& p) {
        throw fs::filesystem_error("rename", p, std::make_error_code(std::errc::read_only_file_system));
      });
      ADD_FAILURE() << "committed";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "cannot finish moving this run's outputs into '" + dir.string() +
                                           "' (Read-only file system): the rest are in '" +
                                           staging.string() + "', and the next run with this output folder "
                                           "moves them in first");
    }
  }
  EXPECT_EQ(folder_holds(dir), Holds::nothing) << "an incomplete folder has no manifest";
  EXPECT_EQ(read(staging / "manifest.json"), R"({"experiment": "new"})") << "the staging folder kept";
  {
    OutputDir out(dir, kOutputs, kWrites);  // finishes the failed commit first
    EXPECT_EQ(read(dir / "manifest.json"), R"({"experiment": "new"})");
    for (const char* f : {"summary.txt", "state.ply"}) EXPECT_EQ(read(dir / f), "new") << f;
  }
  EXPECT_FALSE(fs::exists(staging)) << "staging left behind";
  fs::remove_all(dir);
}

TEST(OutputDir, CommitRemovesTheOldOutputsTheNewOneLacks) {
  const fs::path dir = fresh("deformlab-commit-stale");
  fs::create_directories(dir / "frames");
  write(dir / "frames" / "frame_1.png", "old");
  for (const char* f : {"summary.txt", "state.ply", "trace.json", "notes.txt"}) write(dir / f, "old");
  write(dir / "manifest.json", R"({"experiment": "paper-drag"})");  // a run's
  {
    OutputDir out(dir, kOutputs, kWrites);
    write(out.staged("summary.txt"), "new");
    write(out.staged("manifest.json"), "new");
    out.commit();
  }
  EXPECT_EQ(read(dir / "manifest.json"), "new");
  EXPECT_EQ(read(dir / "summary.txt"), "new");
  for (const char* f : {"state.ply", "trace.json", "frames"}) EXPECT_FALSE(fs::exists(dir / f)) << f;
  EXPECT_EQ(read(dir / "notes.txt"), "old") << "not an output: kept";
  fs::remove_all(dir);
}

// A commit stopped after any of its moves (the old outputs the new run lacks aside, then the new
// outputs in) leaves a folder that the next run accepts, whatever it writes: none of the old
// outputs is left there unlisted, and the next commit leaves nothing else behind.
TEST(OutputDir, ACommitStoppedAnywhereLeavesNoOldOutputUnlisted) {
  const std::vector<std::string> all = {"summary.txt", "state.ply", "trace.json", "frames/"};
  for (int stop = 1; stop <= 4; ++stop) {  // 3 entries aside, 1 in
    SCOPED_TRACE("stopped after move " + std::to_string(stop));
    const fs::path dir = fresh("deformlab-commit-stopped-stale");
    fs::create_directories(dir / "frames");
    write(dir / "frames" / "frame_1.png", "old");
    for (const char* f : {"summary.txt", "state.ply", "trace.json"}) write(dir / f, "old");
    write(dir / "manifest.json", R"({"experiment": "paper-drag"})");  // a run's
    EXPECT_EXIT(
        {
          OutputDir out(dir, kOutputs, {"summary.txt"});
          write(out.staged("summary.txt"), "new");
          write(out.staged("manifest.json"), R"({"experiment": "new", "files": {"summary.txt": {}}})");
          int moves = 0;
          out.commit([&](const fs::path&) {
            if (++moves == stop) ::_exit(3);
          });
        },
        testing::ExitedWithCode(3), "");
    {
      OutputDir out(dir, kOutputs, all);  // would refuse an entry no manifest there names
      if (stop == 4) {
        EXPECT_EQ(read(dir / "summary.txt"), "new") << "the stopped commit finished";
      }
      for (const char* f : {"summary.txt", "state.ply", "trace.json"}) write(out.staged(f), "newer");
      write(out.staged("manifest.json"), "newer");
      out.commit();
    }
    std::vector<std::string> left;
    for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
    std::sort(left.begin(), left.end());
    EXPECT_EQ(left, (std::vector<std::string>{"manifest.json", "state.ply", "summary.txt", "trace.json"}))
        << "no old frames, staging or aside folder left";
    fs::remove_all(dir);
  }
}

TEST(OutputDir, CommitLeavesFilesOfAFolderThatHeldNoOutput) {
  const fs::path dir = fresh("deformlab-commit-foreign");
  fs::create_directories(dir / "frames");
  write(dir / "frames" / "mine.png", "mine");
  write(dir / "trace.json", "mine");
  {
    OutputDir out(dir, kOutputs, {});
    write(out.staged("manifest.json"), "new");
    out.commit();
  }
  EXPECT_EQ(read(dir / "frames" / "mine.png"), "mine");
  EXPECT_EQ(read(dir / "trace.json"), "mine");
  fs::remove_all(dir);
}

// An output that would replace an entry no earlier run wrote is refused before the run: in a
// folder that held no run, and in one whose run's manifest does not name it.
TEST(OutputDir, WhatNoRunWroteIsNotReplaced) {
  const fs::path dir = fresh("deformlab-commit-theirs");
  fs::create_directories(dir / "frames");
  write(dir / "frames" / "keep.txt", "mine");
  const std::string error = "output folder '" + dir.string() +
                            "' holds 'frames/', which no earlier run's manifest there names (not a deformlab output): "
                            "move it or give another --out";
  const std::vector<std::string> with_frames = {"summary.txt", "frames/"};
  try {
    OutputDir out(dir, kOutputs, with_frames);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(e.what(), error);
  }
  write(dir / "manifest.json", R"({"experiment": "paper-drag", "files": {"summary.txt": ""}})");
  EXPECT_THROW(OutputDir(dir, kOutputs, with_frames), std::invalid_argument) << "a run that wrote no frames";
  EXPECT_EQ(read(dir / "frames" / "keep.txt"), "mine");
  write(dir / "manifest.json", R"({"experiment": "paper-drag", "files": {"summary.txt": "", "frames/": ""}})");
  // The earlier run's frames are replaced as a whole, but not with a file no run writes there.
  for (const auto& writes : {with_frames, kWrites}) {
    try {
      OutputDir out(dir, kOutputs, writes);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(e.what(), "output folder '" + dir.string() +
                              "' holds 'frames/keep.txt', which no run writes there: move it or give another --out");
    }
  }
  fs::remove(dir / "frames" / "keep.txt");
  write(dir / "frames" / "frame_000010.png", "a frame");
  write(dir / "frames" / "frames.mp4", "a movie");
  {
    OutputDir out(dir, kOutputs, with_frames);
    fs::create_directories(out.staged("frames"));
    write(out.staged("manifest.json"), "new");
    out.commit();
  }
  EXPECT_FALSE(fs::exists(dir / "frames" / "frame_000010.png"));
  // A manifest from before "frames/" was listed names the frames as "frames".
  write(dir / "manifest.json", R"({"experiment": "paper-drag", "files": {"summary.txt": ""}, "frames": {}})");
  EXPECT_NO_THROW(OutputDir(dir, kOutputs, with_frames));
  // What the earlier run did not write stays, though the new one does not write it either.
  write(dir / "manifest.json", R"({"experiment": "paper-drag", "files": {"summary.txt": ""}})");
  write(dir / "trace.json", "mine");
  {
    OutputDir out(dir, kOutputs, {"summary.txt"});
    write(out.staged("manifest.json"), "new");
    out.commit();
  }
  EXPECT_EQ(read(dir / "trace.json"), "mine");
  // A manifest.json that is no run's is not replaced either.
  write(dir / "manifest.json", R"({"name": "my web app"})");
  EXPECT_THROW(OutputDir(dir, kOutputs, {"summary.txt"}), std::invalid_argument);
  fs::remove_all(dir);
}

TEST(OutputFiles, AFailedWriteSaysWhy) {
  try {
    write_json("/dev/full", nlohmann::json{{"a", 1}});
    ADD_FAILURE() << "written";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "cannot write /dev/full: No space left on device");
  }
}

// write_atomically replaces a regular file whole, makes its folders, names that file (not its
// temporary) when it fails, and writes to what is no regular file (a pipe, a device) as it is.
TEST(OutputFiles, WrittenWholeOrNotAtAll) {
  const fs::path dir = fs::temp_directory_path() / ("deformlab-atomic-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_atomically(dir / "a.json", "new");
  std::ifstream in(dir / "a.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "new");
  fs::create_symlink("/dev/null", dir / "sink");
  write_atomically(dir / "sink", "x");
  EXPECT_TRUE(fs::is_symlink(dir / "sink")) << "the link, and the device behind it, stay";
  write_atomically(dir / "new" / "deeper" / "b.json", "made");
  std::ifstream made(dir / "new" / "deeper" / "b.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(made), {}), "made");
  try {  // a name too long fails after its folders are made: they go again
    write_atomically(dir / "made" / "here" / std::string(300, 'x'), "x");
    ADD_FAILURE() << "written";
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(dir / "made"));
  try {
    write_atomically(dir / "a.json" / "b.json", "x");
    ADD_FAILURE() << "written";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write " + (dir / "a.json" / "b.json").string() + ": Not a directory");
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 3) << "no temporary left";
  fs::remove_all(dir);
}

TEST(OutputDir, AFolderHoldsOneRunOrOneExperiment) {
  const fs::path dir = fresh("deformlab-folder-holds");
  EXPECT_EQ(folder_holds(dir), Holds::nothing);
  EXPECT_NO_THROW(require_holds_nothing_but(dir, Holds::run));
  write(dir / "manifest.json", R"({"experiment": "paper-drag", "pipeline": "cpu"})");
  EXPECT_EQ(folder_holds(dir), Holds::run);
  EXPECT_NO_THROW(require_holds_nothing_but(dir, Holds::run));
  EXPECT_THROW(require_holds_nothing_but(dir, Holds::experiment), std::invalid_argument);
  write(dir / "manifest.json", R"({"experiment": {"name": "quick"}})");
  EXPECT_EQ(folder_holds(dir), Holds::experiment);
  EXPECT_THROW(require_holds_nothing_but(dir, Holds::run), std::invalid_argument);
  fs::remove(dir / "manifest.json");
  fs::create_directories(dir / "cells");  // a sweep stopped before its manifest
  EXPECT_EQ(folder_holds(dir), Holds::experiment);
  EXPECT_NO_THROW(require_holds_nothing_but(dir / "cells" / "x", Holds::run)) << "no manifest says so";
  // Nothing goes inside either: a run into an experiment's cells/ had made its folder unreadable.
  // Another tool's manifest above an output does not count.
  write(dir / "manifest.json", R"({"name": "webapp", "experiment": "A/B test 7"})");
  EXPECT_NO_THROW(require_holds_nothing_but(dir / "runs" / "x", Holds::run));
  write(dir / "manifest.json", R"({"experiment": {"name": "quick"}, "build": {}, "machine": {}})");
  for (Holds want : {Holds::run, Holds::experiment}) {
    EXPECT_THROW(require_holds_nothing_but(dir / "cells", want), std::invalid_argument);
    EXPECT_THROW(require_holds_nothing_but(dir / "new" / "deeper", want), std::invalid_argument);
  }
  fs::remove_all(dir / "cells");
  write(dir / "manifest.json", "{");  // cut short: said as such, not taken for another kind of folder
  for (Holds want : {Holds::run, Holds::experiment}) {
    try {
      require_holds_nothing_but(dir, want);
      ADD_FAILURE() << "a folder with an unreadable manifest was taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("output folder '" + dir.string() + "': its manifest '" +
                                                (dir / "manifest.json").string() + "' is not valid JSON: ",
                                            0),
                0u)
          << e.what();
      EXPECT_TRUE(std::string(e.what()).ends_with(": move it or give another --out")) << e.what();
    }
  }
  write(dir / "manifest.json", R"({"experiment": "paper-drag", "pipeline": "cpu", "build": {}, "machine": {}})");
  try {
    require_holds_nothing_but(dir / "frames", Holds::run);
    ADD_FAILURE() << "a run inside a run's folder was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lies inside '"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace deformlab::test
