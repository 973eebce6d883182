// The files of a frames/ folder, named in one place for the writer and for the checks that
// tell them from a user's: frame_NNNNNN.png a frame (its step), frames.mp4 their movie.
#pragma once
#include <cstdio>
#include <string>

namespace deformlab {

inline constexpr const char* kFramesMovie = "frames.mp4";
inline constexpr const char* kFrameGlob = "frame_*.png";

inline std::string frame_file(int step) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06d.png", step);
  return name;
}

// Whether `name` is one a frames/ folder's writer writes.
inline bool is_frames_file(const std::string& name) {
  return name == kFramesMovie || (name.starts_with("frame_") && name.ends_with(".png"));
}

}  // namespace deformlab
