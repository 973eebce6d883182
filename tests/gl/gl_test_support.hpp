// Helpers for the GL tests: skip only where no GL context can be made at all.
#pragma once
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "core/pipeline.hpp"
#include "gl/context.hpp"
#include "gl/pipelines_internal.hpp"
#include "tests/support/gpu_required.hpp"

#define DEFORMLAB_REQUIRE_GL() DEFORMLAB_SKIP_IF_UNAVAILABLE(::deformlab::gl::unavailable_reason())

namespace deformlab::test {

inline std::unique_ptr<Pipeline> make_gl(const std::string& name, const PipelineSetup& s) {
  return name == "glsl-tf" ? gl::make_tf_pipeline(s) : gl::make_compute_pipeline(s);
}

}  // namespace deformlab::test
