#include "viewer.hpp"

#include <GL/glew.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/interrupt.hpp"
#include "core/number_text.hpp"
#include "core/one_line.hpp"
#include "core/run.hpp"
#include "experiments/output.hpp"
#include "gl/context.hpp"
#include "experiments/pipelines.hpp"
#include "orbit.hpp"
#include "panel.hpp"
#include "recorder.hpp"
#if DEFORMLAB_VIEWER_INTEROP
#include "interop/gl_positions.hpp"
#endif

#include <stb/stb_image_write.h>

namespace deformlab::viewer {
namespace {

constexpr double kPickRadiusPx = 14.0;
constexpr int kVideoFps = 30;
using Clock = std::chrono::steady_clock;

nlohmann::json to_json(Vec3f v) { return {v.x, v.y, v.z}; }

class Viewer {
 public:
  Viewer(Window& w, Session& s, const ViewOptions& o)
      : w_(w), s_(s), o_(o), r_(s.model(), gl::with_obstacles({.width = view_width(), .height = std::max(w.height(), 1)}, s.params())),
        home_(r_.camera()), start_(s.pipeline().state()), script_(o.script) {
    if (!o_.record.empty()) rec_ = std::make_unique<Recorder>(o_.record, w_.width(), w_.height(), kVideoFps);
    summary_["recordings"] = nlohmann::json::array();
    panel_.steps_per_frame = o_.steps_per_frame;
    watch();
    draw_state();  // picking reads the depth of the frame last drawn
  }

  int loop() {
    int code = 0;
    const int video_frames = o_.seconds > 0 ? std::max(1, int(std::lround(o_.seconds * kVideoFps))) : 0;  // 0: no limit
    // SIGINT or SIGTERM ends the loop as the window's close button does, so that the
    // recording, the script and the summary are still written.
    while (!quit_ && !w_.should_close() && !InterruptCatcher::caught()) {
      std::vector<Event> events;
      for (; next_ < script_.size() && script_[next_].frame <= frame_; ++next_) events.push_back(script_[next_]);
      w_.poll(frame_, events);
      for (const Event& e : events) apply(e);
      simulate();
      draw();
      for (const std::string& file : std::exchange(shots_, {})) screenshot(file);
      if (rec_ && (rec_->width() != w_.width() || rec_->height() != w_.height())) stop_recording();
      if (rec_) add_to_recording();
      w_.swap();
      ++frame_;
      if ((o_.frames > 0 && frame_ >= o_.frames) || (video_frames > 0 && frame_ >= video_frames)) quit_ = true;
    }
    if (const int sig = InterruptCatcher::caught())
      std::cerr << "deformlab: note: " << signal_name(sig) << " at frame " << frame_
                << ": ending the session as its window's close does\n";
    try {
      if (rec_) finish_recording();
      if (!o_.save_script.empty()) write_script(o_.save_script, recorded_);
    } catch (const std::exception& e) {
      std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
      code = 1;
    }
    if (!o_.summary.empty()) code = std::max(code, write_summary());
    return failed_writes_ ? std::max(code, 1) : code;
  }

 private:
  int view_width() const { return std::max(w_.width() - kPanelWidth, 1); }

  // The pipeline's clocks and profiler, made again whenever the pipeline is.
  void watch() {
    timer_ = s_.pipeline().step_timer();
    prof_ = std::make_unique<Profiler>();
    if (panel_.profile) s_.pipeline().set_profiler(prof_.get());
  }

  void apply(const Event& e) {
    if (e.kind != Event::Kind::move || mouse_ != Mouse::none) recorded_.push_back(e);
    switch (e.kind) {
      case Event::Kind::press: return press(e);
      case Event::Kind::move: return move(e.x, e.y);
      case Event::Kind::release: return release();
      case Event::Kind::scroll: {
        gl::Camera c = r_.camera();
        zoom(c, std::pow(0.9f, float(e.y)));
        return r_.set_camera(c);
      }
      case Event::Kind::key: return key(e.key);
      case Event::Kind::set: return set(e.settings);
      case Event::Kind::screenshot: shots_.push_back(e.file); return;
      case Event::Kind::quit: quit_ = true;
    }
  }

