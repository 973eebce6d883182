// Device discovery, memory checks and the benchmarks' ceilings: the copy bandwidth and the
// gather floor.
#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "check.cuh"
#include "core/grid_stencil.hpp"
#include "cuda_pipeline.hpp"

namespace deformlab::cuda {

void fail(cudaError_t e, const std::string& what) {
  throw std::runtime_error("CUDA error while " + what + ": " + cudaGetErrorName(e) + " (" + cudaGetErrorString(e) +
                           ")");
}

std::string unavailable() {
  static std::once_flag once;
  static std::string why;
  std::call_once(once, [] {
    int count = 0;
    const cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess)
      why = std::string("no usable CUDA driver or device (cudaGetDeviceCount: ") + cudaGetErrorString(e) + ")";
    else if (count == 0)
      why = "no CUDA device";
  });
  return why;
}

void require_device_memory(std::int64_t bytes, const std::string& what) {
  std::size_t free = 0, total = 0;
  check(cudaMemGetInfo(&free, &total), "querying free device memory");
  if (bytes > std::int64_t(free))
    throw std::invalid_argument(what + " needs " + std::to_string(bytes) + " bytes of device memory, but only " +
                                std::to_string(free) + " of " + std::to_string(total) + " bytes are free");
}

DeviceInfo device_info() {
  DeviceInfo d;
  int dev = 0;
  check(cudaGetDevice(&dev), "querying the current device");
  cudaDeviceProp p{};
  check(cudaGetDeviceProperties(&p, dev), "querying device properties");
  d.name = p.name;
  d.sm_count = p.multiProcessorCount;
  d.memory_gib = double(p.totalGlobalMem) / double(1 << 30);
  d.cc_major = p.major;
  d.cc_minor = p.minor;
  check(cudaDriverGetVersion(&d.driver_version), "querying the driver version");
  check(cudaRuntimeGetVersion(&d.runtime_version), "querying the runtime version");
  return d;
}

double copy_ms(std::int64_t bytes, int reps) {
  require_device_memory(2 * bytes, "the copy benchmark");
  Buffer<char> a, b;
  a.allocate(std::size_t(bytes), "allocating the copy source");
  b.allocate(std::size_t(bytes), "allocating the copy destination");
  check(cudaMemset(a.get(), 1, std::size_t(bytes)), "filling the copy source");
  cudaEvent_t e0, e1;
  check(cudaEventCreate(&e0), "creating a timing event");
  check(cudaEventCreate(&e1), "creating a timing event");
  std::vector<double> ms;
  for (int r = 0; r <= reps; ++r) {
    check(cudaEventRecord(e0), "recording the copy start");
    check(cudaMemcpyAsync(b.get(), a.get(), std::size_t(bytes), cudaMemcpyDeviceToDevice), "copying device memory");
    check(cudaEventRecord(e1), "recording the copy end");
    check(cudaEventSynchronize(e1), "running the copy");
    float t = 0.f;
    check(cudaEventElapsedTime(&t, e0, e1), "reading the copy timer");
    if (r > 0) ms.push_back(t);  // the first copy is a warm-up
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

namespace {

// cuda-fused's loads and stores on an n x n cloth without its arithmetic: each node reads its x
// and v, its stencil neighbours' x (and v: Velocities), Verlet's previous position (Previous,
// over which x is written), and writes x and v with the neighbours' components summed in, so
// that no load is dead. Neighbours outside the grid are skipped; loads go four at a time.
template <bool Velocities, bool Previous>
__global__ void gather_floor(int n, const float4* __restrict__ x, const float4* __restrict__ v, float4* xo,
                             float4* __restrict__ vo) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x, j = blockIdx.y * blockDim.y + threadIdx.y;
  if (i >= n || j >= n) return;
  const int node = j * n + i;
  float4 sx = x[node], sv = v[node];
  if (Previous) sx.w += xo[node].x;
  const bool inside = i >= 2 && i < n - 2 && j >= 2 && j < n - 2;
#pragma unroll
  for (int g = 0; g < kClothStencil; g += 4) {
    float4 xn[4], vn[4];
#pragma unroll
    for (int q = 0; q < 4; ++q) {
      const GridOffset o = grid_offset(false, g + q);
      const bool ok = inside || (i + o.di >= 0 && i + o.di < n && j + o.dj >= 0 && j + o.dj < n);
      const int at = node + o.di + o.dj * n;
      xn[q] = ok ? x[at] : float4{};
      if (Velocities) vn[q] = ok ? v[at] : float4{};
    }
#pragma unroll
    for (int q = 0; q < 4; ++q) {
      sx.x += xn[q].x, sx.y += xn[q].y, sx.z += xn[q].z;
      if (Velocities) sv.x += vn[q].x, sv.y += vn[q].y, sv.z += vn[q].z;
    }
  }
  xo[node] = sx;
  vo[node] = sv;
}

}  // namespace

double gather_floor_ms(int n, Tile tile, bool velocities, bool previous, int batches) {
  const std::int64_t nodes = std::int64_t(n) * n;
  require_device_memory(4 * nodes * std::int64_t(sizeof(float4)), "the gather floor");
  Buffer<float4> x, v, xo, vo;
  x.allocate(std::size_t(nodes), "allocating the gather floor's positions");
  v.allocate(std::size_t(nodes), "allocating the gather floor's velocities");
  xo.allocate(std::size_t(nodes), "allocating the gather floor's output positions");
  vo.allocate(std::size_t(nodes), "allocating the gather floor's output velocities");
  for (const Buffer<float4>* b : {&x, &v, &xo, &vo})
    check(cudaMemset(b->get(), 0x3c, b->size() * sizeof(float4)), "filling the gather floor's arrays");
  const dim3 threads(unsigned(tile.x), unsigned(tile.y)),
      blocks(unsigned((n + tile.x - 1) / tile.x), unsigned((n + tile.y - 1) / tile.y));
  auto kernel = velocities ? (previous ? gather_floor<true, true> : gather_floor<true, false>)
                           : (previous ? gather_floor<false, true> : gather_floor<false, false>);
  constexpr int kWarmup = 10, kBatch = 10;
  auto launch = [&] { kernel<<<blocks, threads>>>(n, x.get(), v.get(), xo.get(), vo.get()); };
  for (int w = 0; w < kWarmup; ++w) launch();
  check_launch("launching the gather floor");
  cudaEvent_t e0, e1;
  check(cudaEventCreate(&e0), "creating a timing event");
  check(cudaEventCreate(&e1), "creating a timing event");
  std::vector<double> ms;
  for (int b = 0; b < batches; ++b) {
    check(cudaEventRecord(e0), "recording the gather floor's start");
    for (int l = 0; l < kBatch; ++l) launch();
    check(cudaEventRecord(e1), "recording the gather floor's end");
    check(cudaEventSynchronize(e1), "running the gather floor");
    float t = 0.f;
    check(cudaEventElapsedTime(&t, e0, e1), "reading the gather floor's timer");
    ms.push_back(double(t) / kBatch);
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

}  // namespace deformlab::cuda
