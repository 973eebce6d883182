#include "recorder.hpp"

#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include "experiments/output.hpp"

namespace deformlab::viewer {
namespace {

std::string shell_quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

Recorder::Recorder(std::string file, int width, int height, int fps)
    : file_(std::move(file)), partial_(file_ + ".partial-" + std::to_string(getpid())), w_(width), h_(height) {
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0)
    throw std::invalid_argument("recording needs ffmpeg, which is not installed");
  try {
    made_ = make_folders_for(file_);
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(std::string("cannot record: ") + e.what());
  }
  std::signal(SIGPIPE, SIG_IGN);  // a failed ffmpeg shows as a write error, not a dead viewer
  // H.264 in yuv420p wants even sizes: an odd last row or column is cut. In a session of its
  // own (setsid), so that a terminal's Ctrl-C reaches the viewer, which finishes the recording,
  // and not ffmpeg.
  const bool own_session = std::system("command -v setsid >/dev/null 2>&1") == 0;
  const std::string cmd = std::string(own_session ? "exec setsid -w " : "exec ") +
                          "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgba -s " + std::to_string(w_) + "x" +
                          std::to_string(h_) + " -r " + std::to_string(fps) +
                          " -i - -vf 'vflip,crop=trunc(iw/2)*2:trunc(ih/2)*2' -c:v libx264 -pix_fmt yuv420p -f mp4 " +
                          shell_quoted(partial_);
  pipe_ = popen(cmd.c_str(), "w");
  if (!pipe_) {
    discard();
    throw std::runtime_error("cannot start ffmpeg");
  }
}

Recorder::~Recorder() {
  if (!pipe_) return;
  pclose(pipe_);
  discard();
}

void Recorder::discard() const {
  std::error_code ec;
  std::filesystem::remove(partial_, ec);
  remove_made_folders(made_);
}

void Recorder::add(const std::vector<std::uint8_t>& rgba) {
  if (!pipe_) throw std::logic_error("the recording is finished");
  if (rgba.size() != std::size_t(w_) * h_ * 4) throw std::logic_error("a frame of the wrong size");
  if (std::fwrite(rgba.data(), 1, rgba.size(), pipe_) != rgba.size())
    throw std::runtime_error("ffmpeg stopped taking frames for " + file_);
  ++frames_;
}

void Recorder::finish() {
  const int status = pclose(std::exchange(pipe_, nullptr));
  if (status != 0 || frames_ == 0) {
    discard();
    throw std::runtime_error("ffmpeg could not write " + file_);
  }
  std::error_code ec;
  if (std::filesystem::rename(partial_, file_, ec); ec) {
    discard();
    throw std::runtime_error("cannot move the recording into " + file_ + ": " + ec.message());
  }
}

}  // namespace deformlab::viewer
