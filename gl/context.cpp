#include "context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <link.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "deformlab_shaders.hpp"

namespace deformlab::gl {
namespace {

ContextOptions g_options;

std::string egl_error(const char* what) {
  std::ostringstream os;
  os << what << " failed (EGL error 0x" << std::hex << eglGetError() << ")";
  return os.str();
}

template <class F>
F egl_proc(const char* name) {
  return reinterpret_cast<F>(eglGetProcAddress(name));
}

bool has_extension(const char* list, std::string_view ext) {
  if (!list) return false;
  const std::string_view all(list);
  for (std::size_t p = all.find(ext); p != std::string_view::npos; p = all.find(ext, p + 1)) {
    const bool start = p == 0 || all[p - 1] == ' ';
    const bool stop = p + ext.size() == all.size() || all[p + ext.size()] == ' ';
    if (start && stop) return true;
  }
  return false;
}

// Keeps every library loaded so far (the GL driver among them) until the process exits:
// eglTerminate unloads the driver, after which LeakSanitizer, which reads the process at exit,
// cannot name the frames of the blocks the driver keeps for the process's life (Mesa's
// llvmpipe keeps two of 56 bytes), and so no suppression could match them.
void pin_loaded_libraries() {
  std::vector<std::string> names;
  dl_iterate_phdr(
      [](dl_phdr_info* i, std::size_t, void* out) {
        if (i->dlpi_name && *i->dlpi_name) static_cast<std::vector<std::string>*>(out)->push_back(i->dlpi_name);
        return 0;
      },
      &names);
  for (const std::string& n : names) dlopen(n.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
}

const char* debug_stage = "setup";

void GLAPIENTRY on_debug(GLenum, GLenum type, GLuint, GLenum severity, GLsizei, const GLchar* msg, const void*) {
  if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
  std::cerr << "GL debug [" << debug_stage << "]" << (type == GL_DEBUG_TYPE_ERROR ? " error: " : ": ") << msg << "\n";
}

class Context {
 public:
  // The headless context: made here, current without a surface.
  Context() {
    display_ = open_display();
    if (!eglBindAPI(EGL_OPENGL_API)) fail(egl_error("eglBindAPI(EGL_OPENGL_API)"));
    EGLConfig config = EGL_NO_CONFIG_KHR;
    const EGLint cfg_attr[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint count = 0;
    if (!eglChooseConfig(display_, cfg_attr, &config, 1, &count) || count == 0) {
      if (!has_extension(eglQueryString(display_, EGL_EXTENSIONS), "EGL_KHR_no_config_context"))
        fail("the EGL display offers no OpenGL config");
      config = EGL_NO_CONFIG_KHR;
    }
    info_.debug = g_options.debug;
    if (const char* e = std::getenv("DEFORMLAB_GL_DEBUG"); e && std::string_view(e) == "1") info_.debug = true;
    // The newest core version first (NVIDIA gives exactly the version asked for), 4.3 last.
    for (const EGLint minor : {6, 5, 3}) {
      const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, minor,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_CONTEXT_OPENGL_DEBUG, info_.debug ? EGL_TRUE : EGL_FALSE, EGL_NONE};
      context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, ctx_attr);
      if (context_ != EGL_NO_CONTEXT) break;
    }
    if (context_ == EGL_NO_CONTEXT)
      fail(egl_error("creating an OpenGL 4.3 core context") + " on " + info_.platform +
           ": the driver may be too old for OpenGL 4.3");
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      fail(egl_error("eglMakeCurrent without a surface"));
    pin_loaded_libraries();
    load_gl();
    // A surfaceless context has no default framebuffer; every draw (transform feedback with
    // the rasteriser discarded too) needs a complete framebuffer bound.
    glGenFramebuffers(1, &fbo_);
    glGenRenderbuffers(1, &rbo_);
    glBindRenderbuffer(GL_RENDERBUFFER, rbo_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 1, 1);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rbo_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("the 1x1 framebuffer is incomplete");
    glViewport(0, 0, 1, 1);
    check("context setup");
  }

  // A window's context, made current on this thread by its window system, which keeps it.
  explicit Context(const std::string& platform) {
    info_.platform = platform;
    pin_loaded_libraries();
    load_gl();
    check("context setup");
  }

  ~Context() {
    if (context_ == EGL_NO_CONTEXT) return;
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }

  const ContextInfo& info() const { return info_; }
  void make_current() const {
    if (context_ != EGL_NO_CONTEXT && eglGetCurrentContext() != context_ &&
        !eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw std::runtime_error(egl_error("eglMakeCurrent"));
  }

 private:
  // The entry points and facts of the current context.
  void load_gl() {
    // Debian's GLEW is built for GLX: under EGL glewInit loads every entry point and then
    // reports GLEW_ERROR_NO_GLX_DISPLAY, which is success here.
    glewExperimental = GL_TRUE;
    const GLenum g = glewInit();
    if (g != GLEW_OK && g != GLEW_ERROR_NO_GLX_DISPLAY)
      fail(std::string("glewInit: ") + reinterpret_cast<const char*>(glewGetErrorString(g)));
    while (glGetError() != GL_NO_ERROR) {
    }
    auto str = [](GLenum e) {
      const GLubyte* s = glGetString(e);
      return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
    };
    info_.vendor = str(GL_VENDOR);
    info_.renderer = str(GL_RENDERER);
    info_.version = str(GL_VERSION);
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 43) fail("OpenGL " + info_.version + " is older than the 4.3 core this needs");
    info_.software = info_.renderer.find("llvmpipe") != std::string::npos ||
                     info_.renderer.find("softpipe") != std::string::npos ||
                     info_.renderer.find("SwiftShader") != std::string::npos;
    if (info_.debug && glDebugMessageCallback) {
      glEnable(GL_DEBUG_OUTPUT);
      glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
      glDebugMessageCallback(on_debug, nullptr);
    }
  }

  [[noreturn]] void fail(const std::string& why) {
    if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
    if (display_ != EGL_NO_DISPLAY) eglTerminate(display_);
    context_ = EGL_NO_CONTEXT;
    throw std::invalid_argument("OpenGL unavailable: " + why);
  }

  // The EGL device platform (a GPU with EGL_NV_device_cuda first, or --gl-device N), then
  // Mesa's surfaceless platform, then the default display.
  EGLDisplay open_display() {
    std::string tried;
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    auto get_platform_display = egl_proc<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT");
    auto query_devices = egl_proc<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
    auto query_device_string = egl_proc<PFNEGLQUERYDEVICESTRINGEXTPROC>("eglQueryDeviceStringEXT");
    EGLint n = 0;
    std::vector<EGLDeviceEXT> devices;
    if (get_platform_display && query_devices && has_extension(client, "EGL_EXT_platform_device") &&
        query_devices(0, nullptr, &n) && n > 0) {
      devices.resize(n);
      query_devices(n, devices.data(), &n);
    }
    if (g_options.device >= int(devices.size()))
      fail("--gl-device " + std::to_string(g_options.device) + " does not exist: EGL lists " +
           std::to_string(devices.size()) + " device(s)");
    int pick = g_options.device;
    for (int d = 0; pick < 0 && d < int(devices.size()); ++d)
      if (has_extension(query_device_string(devices[d], EGL_EXTENSIONS), "EGL_NV_device_cuda")) pick = d;
    if (pick < 0 && !devices.empty()) pick = 0;
    if (pick >= 0) {
      EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[pick], nullptr);
      if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
        info_.platform = "EGL device " + std::to_string(pick) + " of " + std::to_string(devices.size());
        return d;
      }
      if (g_options.device >= 0) fail(egl_error(("opening EGL device " + std::to_string(pick)).c_str()));
      tried += egl_error("EGL device platform") + "; ";
    } else {
      tried += "no EGL devices listed; ";
    }
    if (get_platform_display && has_extension(client, "EGL_MESA_platform_surfaceless")) {
      EGLDisplay d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
        info_.platform = "Mesa surfaceless platform";
        return d;
      }
      tried += egl_error("Mesa surfaceless platform") + "; ";
    }
    EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
      info_.platform = "default EGL display";
      return d;
    }
    tried += egl_error("default display");
    fail("no EGL display (" + tried + "); is an OpenGL driver with EGL installed?");
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  GLuint fbo_ = 0, rbo_ = 0;
  ContextInfo info_;
};

