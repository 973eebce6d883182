// `deformlab calibrate`: this device's ceilings as JSON (see interop/calibrate.hpp).
#include <iostream>

#include "commands.hpp"
#include "experiments/output.hpp"
#if DEFORMLAB_HAVE_INTEROP
#include "interop/calibrate.hpp"
#endif

namespace deformlab::app {

int calibrate_command(const CalibrateArgs& a) {
#if DEFORMLAB_HAVE_INTEROP
  return report_errors([&] {
    nlohmann::json j = interop::calibrate({}, std::cerr);
    j["command"] = a.argv;
    j["build"] = build_info();
    j["machine"] = machine_info();
    if (a.out) {
      write_json(*a.out, j);
      std::cerr << "  wrote " << *a.out << "\n";
    } else {
      std::cout << j.dump(2) << "\n";
    }
    return 0;
  });
#else
  (void)a;
  std::cerr << "deformlab: error: calibrate measures CUDA and OpenGL together; this build has "
#if DEFORMLAB_HAVE_CUDA
               "no OpenGL (configure with OpenGL, EGL and GLEW found)\n";
#elif DEFORMLAB_HAVE_GL
               "no CUDA (configure with a CUDA compiler found)\n";
#else
               "neither CUDA nor OpenGL\n";
#endif
  return 2;
#endif
}

}  // namespace deformlab::app
