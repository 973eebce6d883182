// A file that could not be opened or written, with the system's reason where it left one
// ("No space left on device", "Permission denied"): `error` is errno as the failed call left
// it, 0 for none. A writer clears errno once its file is open, so that what it reads at the end
// comes from that file's writes.
#pragma once
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace deformlab {

inline std::runtime_error write_error(const std::string& path, int error = errno) {
  return std::runtime_error("cannot write " + path + (error ? std::string(": ") + std::strerror(error) : std::string()));
}

}  // namespace deformlab