struct Holder {
  std::unique_ptr<Context> ctx;
  std::string error;  // set once creation failed: later calls fail the same way
};

Holder& holder() {
  static Holder h;
  return h;
}

}  // namespace

void configure(const ContextOptions& o) {
  if (holder().ctx && (o.device != g_options.device || o.debug != g_options.debug))
    throw std::invalid_argument("the OpenGL context already exists with other options");
  if (o.device < -1) throw std::invalid_argument("--gl-device must be >= 0");
  g_options = o;
}

const ContextInfo& context() {
  Holder& h = holder();
  if (!h.ctx) {
    if (!h.error.empty()) throw std::invalid_argument(h.error);
    try {
      h.ctx = std::make_unique<Context>();
    } catch (const std::invalid_argument& e) {
      h.error = e.what();
      throw;
    }
  }
  h.ctx->make_current();
  return h.ctx->info();
}

std::string unavailable_reason() {
  try {
    context();
    return {};
  } catch (const std::exception& e) {
    return e.what();
  }
}

void adopt_current_context(const std::string& platform) {
  Holder& h = holder();
  if (h.ctx) throw std::logic_error("an OpenGL context is already in use");
  h.ctx = std::make_unique<Context>(platform);
}

bool context_created() { return bool(holder().ctx); }

