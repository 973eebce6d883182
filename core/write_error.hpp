// Files written whole, and the error for one that could not be opened or written, with the
// system's reason where it left one ("No space left on device", "Permission denied").
#pragma once
#include <cerrno>
#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>

namespace deformlab {

// `error`: errno as the failed call left it, 0 for none.
std::runtime_error write_error(const std::string& path, int error = errno);

// Opens `path` (truncating it), writes it through `body` and closes it; throws write_error
// where opening, a write or the close failed. errno is cleared once the file is open, so that
// the reason given is one of this file's writes.
void write_file(const std::string& path, const std::function<void(std::ostream&)>& body, bool binary = false);

}  // namespace deformlab