  void press(const Event& e) {
    mx_ = e.x;
    my_ = e.y;
    if (e.button != "left") {
      mouse_ = Mouse::pan;
      return;
    }
    const gl::Camera& c = r_.camera();
    const int w = view_width(), h = r_.height();
    const State st = s_.pipeline().state();  // picking reads the state back once per click
    const std::optional<Vec3f> surface = r_.surface_at(e.x, e.y);
    const int node = surface ? nearest_node(st.x, *surface)
                             : pick_node(st.x, e.x, e.y, kPickRadiusPx, [&](Vec3f x) { return c.pixel(x, w, h); });
    if (node < 0) {
      mouse_ = Mouse::orbit;
      return;
    }
    if (e.shift) {
      s_.toggle_pin(node);
      watch();
      summary_["pins"].push_back({{"frame", frame_}, {"node", node}, {"pinned", s_.model().pinned(node)}});
      return;
    }
    mouse_ = Mouse::drag_node;
    plane_point_ = st.x[node];
    plane_normal_ = c.axes().forward;
    s_.drag(node, plane_point_);
    target_ = plane_point_;
  }

  void move(double x, double y) {
    const float dx = float(x - mx_), dy = float(y - my_);
    mx_ = x;
    my_ = y;
    gl::Camera c = r_.camera();
    switch (mouse_) {
      case Mouse::drag_node: {
        const auto [o, d] = c.ray(x, y, view_width(), r_.height());
        target_ = on_plane(o, d, plane_point_, plane_normal_);
        ray_ = {o, d};
        return s_.drag(s_.dragged(), target_);
      }
      case Mouse::orbit: orbit(c, dx * 0.008f, dy * 0.008f); break;
      case Mouse::pan: pan(c, dx, dy, r_.height()); break;
      case Mouse::none: return;
    }
    r_.set_camera(c);
  }

  // Ends a drag (also one that a reset ends: the node goes back to rest).
  void release() {
    if (mouse_ == Mouse::drag_node && s_.dragged() >= 0) {
      const int node = s_.dragged();
      const Vec3f x = s_.pipeline().state().x[node];
      nlohmann::json pick = {{"frame", frame_}, {"node", node}, {"target", to_json(target_)}, {"position", to_json(x)}};
      if (ray_) pick["ray"] = {{"origin", to_json(ray_->first)}, {"direction", to_json(ray_->second)}};
      summary_["drags"].push_back(pick);
      s_.release();
    }
    mouse_ = Mouse::none;
  }

  void finish_recording() {
    const std::unique_ptr<Recorder> r = std::move(rec_);
    r->finish();
    summary_["recordings"].push_back({{"file", r->file()}, {"frames", r->frames()}, {"fps", kVideoFps}});
    message_ = "recorded " + r->file() + " (" + std::to_string(r->frames()) + " frames)";
  }

  // A recording whose ffmpeg has gone ends with the message why; the session goes on.
  void add_to_recording() {
    try {
      rec_->add(window_pixels());
    } catch (const std::runtime_error& e) {
      message_ = e.what();
      std::cerr << "deformlab: note: " << one_line(e.what()) << "; the recording ends\n";
      rec_.reset();
    }
  }

  // Key v: a recording into deformlab-view-<frame>.mp4 starts, or the one running ends.
  void stop_recording() {
    try {
      finish_recording();
    } catch (const std::exception& e) {
      message_ = e.what();
    }
  }
  void toggle_recording() {
    if (rec_) return stop_recording();
    try {
      rec_ = std::make_unique<Recorder>("deformlab-view-" + std::to_string(frame_) + ".mp4", w_.width(), w_.height(),
                                        kVideoFps);
      message_ = "recording " + rec_->file();
    } catch (const std::exception& e) {
      message_ = e.what();
    }
  }

  void key(const std::string& k) {
    if (k == "space") paused_ = !paused_;
    else if (k == "c") panel_.colour = (panel_.colour + 1) % 3;
    else if (k == "p") shots_.push_back("deformlab-view-" + std::to_string(frame_) + ".png");
    else if (k == "v") toggle_recording();
    else if (k == "n") single_ = true;
    else if (k == "r") r_.set_camera(home_);
    else if (k == "backspace") reset();
    else if (k == "w") r_.set_wireframe(panel_.wireframe = !panel_.wireframe);
    else if (k == "m") set_mode(panel_.points ? gl::RenderOptions::Mode::automatic : gl::RenderOptions::Mode::points);
  }

  void set_mode(gl::RenderOptions::Mode m) {
    try {
      r_.set_mode(m);
      panel_.points = m == gl::RenderOptions::Mode::points;
    } catch (const std::exception& e) {
      message_ = e.what();
    }
  }

  void reset() {
    release();
    s_.reset();
    message_.clear();
    paused_ = diverged_ = false;
    watch();
  }

