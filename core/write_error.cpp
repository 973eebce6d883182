#include "write_error.hpp"

#include <cstring>
#include <fstream>

namespace deformlab {

std::runtime_error write_error(const std::string& path, int error) {
  return std::runtime_error("cannot write " + path + (error ? std::string(": ") + std::strerror(error) : std::string()));
}

void write_file(const std::string& path, const std::function<void(std::ostream&)>& body, bool binary) {
  std::ofstream out(path, binary ? std::ios::binary : std::ios::openmode{});
  if (!out) throw write_error(path);
  errno = 0;
  body(out);
  out.close();  // the stream's own buffer goes out here: a full disk shows now or never
  if (!out) throw write_error(path);
}

}  // namespace deformlab