void check(std::string_view stage) {
  std::string errors;
  for (GLenum e = glGetError(); e != GL_NO_ERROR; e = glGetError()) {
    std::ostringstream os;
    os << (errors.empty() ? "" : ", ") << "0x" << std::hex << e;
    errors += os.str();
    if (errors.size() > 200) break;
  }
  if (!errors.empty()) throw std::runtime_error("OpenGL error in " + std::string(stage) + ": " + errors);
}

void check_debug(std::string_view stage) {
  if (!holder().ctx || !holder().ctx->info().debug) return;
  static std::string name;
  name = stage;
  debug_stage = name.c_str();
  check(stage);
}

std::string shader_file(std::string_view name) {
  if (const char* dir = std::getenv("DEFORMLAB_SHADER_DIR"); dir && *dir) {
    std::ifstream in(std::string(dir) + "/" + std::string(name));
    if (in) {
      std::stringstream ss;
      ss << in.rdbuf();
      return ss.str();
    }
  }
  if (auto s = shaders::find(name)) return std::string(*s);
  throw std::logic_error("no shader file named " + std::string(name));
}

Timer::Timer() : software_(context().software) {}

Timer::~Timer() {
  if (!free_.empty()) glDeleteQueries(GLsizei(free_.size()), free_.data());
  if (!pending_.empty()) glDeleteQueries(GLsizei(pending_.size()), pending_.data());
}

void Timer::stamp() {
  if (free_.empty()) {
    free_.resize(32);
    glGenQueries(32, free_.data());
  }
  const GLuint q = free_.back();
  free_.pop_back();
  glQueryCounter(q, GL_TIMESTAMP);
  pending_.push_back(q);
}

void Timer::begin() {
  if (software_) {
    glFinish();
    t0_ = std::chrono::steady_clock::now();
    return;
  }
  if (pending_.size() >= 4096) collect(64);  // the older half is long finished
  stamp();
}

void Timer::end() {
  if (software_) {
    glFinish();
    done_.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count());
    return;
  }
  stamp();
}

void Timer::collect(std::size_t keep) {
  std::size_t k = 0;
  for (; k + keep + 1 < pending_.size(); k += 2) {
    GLuint64 t[2] = {};
    glGetQueryObjectui64v(pending_[k], GL_QUERY_RESULT, &t[0]);
    glGetQueryObjectui64v(pending_[k + 1], GL_QUERY_RESULT, &t[1]);
    done_.push_back(double(t[1] - t[0]) * 1e-6);
    free_.push_back(pending_[k]);
    free_.push_back(pending_[k + 1]);
  }
  pending_.erase(pending_.begin(), pending_.begin() + long(k));
}

std::vector<double> Timer::take() {
  collect(0);
  return std::exchange(done_, {});
}

std::string Timer::method() const {
  return software_ ? "host clock after glFinish, as software OpenGL's timer queries mean nothing"
                   : "GL timer queries";
}

void TimerSpans::begin(const Profiler& p, const char* name) {
  if (!timer_) timer_ = std::make_unique<Timer>();
  pending_.push_back({name, p.step(), p.now_ms()});
  range_.emplace(name);
  timer_->begin();
}

void TimerSpans::end() {
  timer_->end();
  range_.reset();
}

void TimerSpans::collect(Profiler* p) {
  if (pending_.empty()) return;
  const std::vector<double> ms = timer_->take();
  for (std::size_t k = 0; k < pending_.size() && k < ms.size(); ++k)
    if (p) p->add({pending_[k].name, pending_[k].step, pending_[k].start_ms, ms[k], timer_->method()});
  pending_.clear();
}

std::string TimerSpans::method() const { return timer_ ? timer_->method() : Timer().method(); }

}  // namespace deformlab::gl
