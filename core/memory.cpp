#include "memory.hpp"

#include <fstream>
#include <sstream>

#include "model.hpp"

namespace deformlab {

std::int64_t model_host_bytes(const ModelSize& s) {
  const std::int64_t nodes = s.nodes * kGridBytesPerNode;
  if (s.grid) return nodes;
  // spring ends, rest length, kind, per-spring k and kd; CSR offsets and two links per spring
  return nodes + s.springs * (4 + 4 + 4 + 1 + 4 + 4) + (s.nodes + 1) * 4 + 2 * s.springs * (4 + 4);
}

std::int64_t state_host_bytes(std::int64_t nodes) { return nodes * 2 * 12; }

namespace {

std::optional<std::int64_t> read_number(const std::string& file) {
  std::ifstream in(file);
  std::string word;
  if (!(in >> word) || word == "max") return std::nullopt;
  try {
    return std::stoll(word);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::int64_t stat_value(const std::string& file, const std::string& key) {
  std::ifstream in(file);
  std::string k;
  std::int64_t v = 0;
  while (in >> k >> v)
    if (k == key) return v;
  return 0;
}

// The memory limit of the process's cgroup (v2 "0::/path": memory.max; v1 "N:memory:/path":
// memory.limit_in_bytes), less what the group uses beyond reclaimable file cache. None when
// there is no limit or it cannot be read.
std::optional<MemoryLimit> cgroup_limit() {
  std::ifstream in("/proc/self/cgroup");
  for (std::string line; std::getline(in, line);) {
    const bool v2 = line.rfind("0::", 0) == 0;
    const auto at = line.find(":memory:");
    if (!v2 && at == std::string::npos) continue;
    const std::string root = v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory";
    const std::string path = v2 ? line.substr(3) : line.substr(at + 8);
    const std::string max_file = v2 ? "/memory.max" : "/memory.limit_in_bytes";
    const std::string used_file = v2 ? "/memory.current" : "/memory.usage_in_bytes";
    for (const std::string& dir : {root + path, root}) {
      const auto max = read_number(dir + max_file), used = read_number(dir + used_file);
      if (!max || !used || *max >= (std::int64_t(1) << 60)) continue;
      const std::int64_t cache = stat_value(dir + "/memory.stat", "inactive_file");
      return MemoryLimit{*max - (*used - cache), "the cgroup's memory limit (" + dir + max_file + ")"};
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<MemoryLimit> host_memory_limit() {
  std::optional<MemoryLimit> best;
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  std::int64_t kb = 0;
  while (in >> key >> kb >> unit)
    if (key == "MemAvailable:") best = MemoryLimit{kb * 1024, "MemAvailable (/proc/meminfo)"};
  if (const auto c = cgroup_limit(); c && (!best || c->bytes < best->bytes)) best = c;
  return best;
}

std::string bytes_text(std::int64_t bytes) {
  if (bytes >= std::int64_t(1) << 30) return gib(bytes);
  std::ostringstream os;
  os.precision(3);
  os << double(bytes) / double(1 << 20) << " MiB";
  return os.str();
}

std::string about_nodes(double n) {
  std::ostringstream os;
  os.precision(3);
  os << "about " << n << " nodes";
  return os.str();
}

std::string gib(std::int64_t bytes) {
  std::ostringstream os;
  os.precision(3);
  os << double(bytes) / double(std::int64_t(1) << 30) << " GiB";
  return os.str();
}

}  // namespace deformlab
