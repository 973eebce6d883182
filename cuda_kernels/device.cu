// Device properties, memory checks and the benchmarks' references: the copy bandwidth and the
// bare gather.
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "check.cuh"
#include "core/grid_stencil.hpp"
#include "core/physics.hpp"
#include "core/timed_work.hpp"
#include "cuda_pipeline.hpp"
#include "event_spans.hpp"

namespace deformlab::cuda {

std::atomic<std::int64_t> g_buffer_bytes{0};
std::int64_t buffer_bytes() { return g_buffer_bytes; }

void fail(cudaError_t e, const std::string& what) {
  throw std::runtime_error("CUDA error while " + what + ": " + cudaGetErrorName(e) + " (" + cudaGetErrorString(e) +
                           ")");
}

void require_device_memory(std::int64_t bytes, const std::string& what) {
  std::size_t free = 0, total = 0;
  check(cudaMemGetInfo(&free, &total), "querying free device memory");
  if (bytes > std::int64_t(free))
    throw std::invalid_argument(what + " needs " + std::to_string(bytes) + " bytes of device memory, but only " +
                                std::to_string(free) + " of " + std::to_string(total) + " bytes are free");
}

namespace {

// The CUDA device `device` (-1: the current one).
int device_or_current(int device) {
  if (device < 0) check(cudaGetDevice(&device), "querying the current device");
  return device;
}

std::string pci_bus_id(int device) {
  char bus[32] = {};
  check(cudaDeviceGetPCIBusId(bus, sizeof bus, device_or_current(device)), "querying the PCI bus id");
  return bus;
}

}  // namespace

DeviceInfo device_info(int device) {
  DeviceInfo d;
  const int dev = device_or_current(device);
  cudaDeviceProp p{};
  check(cudaGetDeviceProperties(&p, dev), "querying device properties");
  d.name = p.name;
  d.sm_count = p.multiProcessorCount;
  d.memory_gib = double(p.totalGlobalMem) / double(1 << 30);
  d.cc_major = p.major;
  d.cc_minor = p.minor;
  check(cudaDriverGetVersion(&d.driver_version), "querying the driver version");
  check(cudaRuntimeGetVersion(&d.runtime_version), "querying the runtime version");
  d.pci_bus_id = pci_bus_id(dev);
  return d;
}

namespace {

// `work` on the default stream timed as the steps are (time_back_to_back: one event at each
// call's end, as EventStepTimer times steps), after calls for `warm_ms` (warm_up) and
// kReferenceWarmUp more; the current device's clock watched. `what` names the work.
template <class Work>
TimedWork time_launches(double warm_ms, int min_calls, Work&& work, const std::string& what) {
  warm_up(work, [&] { check(cudaDeviceSynchronize(), ("warming up " + what).c_str()); }, warm_ms);
  check_launch(("starting " + what).c_str());
  std::int64_t launched = 0;
  EventStepTimer timer(nullptr, &launched, [] {});
  return time_back_to_back(timer, [&] { work(), ++launched; }, kReferenceWarmUp, min_calls, pci_bus_id(-1));
}

// cuda-fused's loads and stores on an n x n cloth without its arithmetic: each node reads its x
// and v and its stencil neighbours' x (and v: Velocities), and writes x and v with the
// neighbours' components summed in, so that no load is dead. Neighbours outside the grid are
// skipped; loads go Group at a time.
template <bool Velocities, int Group>
__global__ void bare_gather(int n, const float4* __restrict__ x, const float4* __restrict__ v,
                            float4* __restrict__ xo, float4* __restrict__ vo) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x, j = blockIdx.y * blockDim.y + threadIdx.y;
  if (i >= n || j >= n) return;
  const int node = j * n + i;
  float4 sx = x[node], sv = v[node];
  const bool inside = i >= STENCIL_REACH && i < n - STENCIL_REACH && j >= STENCIL_REACH && j < n - STENCIL_REACH;
#pragma unroll
  for (int g = 0; g < kClothStencil; g += Group) {
    float4 xn[Group], vn[Group];
#pragma unroll
    for (int q = 0; q < Group; ++q) {
      const GridOffset o = grid_offset(false, g + q);
      const bool ok = inside || (i + o.di >= 0 && i + o.di < n && j + o.dj >= 0 && j + o.dj < n);
      const int at = node + o.di + o.dj * n;
      xn[q] = ok ? x[at] : float4{};
      if (Velocities) vn[q] = ok ? v[at] : float4{};
    }
#pragma unroll
    for (int q = 0; q < Group; ++q) {
      sx.x += xn[q].x, sx.y += xn[q].y, sx.z += xn[q].z;
      if (Velocities) sv.x += vn[q].x, sv.y += vn[q].y, sv.z += vn[q].z;
    }
  }
  xo[node] = sx;
  vo[node] = sv;
}

}  // namespace

TimedWork time_copy(std::int64_t bytes, int min_reps, double warm_ms) {
  require_device_memory(2 * bytes, "the copy benchmark");
  Buffer<char> a, b;
  a.allocate(std::size_t(bytes), "allocating the copy source");
  b.allocate(std::size_t(bytes), "allocating the copy destination");
  check(cudaMemset(a.get(), 1, std::size_t(bytes)), "filling the copy source");
  return time_launches(warm_ms, min_reps, [&] {
    check(cudaMemcpyAsync(b.get(), a.get(), std::size_t(bytes), cudaMemcpyDeviceToDevice), "copying device memory");
  }, "the copy");
}

TimedWork time_bare_gather(int n, Tile tile, bool velocities, double warm_ms) {
  const std::int64_t nodes = std::int64_t(n) * n;
  require_device_memory(4 * nodes * std::int64_t(sizeof(float4)), "the bare gather");
  Buffer<float4> x, v, xo, vo;
  x.allocate(std::size_t(nodes), "allocating the bare gather's positions");
  v.allocate(std::size_t(nodes), "allocating the bare gather's velocities");
  xo.allocate(std::size_t(nodes), "allocating the bare gather's output positions");
  vo.allocate(std::size_t(nodes), "allocating the bare gather's output velocities");
  for (const Buffer<float4>* b : {&x, &v, &xo, &vo})
    check(cudaMemset(b->get(), 0x3c, b->size() * sizeof(float4)), "filling the bare gather's arrays");
  const dim3 threads(unsigned(tile.x), unsigned(tile.y)),
      blocks(unsigned((n + tile.x - 1) / tile.x), unsigned((n + tile.y - 1) / tile.y));
  using Kernel = void (*)(int, const float4*, const float4*, float4*, float4*);
  auto pick = [&](auto group) -> Kernel {
    constexpr int g = decltype(group)::value;
    return velocities ? bare_gather<true, g> : bare_gather<false, g>;
  };
  TimedWork best;
  for (const Kernel kernel : {pick(std::integral_constant<int, 1>{}), pick(std::integral_constant<int, 2>{}),
                              pick(std::integral_constant<int, 4>{})}) {
    TimedWork w = time_launches(warm_ms, 10, [&] {
      kernel<<<blocks, threads>>>(n, x.get(), v.get(), xo.get(), vo.get());
    }, "the bare gather");
    if (best.ms.empty() || w.median_ms() < best.median_ms()) best = std::move(w);
  }
  return best;
}

}  // namespace deformlab::cuda
