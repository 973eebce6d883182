#include "child_read.hpp"

#include <fcntl.h>
#include <omp.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string_view>

namespace deformlab {

namespace {

// The pipe's messages: 'M', the three array lengths, the arrays, the note count and the
// notes; or 'E' and the error's text. A string is its length (8 bytes) and its bytes.
constexpr char kMesh = 'M', kError = 'E';

bool write_all(int fd, const void* data, std::size_t size) {
  auto p = static_cast<const char*>(data);
  while (size) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= std::size_t(n);
  }
  return true;
}

bool read_all(int fd, void* data, std::size_t size) {
  auto p = static_cast<char*>(data);
  while (size) {
    const ssize_t n = ::read(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= std::size_t(n);
  }
  return true;
}

struct Writer {
  int fd;
  bool ok = true;
  void bytes(const void* data, std::size_t size) { ok = ok && write_all(fd, data, size); }
  void count(std::uint64_t n) { bytes(&n, sizeof n); }
  void text(std::string_view s) {
    count(s.size());
    bytes(s.data(), s.size());
  }
  template <class T>
  void array(const std::vector<T>& a) {
    bytes(a.data(), a.size() * sizeof(T));
  }
};

struct Reader {
  int fd;
  bool ok = true;
  void bytes(void* data, std::size_t size) { ok = ok && read_all(fd, data, size); }
  std::uint64_t count() {
    std::uint64_t n = 0;
    bytes(&n, sizeof n);
    return ok ? n : 0;
  }
  std::string text() {
    std::string s(count(), '\0');
    bytes(s.data(), s.size());
    return s;
  }
  template <class T>
  void array(std::vector<T>& a, std::uint64_t n) {
    a.resize(n);
    bytes(a.data(), a.size() * sizeof(T));
  }
};

std::string gib(std::int64_t bytes) {
  char s[32];
  std::snprintf(s, sizeof s, "%.3g GiB", double(bytes) / double(1 << 30));
  return s;
}

// In the child: caps its data segment at what it has plus `cap`, reads, writes the message.
[[noreturn]] void child(int fd, const std::string& what, std::int64_t cap,
                        const std::function<Mesh(std::vector<std::string>&)>& read) {
  if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, STDERR_FILENO);
  // The parent's OpenMP threads are not in the child, and libgomp would wait for them in a
  // parallel region of more than one thread: a reader that runs one runs it on this thread.
  omp_set_num_threads(1);
  if (FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    long kb = -1;
    while (kb < 0 && std::fgets(line, sizeof line, f)) std::sscanf(line, "VmData: %ld kB", &kb);
    std::fclose(f);
    if (rlimit limit{}; kb >= 0 && ::getrlimit(RLIMIT_DATA, &limit) == 0) {
      limit.rlim_cur = std::min(limit.rlim_max, rlim_t(kb) * 1024 + rlim_t(cap));
      ::setrlimit(RLIMIT_DATA, &limit);
    }
  }
  static bool out_of_memory = false;  // the libraries turn std::bad_alloc into their own errors
  std::set_new_handler([] {
    out_of_memory = true;
    std::set_new_handler(nullptr);
    throw std::bad_alloc();
  });
  Writer out{fd};
  auto fail = [&](const std::string& error) {
    out.bytes(&kError, 1);
    out.text(out_of_memory ? what + ": reading it took more than the " + gib(cap) +
                                 " of memory allowed for a file of its size (damaged counts?)"
                           : error);
  };
  try {
    std::vector<std::string> notes;
    const Mesh m = read(notes);
    out.bytes(&kMesh, 1);
    out.count(m.position.size());
    out.count(m.triangle.size());
    out.count(m.tetrahedron.size());
    out.array(m.position);
    out.array(m.triangle);
    out.array(m.tetrahedron);
    out.count(notes.size());
    for (const auto& n : notes) out.text(n);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  ::_exit(out.ok ? 0 : 1);
}

}  // namespace

std::int64_t child_read_memory_cap(std::int64_t file_bytes) {
  return std::max<std::int64_t>(std::int64_t(2) << 30, 64 * file_bytes);
}

Mesh read_in_child(const std::string& what, std::int64_t memory_cap,
                   const std::function<Mesh(std::vector<std::string>&)>& read, std::vector<std::string>& notes) {
  int fd[2];
  if (::pipe2(fd, O_CLOEXEC) != 0) return read(notes);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd[0]);
    ::close(fd[1]);
    return read(notes);
  }
  if (pid == 0) {
    ::close(fd[0]);
    child(fd[1], what, memory_cap, read);
  }
  ::close(fd[1]);
  Reader in{fd[0]};
  char kind = 0;
  in.bytes(&kind, 1);
  Mesh m;
  std::string error;
  std::vector<std::string> child_notes;
  if (in.ok && kind == kMesh) {
    const auto positions = in.count(), triangles = in.count(), tetrahedra = in.count();
    in.array(m.position, positions);
    in.array(m.triangle, triangles);
    in.array(m.tetrahedron, tetrahedra);
    child_notes.resize(in.count());
    for (auto& n : child_notes) n = in.text();
  } else if (in.ok && kind == kError) {
    error = in.text();
  }
  ::close(fd[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!in.ok || (kind != kMesh && kind != kError)) {
    if (WIFSIGNALED(status))
      throw std::invalid_argument(what + ": its reader stopped on signal " + std::to_string(WTERMSIG(status)) + " (" +
                                  ::strsignal(WTERMSIG(status)) + "): a damaged file?");
    throw std::invalid_argument(what + ": its reader stopped without a mesh (exit status " +
                                std::to_string(WEXITSTATUS(status)) + "): a damaged file?");
  }
  if (kind == kError) throw std::invalid_argument(error);
  notes.insert(notes.end(), child_notes.begin(), child_notes.end());
  return m;
}

}  // namespace deformlab
