// `deformlab calibrate`: this device's ceilings as JSON (see interop/calibrate.hpp).
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "experiments/output.hpp"
#if DEFORMLAB_HAVE_INTEROP
#include "interop/calibrate.hpp"
#endif

namespace deformlab::app {

nlohmann::json measure_calibration(const std::vector<std::string>& argv) {
#if DEFORMLAB_HAVE_INTEROP
  nlohmann::json j = interop::calibrate({}, std::cerr);
  j["command"] = argv;
  j["build"] = build_info();
  j["machine"] = machine_info();
  return j;
#else
  (void)argv;
  throw std::invalid_argument(
      "calibrate measures CUDA and OpenGL together; this build has "
#if DEFORMLAB_HAVE_CUDA
      "no OpenGL (configure with OpenGL, EGL and GLEW found)");
#elif DEFORMLAB_HAVE_GL
      "no CUDA (configure with a CUDA compiler found)");
#else
      "neither CUDA nor OpenGL");
#endif
#endif
}

int calibrate_command(const CalibrateArgs& a) {
  return report_errors([&] {
    if (a.out) require_file_target(*a.out, "--out");  // before the measurement, which takes seconds
    const nlohmann::json j = measure_calibration(a.argv);
    if (a.out) {
      write_atomically(*a.out, j.dump(2) + "\n");
      std::cerr << "  wrote " << *a.out << "\n";
    } else {
      std::cout << j.dump(2) << "\n";
    }
    return 0;
  });
}

}  // namespace deformlab::app
