// `deformlab view`: the scene in a window (viewer/).
#include <stdexcept>

#include "commands.hpp"
#include "run_input.hpp"
#if DEFORMLAB_HAVE_VIEWER
#include "core/scene.hpp"
#include "viewer/viewer.hpp"
#endif

namespace deformlab::app {

int view_command(const ViewArgs& a) {
  return report_errors([&]() -> int {
    if (a.steps_per_frame < 1) throw std::invalid_argument("--steps-per-frame must be at least 1");
    if (a.seconds && !a.record) throw std::invalid_argument("--seconds needs --record");
    if (a.seconds && !(*a.seconds > 0 && *a.seconds <= 3600)) throw std::invalid_argument("--seconds must be in (0, 3600]");
    if (a.max_frames && *a.max_frames < 1) throw std::invalid_argument("--max-frames must be at least 1");
    const std::vector<int> size = parse_size(a.size, 2, "--size");
    check_run_flags(a.run);
    if (size[0] > 16384 || size[1] > 16384) throw std::invalid_argument("--size: at most 16384x16384");
#if DEFORMLAB_HAVE_VIEWER
    viewer::ViewOptions o;
    o.steps_per_frame = a.steps_per_frame;
    if (a.script) o.script = viewer::read_script(*a.script);
    o.save_script = a.save_script.value_or("");
    o.record = a.record.value_or("");
    o.seconds = a.seconds.value_or(0.0);
    o.frames = a.max_frames.value_or(0);
    o.summary = a.summary.value_or("");
    viewer::Window w(size[0] + viewer::kPanelWidth, size[1], "deformlab view");
    RunInput in = read_run_input(a.run, Output::none);
    w.set_title("deformlab view: " + describe(in.x.scene.model));
    viewer::Session s({std::move(in.model), in.params, in.entry, in.integ, in.options});
    return viewer::run(w, s, o);
#else
    throw std::invalid_argument("view needs a build with OpenGL, GLFW and Dear ImGui");
#endif
  });
}

}  // namespace deformlab::app
