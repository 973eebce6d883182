// An MP4 written as the frames come: RGBA frames piped to ffmpeg (H.264, yuv420p, 30 frames
// per second). The file appears under its name only once finished: until then ffmpeg writes
// FILE.partial-PID, removed if the recording fails, with the folders made for it.
#pragma once
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace deformlab::viewer {

class Recorder {
 public:
  // Makes the file's folder; throws std::invalid_argument when ffmpeg is not installed or the
  // folder cannot be made.
  Recorder(std::string file, int width, int height, int fps = 30);
  ~Recorder();  // a recording never finished is removed
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // One frame of width x height RGBA pixels, rows from the bottom (as glReadPixels gives them).
  void add(const std::vector<std::uint8_t>& rgba);
  // Closes the stream and moves the file into place; throws std::runtime_error when ffmpeg failed.
  void finish();
  int frames() const { return frames_; }
  const std::string& file() const { return file_; }
  int width() const { return w_; }
  int height() const { return h_; }

 private:
  std::string file_, partial_;
  std::vector<std::filesystem::path> made_;  // the folders made for the file, the deepest first
  void discard() const;  // removes the partial file and the folders made for it
  int w_, h_, frames_ = 0;
  FILE* pipe_ = nullptr;
};

}  // namespace deformlab::viewer
