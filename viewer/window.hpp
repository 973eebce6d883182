// The viewer's window: GLFW with an OpenGL 4.5 core context that becomes the process's GL
// context (gl::adopt_current_context), Dear ImGui over it, and the user's input as Events.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "script.hpp"

struct GLFWwindow;

namespace deformlab::viewer {

class Window {
 public:
  // Throws std::invalid_argument with one line when no window can be opened (no display).
  Window(int width, int height, const std::string& title);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  bool should_close() const;
  void set_title(const std::string& title);
  // Polls the window system: the mouse and key input the panel does not take, as events of
  // `frame`, are appended to `out`.
  void poll(int frame, std::vector<Event>& out);
  void begin_panel();  // an ImGui frame
  void end_panel();    // draws it over the current framebuffer
  void swap();
  // The framebuffer's size in pixels.
  int width() const;
  int height() const;

  struct Input;  // where the window system's callbacks put their events

 private:
  GLFWwindow* w_ = nullptr;
  std::unique_ptr<Input> input_;
};

}  // namespace deformlab::viewer
