// The recorder makes the folder its file needs, and takes back what it made when the recording
// fails or is never finished: no folder, no partial file left.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <stdexcept>
#include <vector>

#include "viewer/recorder.hpp"

namespace deformlab::test {
namespace {

namespace fs = std::filesystem;

class RecorderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0) GTEST_SKIP() << "ffmpeg is not installed";
    dir_ = fs::temp_directory_path() / ("deformlab-recorder-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(RecorderTest, MakesItsFolderAndKeepsItWithTheFinishedFile) {
  const fs::path file = dir_ / "a" / "b" / "m.mp4";
  viewer::Recorder r(file.string(), 16, 16);
  EXPECT_TRUE(fs::is_directory(dir_ / "a" / "b"));
  for (int f = 0; f < 3; ++f) r.add(std::vector<std::uint8_t>(16 * 16 * 4, std::uint8_t(40 * f)));
  r.finish();
  EXPECT_GT(fs::file_size(file), 0u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_ / "a" / "b"), fs::directory_iterator()), 1) << "the mp4 alone";
}

TEST_F(RecorderTest, AFailedRecordingTakesBackTheFoldersItMade) {
  fs::create_directories(dir_ / "kept");
  {
    viewer::Recorder r((dir_ / "kept" / "new" / "m.mp4").string(), 16, 16);
    EXPECT_THROW(r.finish(), std::runtime_error) << "no frames: ffmpeg writes nothing";
  }
  EXPECT_FALSE(fs::exists(dir_ / "kept" / "new"));
  EXPECT_TRUE(fs::is_directory(dir_ / "kept")) << "a folder that was there stays";
  {
    viewer::Recorder r((dir_ / "x" / "y" / "m.mp4").string(), 16, 16);
    r.add(std::vector<std::uint8_t>(16 * 16 * 4, 0));
  }  // never finished
  EXPECT_FALSE(fs::exists(dir_ / "x"));
  EXPECT_TRUE(fs::is_empty(dir_ / "kept"));
}

TEST_F(RecorderTest, AFolderThatCannotBeMadeIsRefused) {
  const fs::path file = dir_ / "f";
  std::FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  try {
    viewer::Recorder r((file / "m.mp4").string(), 16, 16);
    ADD_FAILURE() << "a recording under a file was started";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find((file / "m.mp4").string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Not a directory"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_regular_file(file));
}

}  // namespace
}  // namespace deformlab::test
