// Memory a run needs and the memory a machine has. A run is refused before anything is
// allocated when the model, the pipeline's own buffers and the states the run holds do not
// fit; the message names the need and the limit that refused it.
#pragma once
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace deformlab {

// A model or a run larger than this machine's memory: bad input to a run, a cell that does not
// fit to a sweep.
struct DoesNotFit : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// The nodes and springs of a model, counted without building it.
struct ModelSize {
  std::int64_t nodes = 0, springs = 0;
  bool grid = true;  // grids hold no spring arrays
};

// Host bytes of the Model itself (Model::host_bytes() of the built one).
std::int64_t model_host_bytes(const ModelSize& s);
// Host bytes of a State of this many nodes (x and v).
std::int64_t state_host_bytes(std::int64_t nodes);

// What a pipeline allocates beyond the model: host memory and memory on its device.
struct Footprint {
  std::int64_t host = 0, device = 0;
};

// GPU pipelines move states to and from the host this many nodes at a time, through one
// staging buffer of 16 bytes a node: a state never has a second full host copy.
inline constexpr int kTransferChunkNodes = 1 << 20;

// How much memory a limit leaves, and which limit it is.
struct MemoryLimit {
  std::int64_t bytes = 0;
  std::string name;  // e.g. "MemAvailable (/proc/meminfo)"
};

// The tightest of the host memory limits this process can read: MemAvailable and, where the
// process sits in a cgroup with a memory limit, that limit less the group's use (reclaimable
// file cache not counted). None if neither can be read.
std::optional<MemoryLimit> host_memory_limit();

// "12.3 GiB"
std::string gib(std::int64_t bytes);
// "0.293 MiB" under 1 GiB, else as gib().
std::string bytes_text(std::int64_t bytes);
// "about 9.85e+08 nodes": a node count estimated before a mesh is made.
std::string about_nodes(double n);

}  // namespace deformlab
