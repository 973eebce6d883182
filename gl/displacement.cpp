// The GL pipelines' step back and their stop rule's read-back: the largest displacement of a
// step, reduced into a word a state set (reduce_displacement, or posted by the result pass
// itself) and read through a persistently mapped buffer.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <thread>
#include <utility>

#include "gl_pipeline.hpp"

namespace deformlab::gl {

void GlPipeline::step_back() {
  if (back_ != Back::possible) throw std::logic_error(name_ + ": no step to take back");
  // A read queued after the step taken back, and not posted (no step since): copied now, before
  // the clears lose it.
  if (read_queued_ && !read_done_ && read_launch_ != 0 && launches_ == read_launch_) copy_word();
  clear_word(cur_);  // the step taken back added into the word the next step reduces into
  cur_ = 1 - cur_;
  t_ = back_t_;
  half_step_ = back_half_step_;
  back_ = Back::taken;
}

void GlPipeline::queue_displacement() {
  if (back_ == Back::taken) throw std::logic_error(name_ + ": the displacement before a step taken back is not kept");
  if (read_queued_) throw std::logic_error(name_ + ": a displacement read is queued and not taken");
  context();
  read_queued_ = true;
  read_launch_ = stepped_ ? launches_ : 0;
  if (stepped_ && !posts_words()) copy_word();  // before the next step's passes reuse the word
  check(name_ + " displacement read-back");
}

double GlPipeline::take_displacement() {
  if (!read_queued_) throw std::logic_error(name_ + ": no displacement read queued");
  const std::uint64_t steps_since = launches_ - read_launch_;
  if (!read_done_ && read_launch_ != 0 && steps_since > 1)
    throw std::logic_error(name_ + ": a displacement read is taken after the step after the next one");
  read_queued_ = false;
  context();
  std::uint32_t bits = 0;  // no step before the read: nothing moved
  if (!read_done_ && read_launch_ != 0 && steps_since == 1) {
    bits = posted_word(read_launch_);
  } else if (read_launch_ != 0) {  // copied when queued, or now: no step since
    if (!read_done_) copy_word();
    bits = copied_word();
  }
  check(name_ + " displacement read-back");
  float d;
  std::memcpy(&d, &bits, 4);
  return std::isfinite(d) ? double(d) : std::numeric_limits<double>::quiet_NaN();
}

void GlPipeline::copy_word() {
  reduce_displacement();
  glCopyNamedBufferSubData(result_.id(), readback_.id(), word_offset(cur_), 4, 4);
  read_done_ = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);  // copied_word's wait flushes it
}

std::uint32_t GlPipeline::copied_word() {
  GLenum r;
  while ((r = glClientWaitSync(read_done_, GL_SYNC_FLUSH_COMMANDS_BIT, 1'000'000'000)) == GL_TIMEOUT_EXPIRED) {
  }
  glDeleteSync(std::exchange(read_done_, nullptr));
  if (r == GL_WAIT_FAILED) throw std::runtime_error(name_ + ": waiting for the displacement read-back failed");
  return std::uint32_t(std::atomic_ref(*readback_word_).load() >> 32);
}

// Coherent mapped memory shows a pass's write once it lands, but GL promises it only after a
// fence or glFinish: the tag tells a posted word from an older one, and if none shows within a
// second (a very long step, or a driver that holds writes back) glFinish settles it.
std::uint32_t GlPipeline::posted_word(std::uint64_t launch) {
  glFlush();  // the pass that posts it
  const auto posted = [&]() -> std::optional<std::uint32_t> {
    const std::uint64_t w = std::atomic_ref(*readback_word_).load(std::memory_order_acquire);
    if (std::uint32_t(w) != std::uint32_t(launch)) return std::nullopt;
    return std::uint32_t(w >> 32);
  };
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::seconds(1)) {
    if (const auto w = posted()) return *w;
    std::this_thread::yield();  // a software renderer runs the pass on this machine's cores
  }
  glFinish();
  if (const auto w = posted()) return *w;
  throw std::runtime_error(name_ + ": the stop-rule word of result pass " + std::to_string(launch) + " was not posted");
}

double GlPipeline::max_displacement() {
  queue_displacement();
  return take_displacement();
}

void GlPipeline::clear_word(int set) {
  const std::uint32_t zero = 0;
  glClearNamedBufferSubData(result_.id(), GL_R32UI, word_offset(set), 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
}

void GlPipeline::reduce_displacement() {
  clear_word(cur_);
  glUseProgram(reduce_.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, result_.id());
  glUniform1i(reduce_word_, cur_);
  for (const NodeWindow& w : windows_) {
    bind_nodes(0, v_[cur_], w.first, w.count);
    glUniform1i(reduce_n_, w.count);
    glDispatchCompute(GLuint(std::min(1024, (w.count + 255) / 256)), 1, 1);
  }
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);  // for the copy
  glUseProgram(0);
}

}  // namespace deformlab::gl
