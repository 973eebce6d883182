#include "gl_positions.hpp"

#include "cuda_kernels/cuda_pipeline.hpp"

namespace deformlab::interop {

GlPositions::GlPositions(std::int64_t nodes) : sb_(make_shared_buffers(Mode::map)) {
  buffer_ = sb_->add(std::size_t(nodes) * 16, CudaAccess::write);
}

bool GlPositions::update(Pipeline& p) {
  auto* c = dynamic_cast<cuda::CudaPipeline*>(&p);
  if (!c) return false;
  sb_->to_cuda({buffer_});
  c->copy_positions(static_cast<float4*>(sb_->cuda_ptr(buffer_)), sb_->stream());
  sb_->to_gl();
  return true;
}

}  // namespace deformlab::interop
