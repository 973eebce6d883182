// CUDA memory from the driver's virtual memory API (cuMemCreate), exportable as a POSIX fd
// for GL_EXT_memory_object_fd. The driver API is reached through the runtime
// (cudaGetDriverEntryPointByVersion), so nothing links against libcuda.
#pragma once
#include <cstddef>
#include <string>

namespace deformlab::interop {

// Empty when `device` can export cuMemCreate memory as a POSIX fd, else why not.
std::string exportable_memory_unavailable(int device);

class ExportableAllocation {
 public:
  // At least `bytes` on `device`, rounded up to the allocation granularity, mapped
  // read-write into this process's CUDA address space.
  ExportableAllocation(int device, std::size_t bytes);
  ~ExportableAllocation();
  ExportableAllocation(const ExportableAllocation&) = delete;
  ExportableAllocation& operator=(const ExportableAllocation&) = delete;
  void* ptr() const { return reinterpret_cast<void*>(ptr_); }
  std::size_t size() const { return size_; }  // the allocation's size (what an importer must name)
  // A new fd for the allocation; the caller (the importer) owns it.
  int export_fd() const;

 private:
  void release();
  unsigned long long handle_ = 0, ptr_ = 0;
  std::size_t size_ = 0;
  bool mapped_ = false;
};

}  // namespace deformlab::interop
