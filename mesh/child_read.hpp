// A mesh file read in a child process. assimp and Gmsh trust the counts and offsets a file
// states: on a damaged file they can crash or ask for more memory than the machine has. The
// child reads under a memory cap and hands the mesh back through a pipe; a crash or the cap
// becomes one line naming the file, and the parent runs on.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/mesh_model.hpp"

namespace deformlab {

// The memory a child may add to what it inherits while reading a file of this size: 64 times
// the file, at least 2 GiB. The data segment counts address space, not pages touched: a 34 MB
// OBJ took 1.2 GB of it in assimp (560 MB resident), 35 times its size.
std::int64_t child_read_memory_cap(std::int64_t file_bytes);

// Runs read(notes) in a child process whose data segment may grow by `memory_cap` bytes and
// returns its mesh and notes. Throws std::invalid_argument starting "<what>: " when the
// reader throws (with its message), runs out of memory or stops without a mesh (a signal).
// Where no child can be started, reads in this process.
Mesh read_in_child(const std::string& what, std::int64_t memory_cap,
                   const std::function<Mesh(std::vector<std::string>&)>& read, std::vector<std::string>& notes);

}  // namespace deformlab
