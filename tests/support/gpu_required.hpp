// The skip rule of the tests whose GPU stage may be unavailable here (no device, no driver, no
// GL context, no interop): they skip, so that a machine without a GPU stays green, unless the run
// requires every GPU stage (DEFORMLAB_REQUIRE_GPU=1, as scripts/gpu-check.sh sets on a GPU
// machine), where such a stage is a failure rather than a test passed over.
#pragma once
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace deformlab::test {

inline bool gpu_required() {
  const char* v = std::getenv("DEFORMLAB_REQUIRE_GPU");
  return v != nullptr && std::string(v) == "1";
}

}  // namespace deformlab::test

// `why`: why the stage is unavailable here, empty where it runs.
#define DEFORMLAB_SKIP_IF_UNAVAILABLE(why)                                                         \
  do {                                                                                             \
    if (const std::string why_ = (why); !why_.empty()) {                                           \
      if (::deformlab::test::gpu_required()) FAIL() << "a GPU stage this run requires is unavailable: " << why_; \
      GTEST_SKIP() << why_;                                                                        \
    }                                                                                              \
  } while (0)
