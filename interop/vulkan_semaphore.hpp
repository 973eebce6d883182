// A Vulkan timeline semaphore exported as opaque POSIX fds, to be imported into GL and CUDA.
// Vulkan is reached through its loader at run time (dlopen libvulkan.so.1), so binaries
// load where there is no loader or driver; the reason shows when the semaphore is made.
// One per process, made on first use and never destroyed: on the H100's driver, tearing
// Vulkan down (device, instance, loader) lost the process's EGL display, and destroying the
// device while imports were in use made later waits hang.
#pragma once
#include <array>
#include <memory>
#include <string>

namespace deformlab::interop {

class VulkanTimeline {
 public:
  // The semaphore on the Vulkan device whose deviceUUID is `uuid` (the CUDA device's; the
  // first call's, as the process has one GL context and so one device). Throws
  // std::invalid_argument naming what is missing (loader, driver, device, extension, feature),
  // the same way on every call.
  static VulkanTimeline& get(const std::array<unsigned char, 16>& uuid);
  VulkanTimeline(const VulkanTimeline&) = delete;
  VulkanTimeline& operator=(const VulkanTimeline&) = delete;
  // A new fd for the semaphore; each importer takes ownership of its own.
  int export_fd();

  struct Impl;  // the Vulkan handles
  explicit VulkanTimeline(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace deformlab::interop
