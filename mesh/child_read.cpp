#include "child_read.hpp"

#include <fcntl.h>
#include <signal.h>
#include <omp.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "core/memory.hpp"

namespace deformlab {

namespace {

// The pipe's messages: 'M', the three array lengths, the arrays, the note count and the
// notes; or 'E' and the error's text. A string is its length (8 bytes) and its bytes.
constexpr char kMesh = 'M', kError = 'E';

// All `size` bytes through `fd` by read(2) or write(2) (`call`), again after a signal or a
// short count; false at the end of the pipe or on an error.
template <class Byte, class Call>
bool whole(Call call, int fd, Byte* p, std::size_t size) {
  while (size) {
    const ssize_t n = call(fd, p, size);
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
  void bytes(const void* data, std::size_t size) { ok = ok && whole(::write, fd, static_cast<const char*>(data), size); }
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
  void bytes(void* data, std::size_t size) { ok = ok && whole(::read, fd, static_cast<char*>(data), size); }
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

// In the child: caps its data segment at what it has plus the limit and its CPU time, reads,
// writes the message and ends; nothing it throws or returns gets back into the caller's code.
[[noreturn]] void child(int fd, const std::string& what, ChildLimits limits,
                        const std::function<Mesh(std::vector<std::string>&)>& read) noexcept {
  // The libraries' own complaints (and, in a sanitizer build, the sanitizer's report, whose exit
  // status still ends the read with an error) stay out of the one line the parent writes.
  if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, STDERR_FILENO);
  // The parent's OpenMP threads are not in the child, and libgomp would wait for them in a
  // parallel region of more than one thread: a reader that runs one runs it on this thread.
  omp_set_num_threads(1);
  if (FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    long kb = -1;
    while (kb < 0 && std::fgets(line, sizeof line, f)) std::sscanf(line, "VmData: %ld kB", &kb);
    std::fclose(f);
    if (rlimit data{}; kb >= 0 && ::getrlimit(RLIMIT_DATA, &data) == 0) {
      data.rlim_cur = std::min(data.rlim_cur, rlim_t(kb) * 1024 + rlim_t(limits.memory));
      ::setrlimit(RLIMIT_DATA, &data);
    }
  }
  if (rlimit cpu{}; ::getrlimit(RLIMIT_CPU, &cpu) == 0) {  // a child's CPU time starts at 0
    cpu.rlim_cur = std::min(cpu.rlim_cur, rlim_t(limits.cpu_s));
    ::setrlimit(RLIMIT_CPU, &cpu);
  }
  // An allocation past the cap: named as such when it ends the read, and beside the reader's
  // own error when a library caught it and failed later in its own words.
  static bool out_of_memory = false;
  std::set_new_handler([] {
    out_of_memory = true;
    std::set_new_handler(nullptr);
    throw std::bad_alloc();
  });
  const std::string setting = kReadMemoryVariable;
  const std::string cap = "the " + gib(limits.memory) + " of memory " +
                          (limits.memory_set ? setting + " allows" : "allowed for a file of its size");
  const std::string raise = (limits.memory_set ? "" : "damaged counts? ") + setting + "=N allows N GiB";
  Writer out{fd};
  auto send = [&](const std::string& error) {
    out.bytes(&kError, 1);
    out.text(error);
  };
  auto fail = [&](const std::string& error) {
    send(out_of_memory ? error + " (an allocation past " + cap + " failed before: " + raise + ")" : error);
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
  } catch (const std::bad_alloc& e) {  // not past the cap: std::bad_array_new_length
    if (out_of_memory) send(what + ": reading it took more than " + cap + " (" + raise + ")");
    else fail(what + ": " + e.what());
  } catch (const std::exception& e) {
    fail(e.what());
  } catch (...) {
    fail(what + ": its reader failed with an exception of unknown type");
  }
  ::_exit(out.ok ? 0 : 1);
}

// The parent's end of the pipe and the child: closed and reaped however the parent leaves.
struct ChildEnd {
  int fd;
  pid_t pid;
  int status = 0;
  bool reaped = false;
  int wait() {
    ::close(std::exchange(fd, -1));
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    reaped = true;
    return status;
  }
  ~ChildEnd() {
    if (reaped) return;
    ::kill(pid, SIGKILL);
    wait();
  }
};

}  // namespace

ChildLimits child_read_limits(std::int64_t file_bytes) {
  ChildLimits l{std::max<std::int64_t>(std::int64_t(2) << 30, 64 * file_bytes), int(60 + 2 * (file_bytes >> 20))};
  if (const char* set = std::getenv(kReadMemoryVariable)) {
    const std::string_view text = set;
    const bool decimal = !text.empty() && text.find_first_not_of("0123456789.") == std::string_view::npos &&
                         text.find('.') == text.rfind('.') && text.front() != '.' && text.back() != '.';
    const double gib = decimal ? std::strtod(set, nullptr) : 0.0;
    if (!(gib >= 0.01 && gib <= 1048576))
      throw std::invalid_argument(std::string(kReadMemoryVariable) + " '" + set +
                                  "': expected a decimal number of GiB from 0.01 to 1048576");
    l.memory = std::int64_t(gib * double(std::int64_t(1) << 30));
    l.memory_set = true;
  }
  return l;
}

Mesh read_in_child(const std::string& what, ChildLimits limits,
                   const std::function<Mesh(std::vector<std::string>&)>& read, std::vector<std::string>& notes) {
  int fd[2];
  if (::pipe2(fd, O_CLOEXEC) != 0) return read(notes);
  std::fflush(nullptr);  // else the child's copy of an unwritten stdout buffer could be written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd[0]);
    ::close(fd[1]);
    return read(notes);
  }
  if (pid == 0) {
    ::close(fd[0]);
    child(fd[1], what, limits, read);
  }
  ::close(fd[1]);
  ChildEnd end{fd[0], pid};
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
  const int status = end.wait();
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
