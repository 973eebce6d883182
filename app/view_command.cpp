// `deformlab view`: the scene in a window (viewer/).
#include <filesystem>
#include <set>
#include <stdexcept>
#include <utility>

#include "commands.hpp"
#include "experiments/output.hpp"
#include "run_input.hpp"
#if DEFORMLAB_HAVE_VIEWER
#include "core/scene.hpp"
#include "viewer/viewer.hpp"
#endif

namespace deformlab::app {
int view_command(const ViewArgs& a) {
  return report_errors([&]() -> int {
    // A frame's steps run between the window's events (and signals): the panel goes to 200.
    if (a.steps_per_frame < 1 || a.steps_per_frame > 10000) throw std::invalid_argument("--steps-per-frame must be in 1 to 10000");
    if (a.seconds && !a.record) throw std::invalid_argument("--seconds needs --record");
    if (a.seconds && !(*a.seconds > 0 && *a.seconds <= 3600)) throw std::invalid_argument("--seconds must be in (0, 3600]");
    if (a.max_frames && *a.max_frames < 1) throw std::invalid_argument("--max-frames must be at least 1");
    const std::vector<int> size = parse_size(a.size, 2, "--size");
    check_run_flags(a.run);
    if (size[0] > 16384 || size[1] > 16384) throw std::invalid_argument("--size: at most 16384x16384");
    if (a.record && size[1] < 2) throw std::invalid_argument("--record needs a window 2 pixels high or more (H.264 in yuv420p)");
    // Each file the session reads or writes is one flag's (or one screenshot's).
    std::set<std::string> files;
    auto own = [&](const std::string& file, const std::string& what) {
      if (!files.insert(std::filesystem::absolute(file).lexically_normal().string()).second)
        throw std::invalid_argument(what + " '" + file + "' is a file another flag names too");
    };
    if (a.script) own(*a.script, "--script");
    for (const auto& [flag, file] : {std::pair{"--summary", a.summary}, {"--save-script", a.save_script}, {"--record", a.record}}) {
      if (!file) continue;
      require_file_target(*file, flag);
      own(*file, flag);
    }
    if (a.record && std::filesystem::path(*a.record).extension() != ".mp4")
      throw std::invalid_argument("--record '" + *a.record + "': expected a file name ending in .mp4 (the recording is "
                                  "H.264 in an MP4 file)");
#if DEFORMLAB_HAVE_VIEWER
    viewer::ViewOptions o;
    o.steps_per_frame = a.steps_per_frame;
    if (a.script) o.script = viewer::read_script(*a.script);
    for (const viewer::Event& e : o.script)
      if (e.kind == viewer::Event::Kind::screenshot) {
        require_file_target(e.file, "script " + *a.script + ": screenshot");
        own(e.file, "script " + *a.script + ": screenshot");
      }
    o.save_script = a.save_script.value_or("");
    o.record = a.record.value_or("");
    o.seconds = a.seconds.value_or(0.0);
    o.frames = a.max_frames.value_or(0);
    o.summary = a.summary.value_or("");
    RunInput in = read_run_model(a.run);
    viewer::Window w(size[0] + viewer::kPanelWidth, size[1], "deformlab view");
    resolve_pipeline(a.run, in);
    w.set_title("deformlab view: " + describe(in.x.scene.model));
    viewer::Session s({std::move(in.model), in.params, in.entry, in.integ, in.options});
    return viewer::run(w, s, o);
#else
    throw std::invalid_argument("view needs a build with OpenGL, GLFW and Dear ImGui");
#endif
  });
}

}  // namespace deformlab::app
