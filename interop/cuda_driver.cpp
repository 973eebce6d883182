#include "cuda_driver.hpp"

#include <cuda.h>
#include <cuda_runtime.h>

#include <algorithm>
#include <mutex>
#include <type_traits>
#include <stdexcept>

namespace deformlab::interop {
namespace {

struct Driver {
  decltype(&::cuDeviceGet) device_get = nullptr;
  decltype(&::cuDeviceGetAttribute) device_attribute = nullptr;
  decltype(&::cuMemGetAllocationGranularity) granularity = nullptr;
  decltype(&::cuMemCreate) create = nullptr;
  decltype(&::cuMemRelease) release = nullptr;
  decltype(&::cuMemAddressReserve) reserve = nullptr;
  decltype(&::cuMemAddressFree) address_free = nullptr;
  decltype(&::cuMemMap) map = nullptr;
  decltype(&::cuMemUnmap) unmap = nullptr;
  decltype(&::cuMemSetAccess) set_access = nullptr;
  decltype(&::cuMemExportToShareableHandle) export_handle = nullptr;
  std::string error;  // why the entry points could not all be found
};

const Driver& driver() {
  static Driver d;
  static std::once_flag once;
  std::call_once(once, [] {
    auto get = [](const char* name, auto& fn) {
      void* p = nullptr;
      cudaDriverEntryPointQueryResult status{};
      const cudaError_t e = cudaGetDriverEntryPointByVersion(name, &p, 12000, cudaEnableDefault, &status);
      if (e != cudaSuccess || status != cudaDriverEntryPointSuccess || !p) {
        if (d.error.empty())
          d.error = std::string("the CUDA driver does not provide ") + name + " (" +
                    (e != cudaSuccess ? cudaGetErrorString(e) : "entry point not found") + ")";
        return;
      }
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(p);
    };
    get("cuDeviceGet", d.device_get);
    get("cuDeviceGetAttribute", d.device_attribute);
    get("cuMemGetAllocationGranularity", d.granularity);
    get("cuMemCreate", d.create);
    get("cuMemRelease", d.release);
    get("cuMemAddressReserve", d.reserve);
    get("cuMemAddressFree", d.address_free);
    get("cuMemMap", d.map);
    get("cuMemUnmap", d.unmap);
    get("cuMemSetAccess", d.set_access);
    get("cuMemExportToShareableHandle", d.export_handle);
  });
  return d;
}

void check(CUresult r, const char* what) {
  if (r != CUDA_SUCCESS) throw std::runtime_error(std::string("CUDA driver error ") + std::to_string(int(r)) + " in " + what);
}

CUmemAllocationProp properties(int device) {
  CUmemAllocationProp p{};
  p.type = CU_MEM_ALLOCATION_TYPE_PINNED;
  p.location.type = CU_MEM_LOCATION_TYPE_DEVICE;
  p.location.id = device;
  p.requestedHandleTypes = CU_MEM_HANDLE_TYPE_POSIX_FILE_DESCRIPTOR;
  return p;
}

}  // namespace

std::string exportable_memory_unavailable(int device) {
  const Driver& d = driver();
  if (!d.error.empty()) return d.error;
  CUdevice dev = 0;
  if (d.device_get(&dev, device) != CUDA_SUCCESS) return "cuDeviceGet failed for CUDA device " + std::to_string(device);
  int vmm = 0, fd = 0;
  d.device_attribute(&vmm, CU_DEVICE_ATTRIBUTE_VIRTUAL_MEMORY_MANAGEMENT_SUPPORTED, dev);
  d.device_attribute(&fd, CU_DEVICE_ATTRIBUTE_HANDLE_TYPE_POSIX_FILE_DESCRIPTOR_SUPPORTED, dev);
  if (!vmm) return "CUDA device " + std::to_string(device) + " has no virtual memory management (cuMemCreate)";
  if (!fd) return "CUDA device " + std::to_string(device) + " cannot export memory as a POSIX fd";
  return {};
}

ExportableAllocation::ExportableAllocation(int device, std::size_t bytes) {
  if (const std::string why = exportable_memory_unavailable(device); !why.empty()) throw std::invalid_argument(why);
  const Driver& d = driver();
  const CUmemAllocationProp prop = properties(device);
  std::size_t g = 0;
  check(d.granularity(&g, &prop, CU_MEM_ALLOC_GRANULARITY_RECOMMENDED), "cuMemGetAllocationGranularity");
  size_ = (std::max<std::size_t>(bytes, 1) + g - 1) / g * g;
  CUmemGenericAllocationHandle h = 0;
  check(d.create(&h, size_, &prop, 0), "cuMemCreate (exportable device memory)");
  handle_ = h;
  try {
    CUdeviceptr p = 0;
    check(d.reserve(&p, size_, 0, 0, 0), "cuMemAddressReserve");
    ptr_ = p;
    check(d.map(p, size_, 0, h, 0), "cuMemMap");
    mapped_ = true;
    CUmemAccessDesc access{};
    access.location = prop.location;
    access.flags = CU_MEM_ACCESS_FLAGS_PROT_READWRITE;
    check(d.set_access(p, size_, &access, 1), "cuMemSetAccess");
  } catch (...) {
    release();
    throw;
  }
}

ExportableAllocation::~ExportableAllocation() { release(); }

void ExportableAllocation::release() {
  const Driver& d = driver();
  if (mapped_) d.unmap(CUdeviceptr(ptr_), size_);
  if (ptr_) d.address_free(CUdeviceptr(ptr_), size_);
  if (handle_) d.release(CUmemGenericAllocationHandle(handle_));
  mapped_ = false;
  ptr_ = handle_ = 0;
}

int ExportableAllocation::export_fd() const {
  int fd = -1;
  check(driver().export_handle(&fd, CUmemGenericAllocationHandle(handle_), CU_MEM_HANDLE_TYPE_POSIX_FILE_DESCRIPTOR, 0),
        "cuMemExportToShareableHandle (POSIX fd)");
  return fd;
}

}  // namespace deformlab::interop
