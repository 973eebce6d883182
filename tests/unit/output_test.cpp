// Run outputs (experiments/output.hpp): a commit stopped between its renames leaves a folder
// without a manifest, the mark of an incomplete run, and the next run's commit completes it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/output.hpp"

namespace deformlab::test {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& f, const std::string& text) { std::ofstream(f) << text; }
std::string read(const fs::path& f) {
  std::ostringstream os;
  os << std::ifstream(f).rdbuf();
  return os.str();
}

TEST(OutputDir, CommitStoppedBetweenRenamesLeavesNoManifest) {
  const fs::path dir = fs::path(testing::TempDir()) / "deformlab-commit-stopped";
  fs::remove_all(dir);
  fs::create_directories(dir / "state.ply");  // an entry the new file cannot replace: the commit stops there
  write(dir / "state.ply" / "x", "in the way");
  write(dir / "manifest.json", "old");
  write(dir / "summary.txt", "old");
  {
    OutputDir out(dir);
    write(out.staged("summary.txt"), "new");
    write(out.staged("state.ply"), "new");
    write(out.staged("manifest.json"), "new");
    EXPECT_THROW(out.commit(), fs::filesystem_error);
    EXPECT_FALSE(fs::exists(dir / "manifest.json")) << "an incomplete folder must have no manifest";
  }
  fs::remove_all(dir / "state.ply");
  {
    OutputDir out(dir);
    write(out.staged("summary.txt"), "newer");
    write(out.staged("state.ply"), "newer");
    write(out.staged("manifest.json"), "newer");
    out.commit();
  }
  for (const char* f : {"manifest.json", "summary.txt", "state.ply"}) EXPECT_EQ(read(dir / f), "newer") << f;
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".staging-"), std::string::npos) << "staging left behind";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace deformlab::test
