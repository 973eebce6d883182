// A CUDA pipeline's positions drawn by GL without leaving the device: a GL buffer registered
// with CUDA (the map mode of shared_buffers.hpp), filled by a device-to-device copy each time
// it is updated. What the viewer draws CUDA pipelines from.
#pragma once
#include <cstdint>
#include <memory>

#include "core/pipeline.hpp"
#include "shared_buffers.hpp"

namespace deformlab::interop {

class GlPositions {
 public:
  // Throws std::invalid_argument where the map mode is unavailable (unavailable(Mode::map)).
  explicit GlPositions(std::int64_t nodes);
  // Copies the current positions of `p` into buffer(); false, with nothing done, when `p` is
  // not a CUDA pipeline.
  bool update(Pipeline& p);
  GLuint buffer() const { return buffer_; }

 private:
  std::unique_ptr<SharedBuffers> sb_;
  GLuint buffer_ = 0;
};

}  // namespace deformlab::interop
