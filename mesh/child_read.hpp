// A mesh file read in a child process. assimp and Gmsh trust the counts and offsets a file
// states: on a damaged file they can crash, loop or ask for more memory than the machine has.
// The child reads under a memory and a CPU-time cap and hands the mesh back through a pipe; a
// crash or a cap becomes one line naming the file, and the parent runs on.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/mesh_model.hpp"

namespace deformlab {

struct ChildLimits {
  std::int64_t memory = 0;  // bytes the child's data segment may grow by
  int cpu_s = 0;            // seconds of CPU time
  bool memory_set = false;  // by kReadMemoryVariable, not by the file's size
};

// The environment variable that sets the memory cap in GiB, in place of the one the file's size
// gives: for files whose mesh takes far more than 64 times their size (a glTF that instances one
// mesh thousands of times), or a lower cap.
inline constexpr const char* kReadMemoryVariable = "DEFORMLAB_MESH_READ_GIB";

// The limits for a file of this size: memory 64 times the file, at least 2 GiB (the data
// segment counts address space, not pages touched: a 34 MB OBJ took 1.2 GB of it in assimp,
// 560 MB resident), or what kReadMemoryVariable sets (std::invalid_argument where it is no
// decimal number in [0.01, 1048576]); CPU 60 s and 2 s a MB (assimp read that OBJ in 1.1 s of
// CPU time and a 47 MB binary STL in 0.7 s, Gmsh a 52 MB binary .msh in 0.24 s, on a 2-core
// machine).
ChildLimits child_read_limits(std::int64_t file_bytes);

// Runs read(notes) in a child process under `limits` and returns its mesh and notes. Throws
// std::invalid_argument starting "<what>: " when the reader throws (with its message), runs
// out of memory or stops without a mesh (a signal, the CPU cap among them). Where no child
// can be started, reads in this process.
Mesh read_in_child(const std::string& what, ChildLimits limits,
                   const std::function<Mesh(std::vector<std::string>&)>& read, std::vector<std::string>& notes);

}  // namespace deformlab
