// Whether this machine can run the CUDA pipelines (plain C++17: availability.cu is also built
// alone, for other architectures, by its test).
#pragma once
#include <string>

namespace deformlab::cuda {

// Empty when a CUDA device can be used, else the reason (no driver, no device, or a device this
// build has no code for: a probe kernel's attributes are asked for, which creates the context).
std::string unavailable();

}  // namespace deformlab::cuda
