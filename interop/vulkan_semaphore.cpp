#include "vulkan_semaphore.hpp"

#define VK_NO_PROTOTYPES
#include <dlfcn.h>
#include <vulkan/vulkan.h>

#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace deformlab::interop {

// Handles of the process's Vulkan objects; never released (see the header).
struct VulkanTimeline::Impl {
  VkDevice device = VK_NULL_HANDLE;
  VkSemaphore semaphore = VK_NULL_HANDLE;
  PFN_vkGetSemaphoreFdKHR get_semaphore_fd = nullptr;
};

namespace {

[[noreturn]] void fail(const std::string& why) {
  throw std::invalid_argument("external-gpusync unavailable: " + why);
}

void check(VkResult r, const char* what) {
  if (r != VK_SUCCESS) fail(std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")");
}

template <class F>
F load(PFN_vkGetInstanceProcAddr gipa, VkInstance inst, const char* name) {
  auto f = reinterpret_cast<F>(gipa(inst, name));
  if (!f) fail(std::string("the Vulkan loader has no ") + name);
  return f;
}

// Makes the device and semaphore. A failure part-way leaks what was made: the process keeps
// Vulkan alive anyway, and a failure is remembered, not retried.
std::unique_ptr<VulkanTimeline::Impl> make_timeline(const std::array<unsigned char, 16>& uuid) {
  auto impl = std::make_unique<VulkanTimeline::Impl>();
  VulkanTimeline::Impl& v = *impl;
  void* lib = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
  if (!lib) fail(std::string("the Vulkan loader libvulkan.so.1 is not installed (") + dlerror() + ")");
  auto gipa = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(lib, "vkGetInstanceProcAddr"));
  if (!gipa) fail("libvulkan.so.1 has no vkGetInstanceProcAddr");

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "deformlab";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = load<PFN_vkCreateInstance>(gipa, VK_NULL_HANDLE, "vkCreateInstance")(&ici, nullptr, &instance);
  if (r != VK_SUCCESS)
    fail("vkCreateInstance failed (VkResult " + std::to_string(int(r)) +
         "): no Vulkan 1.2 driver found by the loader (VK_DRIVER_FILES names its ICD file)");
  auto enumerate = load<PFN_vkEnumeratePhysicalDevices>(gipa, instance, "vkEnumeratePhysicalDevices");
  auto properties2 = load<PFN_vkGetPhysicalDeviceProperties2>(gipa, instance, "vkGetPhysicalDeviceProperties2");
  auto features2 = load<PFN_vkGetPhysicalDeviceFeatures2>(gipa, instance, "vkGetPhysicalDeviceFeatures2");
  auto extensions =
      load<PFN_vkEnumerateDeviceExtensionProperties>(gipa, instance, "vkEnumerateDeviceExtensionProperties");
  auto create_device = load<PFN_vkCreateDevice>(gipa, instance, "vkCreateDevice");
  auto gdpa = load<PFN_vkGetDeviceProcAddr>(gipa, instance, "vkGetDeviceProcAddr");

  std::uint32_t count = 0;
  check(enumerate(instance, &count, nullptr), "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> devices(count);
  check(enumerate(instance, &count, devices.data()), "vkEnumeratePhysicalDevices");
  VkPhysicalDevice pd = VK_NULL_HANDLE;
  for (VkPhysicalDevice d : devices) {
    VkPhysicalDeviceIDProperties id{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES};
    VkPhysicalDeviceProperties2 p{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &id};
    properties2(d, &p);
    if (std::memcmp(id.deviceUUID, uuid.data(), VK_UUID_SIZE) == 0) pd = d;
  }
  if (!pd)
    fail("none of the " + std::to_string(count) + " Vulkan device(s) is the CUDA device (no matching deviceUUID)");

  VkPhysicalDeviceTimelineSemaphoreFeatures timeline{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_TIMELINE_SEMAPHORE_FEATURES};
  VkPhysicalDeviceFeatures2 f{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &timeline};
  features2(pd, &f);
  if (!timeline.timelineSemaphore) fail("the Vulkan device has no timeline semaphores");
  std::uint32_t n_ext = 0;
  check(extensions(pd, nullptr, &n_ext, nullptr), "vkEnumerateDeviceExtensionProperties");
  std::vector<VkExtensionProperties> ext(n_ext);
  check(extensions(pd, nullptr, &n_ext, ext.data()), "vkEnumerateDeviceExtensionProperties");
  bool fd_ext = false;
  for (const auto& e : ext) fd_ext = fd_ext || std::strcmp(e.extensionName, VK_KHR_EXTERNAL_SEMAPHORE_FD_EXTENSION_NAME) == 0;
  if (!fd_ext) fail("the Vulkan device lacks " VK_KHR_EXTERNAL_SEMAPHORE_FD_EXTENSION_NAME);

  const float priority = 1.f;
  VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue.queueFamilyIndex = 0;
  queue.queueCount = 1;
  queue.pQueuePriorities = &priority;
  VkPhysicalDeviceTimelineSemaphoreFeatures enable{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_TIMELINE_SEMAPHORE_FEATURES};
  enable.timelineSemaphore = VK_TRUE;
  const char* names[] = {VK_KHR_EXTERNAL_SEMAPHORE_FD_EXTENSION_NAME};
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &enable};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &queue;
  dci.enabledExtensionCount = 1;
  dci.ppEnabledExtensionNames = names;
  check(create_device(pd, &dci, nullptr, &v.device), "vkCreateDevice");
  auto dev_load = [&](const char* name) {
    auto f = gdpa(v.device, name);
    if (!f) fail(std::string("the Vulkan device has no ") + name);
    return f;
  };
  v.get_semaphore_fd = reinterpret_cast<PFN_vkGetSemaphoreFdKHR>(dev_load("vkGetSemaphoreFdKHR"));
  auto create_semaphore = reinterpret_cast<PFN_vkCreateSemaphore>(dev_load("vkCreateSemaphore"));

  VkSemaphoreTypeCreateInfo type{VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO};
  type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
  type.initialValue = 0;
  VkExportSemaphoreCreateInfo exp{VK_STRUCTURE_TYPE_EXPORT_SEMAPHORE_CREATE_INFO, &type};
  exp.handleTypes = VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT;
  VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO, &exp};
  check(create_semaphore(v.device, &sci, nullptr, &v.semaphore), "vkCreateSemaphore (exportable timeline)");
  return impl;
}

}  // namespace

VulkanTimeline::VulkanTimeline(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

VulkanTimeline& VulkanTimeline::get(const std::array<unsigned char, 16>& uuid) {
  static std::mutex mu;
  static VulkanTimeline* made = nullptr;  // never deleted (see the header)
  static std::string error;
  std::lock_guard<std::mutex> lock(mu);
  if (!made && error.empty()) {
    try {
      made = new VulkanTimeline(make_timeline(uuid));
    } catch (const std::invalid_argument& e) {
      error = e.what();
    }
  }
  if (!made) throw std::invalid_argument(error);
  return *made;
}

int VulkanTimeline::export_fd() {
  VkSemaphoreGetFdInfoKHR info{VK_STRUCTURE_TYPE_SEMAPHORE_GET_FD_INFO_KHR};
  info.semaphore = impl_->semaphore;
  info.handleType = VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT;
  int fd = -1;
  const VkResult r = impl_->get_semaphore_fd(impl_->device, &info, &fd);
  if (r != VK_SUCCESS) throw std::runtime_error("vkGetSemaphoreFdKHR failed (VkResult " + std::to_string(int(r)) + ")");
  return fd;
}

}  // namespace deformlab::interop
