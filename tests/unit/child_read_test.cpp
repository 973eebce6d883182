// Mesh files read in a child process (mesh/child_read.hpp): the mesh and notes come back
// whole; a reader's error, a crash and a reader past its memory or CPU cap each become one
// std::invalid_argument naming the file, and this process goes on.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "mesh/child_read.hpp"

namespace deformlab::test {
namespace {

const ChildLimits kEnough{std::int64_t(1) << 30, 60};

std::string error_of(ChildLimits limits, const std::function<Mesh(std::vector<std::string>&)>& read) {
  std::vector<std::string> notes;
  try {
    read_in_child("mesh file 'f'", limits, read, notes);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "read";
}

TEST(ChildRead, TheMeshAndNotesComeBackWhole) {
  Mesh sent;
  for (int k = 0; k < 100000; ++k) sent.position.push_back({float(k), 0.5f * float(k), -float(k)});
  for (int k = 0; k < 3000; ++k) sent.triangle.push_back({k, k + 1, k + 7});
  for (int k = 0; k < 5000; ++k) sent.tetrahedron.push_back({k, k + 2, k + 3, 99999 - k});
  std::vector<std::string> notes{"a note from before"};
  const Mesh got = read_in_child("mesh file 'f'", kEnough, [&](std::vector<std::string>& n) {
    n.push_back("left out 2 points and 0 lines");
    n.push_back(std::string(70000, 'x'));  // longer than a pipe's buffer
    return sent;
  }, notes);
  EXPECT_EQ(got.position, sent.position);
  EXPECT_EQ(got.triangle, sent.triangle);
  EXPECT_EQ(got.tetrahedron, sent.tetrahedron);
  EXPECT_EQ(notes, (std::vector<std::string>{"a note from before", "left out 2 points and 0 lines", std::string(70000, 'x')}));
}

// After this process's OpenMP threads have run, a reader's parallel region runs in the child
// (on its one thread) instead of waiting for threads the child does not have.
TEST(ChildRead, AReaderMayRunOpenMpAfterThisProcessHas) {
  int here = 0;
#pragma omp parallel num_threads(2) reduction(+ : here)
  here += 1;
  ASSERT_EQ(here, 2);
  std::vector<std::string> notes;
  const Mesh m = read_in_child("mesh file 'f'", kEnough, [](std::vector<std::string>&) {
    int there = 0;
#pragma omp parallel reduction(+ : there)
    there += 1;
    Mesh out;
    out.position.resize(std::size_t(there));
    return out;
  }, notes);
  EXPECT_EQ(m.position.size(), 1u);
}

TEST(ChildRead, AReadersErrorComesBackAsItIs) {
  EXPECT_EQ(error_of(kEnough, [](std::vector<std::string>&) -> Mesh {
              throw std::invalid_argument("mesh file 'f': no triangles");
            }),
            "mesh file 'f': no triangles");
}

TEST(ChildRead, ACrashIsNamedWithItsSignal) {
  const std::string error = error_of(kEnough, [](std::vector<std::string>&) -> Mesh {
    std::raise(SIGSEGV);
    return {};
  });
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer takes the signal, reports it and ends the child with exit status 1.
  EXPECT_EQ(error, "mesh file 'f': its reader stopped without a mesh (exit status 1): a damaged file?");
#else
  EXPECT_EQ(error, std::string("mesh file 'f': its reader stopped on signal ") + std::to_string(SIGSEGV) + " (" +
                       strsignal(SIGSEGV) + "): a damaged file?");
#endif
}

TEST(ChildRead, AReaderPastItsMemoryCapIsStopped) {
  const std::int64_t cap = std::int64_t(256) << 20;
  const std::string error = error_of({cap, 60}, [&](std::vector<std::string>&) -> Mesh {
    Mesh m;
    m.position.resize(std::size_t(2 * cap / sizeof(Vec3f)));  // twice the cap by itself
    return m;
  });
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer's allocator ends the process where operator new would throw.
  EXPECT_EQ(error.rfind("mesh file 'f': its reader stopped", 0), 0u) << error;
#else
  EXPECT_EQ(error, "mesh file 'f': reading it took more than the 0.25 GiB of memory allowed for a file of its size "
                   "(damaged counts? DEFORMLAB_MESH_READ_GIB=N allows N GiB)");
#endif
  EXPECT_EQ(error_of({cap, 60}, [](std::vector<std::string>&) {
              Mesh m;
              m.position.resize(std::size_t(1) << 20);  // 12 MiB: well under the cap
              return m;
            }),
            "read");
}

// The cap follows the file's size unless DEFORMLAB_MESH_READ_GIB sets it (higher or lower); a
// value that is no plain decimal size is refused, naming the variable.
TEST(ChildRead, TheMemoryCapCanBeSetByTheEnvironment) {
  ::unsetenv(kReadMemoryVariable);
  EXPECT_EQ(child_read_limits(1000).memory, std::int64_t(2) << 30);
  EXPECT_EQ(child_read_limits(std::int64_t(100) << 20).memory, std::int64_t(6400) << 20);
  EXPECT_FALSE(child_read_limits(1000).memory_set);
  ::setenv(kReadMemoryVariable, "0.25", 1);
  const ChildLimits set = child_read_limits(std::int64_t(100) << 20);
  EXPECT_EQ(set.memory, std::int64_t(256) << 20);
  EXPECT_TRUE(set.memory_set);
#if !defined(__SANITIZE_ADDRESS__)  // its allocator ends the process where operator new would throw
  EXPECT_EQ(error_of(set, [&](std::vector<std::string>&) -> Mesh {
              Mesh m;
              m.position.resize(std::size_t(2 * set.memory / sizeof(Vec3f)));
              return m;
            }),
            "mesh file 'f': reading it took more than the 0.25 GiB of memory DEFORMLAB_MESH_READ_GIB allows "
            "(DEFORMLAB_MESH_READ_GIB=N allows N GiB)");
#endif
  for (const char* bad : {"", "abc", "0", "-1", "2x", "inf", "nan", "2000000", " 4", "0x10", "1e3", "1.", ".5",
                          "1.2.3", "0.001"}) {
    ::setenv(kReadMemoryVariable, bad, 1);
    try {
      child_read_limits(1000);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(e.what(), "DEFORMLAB_MESH_READ_GIB '" + std::string(bad) +
                              "': expected a decimal number of GiB from 0.01 to 1048576");
    }
  }
  ::unsetenv(kReadMemoryVariable);
}

// A library that catches the failed allocation and fails later in its own words: its error,
// with the cap beside it.
TEST(ChildRead, AnErrorAfterACaughtAllocationPastTheCapNamesBoth) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator ends the process where operator new would throw";
#endif
  const std::int64_t cap = std::int64_t(256) << 20;
  EXPECT_EQ(error_of({cap, 60}, [&](std::vector<std::string>&) -> Mesh {
              static std::vector<char> big;  // kept: an allocation the compiler cannot leave out
              try {
                big.resize(std::size_t(2 * cap));
              } catch (const std::bad_alloc&) {
              }
              throw std::invalid_argument("mesh file 'f': no nodes");
            }),
            "mesh file 'f': no nodes (an allocation past the 0.25 GiB of memory allowed for a file of its size "
            "failed before: damaged counts? DEFORMLAB_MESH_READ_GIB=N allows N GiB)");
}

TEST(ChildRead, AReaderPastItsCpuTimeIsStopped) {
  const std::string error = error_of({std::int64_t(1) << 30, 1}, [](std::vector<std::string>&) -> Mesh {
    volatile unsigned spins = 0;
    for (;;) spins = spins + 1u;
  });
  EXPECT_EQ(error, std::string("mesh file 'f': its reader stopped on signal ") + std::to_string(SIGXCPU) + " (" +
                       strsignal(SIGXCPU) + "): a damaged file?");
}

TEST(ChildRead, AnExceptionOfAnyTypeEndsInTheChild) {
  EXPECT_EQ(error_of(kEnough, [](std::vector<std::string>&) -> Mesh { throw 42; }),
            "mesh file 'f': its reader failed with an exception of unknown type");
}

}  // namespace
}  // namespace deformlab::test
