// Whether this machine can run the CUDA pipelines (plain C++17: availability.cu is also built
// alone, for other architectures, by its test).
#pragma once
#include <string>

namespace deformlab::cuda {

// Empty when a CUDA device can be used, else the reason: no driver, no device, a device this
// build has no code for, or another error of the first call on it. A probe kernel's attributes
// are asked of the current device (device 0 unless one was chosen), which creates its context.
std::string unavailable();

}  // namespace deformlab::cuda
