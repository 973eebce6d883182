// This device's ceilings, for reports to show every stage time against its own ceiling and
// every hand-off against the floor: device-to-device copy bandwidth, pass-through transform
// feedback vertex rate, compute-shader copy bandwidth (on the memory the GL pipelines' node
// buffers take by default, and on GL's own buffers where that differs), the bare hand-off cost
// of each interop mode at a few buffer sizes, and the floor (a GPU-side semaphore ping-pong
// between GL and CUDA with nothing else to do).
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>
#include <ostream>
#include <vector>

namespace deformlab::interop {

struct CalibrateOptions {
  std::int64_t copy_bytes = std::int64_t(1) << 30;   // device-to-device copy
  std::int64_t tf_vertices = 2048 * 2048;            // pass-through transform feedback
  std::int64_t compute_nodes = std::int64_t(1) << 23;  // compute-shader copy, one vec4 per node
  std::vector<std::int64_t> hand_off_nodes{64 * 64, 512 * 512, 2048 * 2048};  // 16 B per node per buffer
  int reps = 10;          // timed calls of the bandwidth and rate measurements at the least (median)
  int round_trips = 200;  // per hand-off measurement (after 20 warm-up rounds)
};

// Throws std::invalid_argument when CUDA or OpenGL (or a CUDA device behind the GL context)
// is missing. Progress lines go to `log`.
nlohmann::json calibrate(const CalibrateOptions& o, std::ostream& log);
// The floor alone: microseconds per hand-off of a GPU-side semaphore ping-pong between GL
// and CUDA with no work; NaN where external-gpusync is unavailable.
double hand_off_floor_us(int round_trips);

}  // namespace deformlab::interop