  // A replacement of the pipeline, integrator, options or dt.
  void set(const std::map<std::string, std::string>& settings) {
    const PipelineEntry* e = &s_.entry();
    Integrator i = s_.integrator();
    PipelineOptions o = s_.options();
    float dt = s_.params().dt;
    std::string bad;
    if (const auto it = settings.find("pipeline"); it != settings.end()) {  // first: options belong to a pipeline
      e = pipelines().find(it->second);
      if (!e) bad = "unknown pipeline '" + it->second + "'";
      else o.clear();
    }
    for (const auto& [k, v] : settings) {
      if (k == "integrator") {
        if (auto p = parse_integrator(v)) i = *p;
        else bad = "unknown integrator '" + v + "'";
      } else if (k == "dt") {
        const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), dt);
        if (end != v.data() + v.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
          bad = "dt '" + v + "' is not a number";
        else if (ec == std::errc::result_out_of_range) bad = "dt '" + v + "' is out of the float range";
      } else if (k == "options") {
        const auto eq = v.find('=');
        if (eq == std::string::npos) bad = "option '" + v + "': expected NAME=VALUE";
        else o[v.substr(0, eq)] = v.substr(eq + 1);
      }
    }
    nlohmann::json rec = {{"frame", frame_}, {"step", s_.steps()}, {"from", s_.entry().name}, {"settings", settings}};
    if (bad.empty() && e) {
      s_.pipeline().set_profiler(nullptr);
      bad = s_.replace(*e, i, o, dt);
      watch();
    }
    rec["to"] = s_.entry().name;
    if (bad.empty()) {
      rec["carried_exactly"] = s_.carried_exactly();
      message_.clear();
    } else {
      rec["error"] = message_ = bad;
    }
    summary_["replacements"].push_back(rec);
  }

  void simulate() {
    if ((paused_ && !single_) || diverged_) return;
    single_ = false;
    try {
      disp_ = s_.step(single_step_count(), timer_.get(), panel_.profile ? prof_.get() : nullptr);
    } catch (const DivergenceError& e) {
      message_ = e.what();
      diverged_ = paused_ = true;
      summary_["diverged"] = e.what();
    }
    steps_in_window_ += single_step_count();
  }
  int single_step_count() const { return paused_ ? 1 : panel_.steps_per_frame; }

  // The state into the renderer: a GL pipeline's own buffer, a CUDA pipeline's positions
  // copied on the device through interop, else a read-back.
  void draw_state() {
    Pipeline& p = s_.pipeline();
    r_.set_colour(gl::Renderer::Colour(panel_.colour), panel_.scale[panel_.colour]);
    r_.set_time(s_.time());
    if (const unsigned b = p.gl_position_buffer()) {
      r_.draw_positions(b);
      drawn_from_ = "the pipeline's own GL buffer (no copy)";
      return;
    }
#if DEFORMLAB_VIEWER_INTEROP
    try {
      if (!positions_ && interop::unavailable(interop::Mode::map).empty())
        positions_ = std::make_unique<interop::GlPositions>(s_.model().node_count());
      if (positions_ && positions_->update(p)) {
        r_.draw_positions(positions_->buffer());
        drawn_from_ = "a device copy through CUDA-GL interop (map mode)";
        return;
      }
    } catch (const std::exception& e) {
      positions_.reset();
      message_ = std::string("interop drawing failed, reading back instead: ") + e.what();
    }
#endif
    r_.draw(p.state());
    drawn_from_ = "a read-back of the state, uploaded each frame";
  }

