#include "window.hpp"

#include <GL/glew.h>
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui/backends/imgui_impl_glfw.h>
#include <imgui/backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <stdexcept>

#include "gl/context.hpp"

namespace deformlab::viewer {
namespace {

std::string g_glfw_error;
void on_glfw_error(int, const char* what) { g_glfw_error = what ? what : "unknown GLFW error"; }

// A key's name in kKeys, or "" for a key the viewer does not act on.
std::string key_name(int key) {
  std::string name;
  if (key == GLFW_KEY_SPACE) name = "space";
  else if (key == GLFW_KEY_BACKSPACE) name = "backspace";
  else if (key >= GLFW_KEY_A && key <= GLFW_KEY_Z) name = std::string(1, char('a' + key - GLFW_KEY_A));
  return std::find(kKeys.begin(), kKeys.end(), name) != kKeys.end() ? name : "";
}

}  // namespace

struct Window::Input {
  int frame = 0;
  std::vector<Event>* out = nullptr;
  void push(Event e) {
    e.frame = frame;
    if (out) out->push_back(std::move(e));
  }
};

namespace {

Window::Input& input(GLFWwindow* w) { return *static_cast<Window::Input*>(glfwGetWindowUserPointer(w)); }

void on_button(GLFWwindow* w, int button, int action, int mods) {
  if (ImGui::GetIO().WantCaptureMouse && action == GLFW_PRESS) return;
  double x = 0, y = 0;
  glfwGetCursorPos(w, &x, &y);
  Event e;
  e.x = x;
  e.y = y;
  if (action == GLFW_PRESS) {
    e.kind = Event::Kind::press;
    e.button = button == GLFW_MOUSE_BUTTON_RIGHT ? "right" : button == GLFW_MOUSE_BUTTON_MIDDLE ? "middle" : "left";
    e.shift = (mods & GLFW_MOD_SHIFT) != 0;
  } else {
    e.kind = Event::Kind::release;
  }
  input(w).push(e);
}

void on_move(GLFWwindow* w, double x, double y) {
  Event e;
  e.kind = Event::Kind::move;
  e.x = x;
  e.y = y;
  input(w).push(e);
}

void on_scroll(GLFWwindow* w, double, double dy) {
  if (ImGui::GetIO().WantCaptureMouse) return;
  Event e;
  e.kind = Event::Kind::scroll;
  e.y = dy;
  input(w).push(e);
}

void on_key(GLFWwindow* w, int key, int, int action, int) {
  if (ImGui::GetIO().WantCaptureKeyboard || action != GLFW_PRESS) return;
  Event e;
  e.kind = Event::Kind::key;
  e.key = key_name(key);
  if (!e.key.empty()) input(w).push(e);
}

}  // namespace

Window::Window(int width, int height, const std::string& title) : input_(std::make_unique<Input>()) {
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit())
    throw std::invalid_argument("view needs a display (" + g_glfw_error +
                                "); without one, `deformlab run --frames N` renders frames");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  w_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!w_) {
    glfwTerminate();
    throw std::invalid_argument("view cannot open an OpenGL 4.5 core window (" + g_glfw_error + ")");
  }
  glfwMakeContextCurrent(w_);
  glfwSwapInterval(0);  // the simulation sets the pace, not the display
  gl::adopt_current_context("GLFW window");
  glfwSetWindowUserPointer(w_, input_.get());
  glfwSetMouseButtonCallback(w_, on_button);
  glfwSetCursorPosCallback(w_, on_move);
  glfwSetScrollCallback(w_, on_scroll);
  glfwSetKeyCallback(w_, on_key);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left behind
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(w_, true);  // chains to the callbacks above
  ImGui_ImplOpenGL3_Init("#version 430");
}

Window::~Window() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(w_);
  glfwTerminate();
}

bool Window::should_close() const { return glfwWindowShouldClose(w_); }
void Window::set_title(const std::string& title) { glfwSetWindowTitle(w_, title.c_str()); }

void Window::poll(int frame, std::vector<Event>& out) {
  input_->frame = frame;
  input_->out = &out;
  glfwPollEvents();
  input_->out = nullptr;
}

void Window::begin_panel() {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void Window::end_panel() {
  ImGui::Render();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, width(), height());
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void Window::swap() { glfwSwapBuffers(w_); }

int Window::width() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(w_, &w, &h);
  return w;
}

int Window::height() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(w_, &w, &h);
  return h;
}

}  // namespace deformlab::viewer
