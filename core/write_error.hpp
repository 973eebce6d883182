// A file that could not be opened or written, with the system's reason where it left one
// (errno after the failed call: "No space left on device", "Permission denied").
#pragma once
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace deformlab {

inline std::runtime_error write_error(const std::string& path) {
  const int e = errno;
  return std::runtime_error("cannot write " + path + (e ? std::string(": ") + std::strerror(e) : std::string()));
}

}  // namespace deformlab