  void draw() {
    r_.resize(view_width(), std::max(w_.height(), 1));
    draw_state();
    glBindFramebuffer(GL_READ_FRAMEBUFFER, r_.framebuffer());
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glViewport(0, 0, w_.width(), w_.height());
    glClearColor(0.08f, 0.08f, 0.09f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT);
    glBlitFramebuffer(0, 0, r_.width(), r_.height(), 0, 0, r_.width(), r_.height(), GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    refresh_stats();
    w_.begin_panel();
    const PanelActions a = show_panel(panel_, stats_, s_, message_, paused_, bool(rec_));
    w_.end_panel();
    gl::check("drawing the viewer's frame");
    // The panel's changes are applied with the next frame's input, and recorded as such.
    for (Event e : a.events) {
      e.frame = frame_ + 1;
      script_.insert(script_.begin() + long(next_++), e);
    }
    next_ -= a.events.size();
    if (a.profile_changed) {
      if (!panel_.profile) s_.pipeline().set_profiler(nullptr);
      watch();
    }
  }

  // Every half second: steps per second on the host clock, the steps' and stages' medians on
  // their own clocks, the draw's GPU time.
  void refresh_stats() {
    const double since = std::chrono::duration<double>(Clock::now() - window_start_).count();
    if (since < 0.5) return;
    stats_.measured = true;
    stats_.steps_per_s = steps_in_window_ / since;
    stats_.frames_per_s = (frame_ - window_frame_) / since;
    stats_.step_ms = median(timer_->take());
    stats_.step_clock = timer_->clock();
    stats_.draw_ms = median(r_.take_draw_ms());
    stats_.draw_clock = r_.timing_method();
    stats_.displacement = disp_;
    s_.pipeline().set_profiler(nullptr);  // pending spans into prof_
    stats_.stages = prof_->summary();
    stats_.drawn_from = drawn_from_;
    watch();
    window_start_ = Clock::now();
    window_frame_ = frame_;
    steps_in_window_ = 0;
  }

  // The window's pixels, rows from the bottom.
  std::vector<std::uint8_t> window_pixels() {
    std::vector<std::uint8_t> px(std::size_t(w_.width()) * w_.height() * 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w_.width(), w_.height(), GL_RGBA, GL_UNSIGNED_BYTE, px.data());
    gl::check("reading the window back");
    return px;
  }

  // The back buffer as drawn this frame, panel included.
  void screenshot(const std::string& file) {
    std::vector<std::uint8_t> px = window_pixels();
    const std::size_t row = std::size_t(w_.width()) * 4;
    for (int y = 0; y < w_.height() / 2; ++y)
      std::swap_ranges(px.begin() + long(y * row), px.begin() + long((y + 1) * row),
                       px.begin() + long((w_.height() - 1 - y) * row));
    std::string png;
    bool ok = stbi_write_png_to_func([](void* to, void* data, int size) { static_cast<std::string*>(to)->append(static_cast<const char*>(data), std::size_t(size)); },
                                     &png, w_.width(), w_.height(), 4, px.data(), int(row)) != 0;
    try {
      if (ok) write_atomically(file, png);  // whole or not at all: an old file of that name stays otherwise
    } catch (const std::runtime_error& e) {
      ok = false;
      std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
    }
    failed_writes_ = failed_writes_ || !ok;
    const gl::Camera& c = r_.camera();
    summary_["screenshots"].push_back({{"frame", frame_},
                                       {"file", file},
                                       {"written", ok},
                                       {"view", {view_width(), r_.height()}},
                                       {"camera", {{"eye", to_json(c.eye)}, {"target", to_json(c.target)}, {"fovy", c.fovy}}}});
    if (!ok) message_ = "cannot write " + file;
  }

  int write_summary() {
    const State st = s_.pipeline().state();
    double moved = 0.0;
    for (std::size_t k = 0; k < st.x.size(); ++k) moved = std::max(moved, double(norm(st.x[k] - start_.x[k])));
    summary_["frames"] = frame_;
    summary_["steps"] = s_.steps();
    summary_["time_s"] = s_.time();
    summary_["pipeline"] = s_.entry().name;
    summary_["drawn_from"] = drawn_from_;
    summary_["integrator"] = info(s_.integrator()).name;
    summary_["dt"] = shortest_decimal(s_.params().dt);
    summary_["largest_move_m"] = moved;  // of any node since the viewer opened
    try {
      write_atomically(o_.summary, summary_.dump(1) + "\n");
    } catch (const std::runtime_error& e) {
      std::cerr << "deformlab: error: " << one_line(e.what()) << "\n";
      return 1;
    }
    return 0;
  }

  enum class Mouse { none, drag_node, orbit, pan };
  Window& w_;
  Session& s_;
  ViewOptions o_;
  gl::Renderer r_;
  gl::Camera home_;
  State start_;
  std::vector<Event> script_, recorded_;
  std::vector<std::string> shots_;  // screenshots asked for this frame
  std::size_t next_ = 0;
  int frame_ = 0;
  bool paused_ = false, single_ = false, quit_ = false, diverged_ = false;
  bool failed_writes_ = false;  // a screenshot that could not be written: the exit code is 1
  Mouse mouse_ = Mouse::none;
  double mx_ = 0, my_ = 0;
  Vec3f plane_point_, plane_normal_, target_;
  std::optional<std::pair<Vec3f, Vec3f>> ray_;
  std::string message_;
  double disp_ = 0.0;
  std::unique_ptr<StepTimer> timer_;
  std::unique_ptr<Profiler> prof_;
  std::unique_ptr<Recorder> rec_;
#if DEFORMLAB_VIEWER_INTEROP
  std::unique_ptr<interop::GlPositions> positions_;
#endif
  std::string drawn_from_;
  PanelState panel_;
  Stats stats_;
  Clock::time_point window_start_ = Clock::now();
  int window_frame_ = 0, steps_in_window_ = 0;
  nlohmann::json summary_ = nlohmann::json::object();
};

}  // namespace

int run(Window& w, Session& s, const ViewOptions& o) {
  const InterruptCatcher signals;
  return Viewer(w, s, o).loop();
}

}  // namespace deformlab::viewer
