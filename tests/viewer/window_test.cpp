// `deformlab view` in a window under Xvfb (xvfb-run; skipped where it is not installed):
// scripted press-drag-release on a node, pipelines switched mid-run, a screenshot, a recording,
// and the refusals (no display, bad flags, a bad script).
#include <gtest/gtest.h>

#include <cstdlib>
#include <nlohmann/json.hpp>

#include "core/scene.hpp"
#include "gl/render.hpp"
#include "mesh/scene_model.hpp"
#include "tests/unit/cli_support.hpp"

#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

namespace deformlab::test {
namespace {

constexpr int kW = 640, kH = 480;  // the 3D view (--size); the panel adds its width
constexpr const char* kScene =
    R"({"model": {"type": "cloth", "size": [16, 16], "width": 1.0, "height": 1.0, "pins": "top-corners"},
        "dt": 0.002, "damping": 0.05})";

bool have(const char* tool) { return std::system((std::string("command -v ") + tool + " >/dev/null 2>&1").c_str()) == 0; }

class View : public Cli {
 protected:
  void SetUp() override {
    if (!have("xvfb-run")) GTEST_SKIP() << "xvfb-run is not installed (Debian: xvfb)";
    Cli::SetUp();
    scene_ = write("scene.json", kScene);
  }
  // The viewer under a fresh Xvfb server.
  Result view(const std::string& args) {
    return run_wrapped("xvfb-run -a -s '-screen 0 1600x1000x24' ",
                       "view --scene " + scene_.string() + " --size " + std::to_string(kW) + "x" + std::to_string(kH) +
                           " " + args);
  }
  Result run_wrapped(const std::string& prefix, const std::string& args) {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd = prefix + DEFORMLAB_EXE + " " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
  }
  nlohmann::json summary() { return nlohmann::json::parse(slurp(dir_ / "summary.json")); }
  // The model and first camera the viewer has for kScene.
  Model model() { return build_model(load_scene(scene_.string())); }
  gl::Camera camera() { return gl::framing(model(), std::nullopt); }
  fs::path scene_;
};

Vec3f vec(const nlohmann::json& j) { return {j[0].get<float>(), j[1].get<float>(), j[2].get<float>()}; }

TEST_F(View, DraggedNodeFollowsTheCursorRay) {
  const Model m = model();
  const gl::Camera c = camera();
  const int node = 8 * 16 + 8;
  const auto p = c.pixel(m.rest_position[node], kW, kH);
  nlohmann::json events = {{{"frame", 0}, {"event", "press"}, {"x", p[0]}, {"y", p[1]}, {"button", "left"}}};
  for (int k = 1; k <= 8; ++k)
    events.push_back({{"frame", k}, {"event", "move"}, {"x", p[0] + 8 * k}, {"y", p[1] - 10 * k}});
  events.push_back({{"frame", 14}, {"event", "release"}});
  const fs::path script = write("drag.json", nlohmann::json{{"events", events}}.dump());
  const Result r = view("--pipeline cpu --steps-per-frame 4 --max-frames 20 --script " + script.string() +
                        " --summary " + (dir_ / "summary.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json s = summary();
  ASSERT_EQ(s["drags"].size(), 1u) << s.dump();
  const nlohmann::json& d = s["drags"][0];
  EXPECT_EQ(d["node"], node);
  const Vec3f x = vec(d["position"]), o = vec(d["ray"]["origin"]), dir = vec(d["ray"]["direction"]);
  EXPECT_LT(norm(cross(x - o, dir)), 1e-5f) << "the hard handle holds the node on the cursor's ray";
  const auto at = c.pixel(x, kW, kH);
  EXPECT_NEAR(at[0], p[0] + 64, 0.5);
  EXPECT_NEAR(at[1], p[1] - 80, 0.5);
  EXPECT_GT(norm(x - m.rest_position[node]), 0.05f);
  EXPECT_GT(s["largest_move_m"].get<double>(), 0.05) << "the cloth moved";
  EXPECT_EQ(s["steps"], 80);
}

// A reset (backspace) during a drag ends the drag there; the moves and the release after it
// drag nothing (they had read node -1).
TEST_F(View, AResetEndsTheDrag) {
  const int node = 8 * 16 + 8;
  const auto p = camera().pixel(model().rest_position[node], kW, kH);
  const nlohmann::json events = {{{"frame", 0}, {"event", "press"}, {"x", p[0]}, {"y", p[1]}, {"button", "left"}},
                                 {{"frame", 1}, {"event", "move"}, {"x", p[0] + 8}, {"y", p[1] - 10}},
                                 {{"frame", 3}, {"event", "key"}, {"key", "backspace"}},
                                 {{"frame", 4}, {"event", "move"}, {"x", p[0] + 16}, {"y", p[1] - 20}},
                                 {{"frame", 5}, {"event", "release"}}};
  const fs::path script = write("reset.json", nlohmann::json{{"events", events}}.dump());
  const Result r = view("--pipeline cpu --max-frames 8 --script " + script.string() + " --summary " +
                        (dir_ / "summary.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json s = summary();
  ASSERT_EQ(s["drags"].size(), 1u) << s.dump();
  EXPECT_EQ(s["drags"][0]["frame"], 3);
  EXPECT_EQ(s["drags"][0]["node"], node);
}

// A screenshot that cannot be written is said on stderr and in the summary, and the session
// exits 1; the summary is still written. (Its file is a link to /dev/full, which passes the check
// before the window, a device being written as it is, and refuses the write.)
TEST_F(View, AScreenshotThatCannotBeWrittenEndsInExit1) {
  const fs::path full = dir_ / "full.png";
  fs::create_symlink("/dev/full", full);
  const fs::path script = write("shot.json", R"({"events": [{"frame": 1, "event": "screenshot", "file": ")" +
                                                  full.string() + R"("}, {"frame": 2, "event": "quit"}]})");
  const Result r = view("--pipeline cpu --script " + script.string() + " --summary " + (dir_ / "summary.json").string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("deformlab: error: cannot write " + full.string() + ": "), std::string::npos) << r.err;
  EXPECT_EQ(summary()["screenshots"][0]["written"], false);
}

TEST_F(View, SavedSessionReplaysToTheSameState) {
  const Model m = model();
  const auto p = camera().pixel(m.rest_position[5 * 16 + 10], kW, kH);
  nlohmann::json events = {{{"frame", 1}, {"event", "press"}, {"x", p[0]}, {"y", p[1]}, {"button", "left"}},
                           {{"frame", 4}, {"event", "move"}, {"x", p[0] - 30}, {"y", p[1] - 40}},
                           {{"frame", 9}, {"event", "release"}},
                           {{"frame", 10}, {"event", "set"}, {"dt", "0.001"}},
                           {{"frame", 11}, {"event", "key"}, {"key", "space"}},
                           {{"frame", 13}, {"event", "key"}, {"key", "space"}}};
  const fs::path script = write("live.json", nlohmann::json{{"events", events}}.dump());
  const fs::path saved = dir_ / "saved.json", first = dir_ / "first.json", second = dir_ / "summary.json";
  const std::string common = "--pipeline omp --steps-per-frame 3 --max-frames 16 ";
  ASSERT_EQ(view(common + "--script " + script.string() + " --save-script " + saved.string() + " --summary " +
                 first.string()).code, 0);
  ASSERT_EQ(view(common + "--script " + saved.string() + " --summary " + second.string()).code, 0);
  const nlohmann::json a = nlohmann::json::parse(slurp(first)), b = summary();
  ASSERT_EQ(a["drags"].size(), 1u) << a.dump();
  EXPECT_EQ(a["drags"], b["drags"]);
  EXPECT_EQ(a["largest_move_m"], b["largest_move_m"]) << "the same steps from the same input";
  EXPECT_EQ(b["dt"], 0.001) << "the float dt as the decimal given";
  EXPECT_EQ(b["steps"], (16 - 2) * 3) << "two frames paused";
}

TEST_F(View, SwitchedPipelinesCarryTheStateOverExactly) {
  nlohmann::json events = {{{"frame", 3}, {"event", "set"}, {"pipeline", "omp"}},
                           {{"frame", 6}, {"event", "set"}, {"pipeline", "glsl-compute"}, {"integrator", "verlet"}},
                           {{"frame", 9}, {"event", "set"}, {"options", "bogus=1"}}};
  const fs::path script = write("switch.json", nlohmann::json{{"events", events}}.dump());
  const Result r = view("--pipeline cpu --max-frames 12 --script " + script.string() + " --summary " +
                        (dir_ / "summary.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json s = summary();
  ASSERT_EQ(s["replacements"].size(), 3u) << s.dump();
  EXPECT_EQ(s["replacements"][0]["to"], "omp");
  EXPECT_EQ(s["replacements"][0]["carried_exactly"], true);
  EXPECT_EQ(s["replacements"][1]["to"], "glsl-compute");
  EXPECT_EQ(s["replacements"][1]["carried_exactly"], true);
  EXPECT_EQ(s["replacements"][2]["to"], "glsl-compute") << "an option it does not take leaves it";
  EXPECT_NE(s["replacements"][2]["error"].get<std::string>().find("bogus"), std::string::npos) << s["replacements"][2];
  EXPECT_EQ(s["pipeline"], "glsl-compute");
  EXPECT_EQ(s["integrator"], "verlet");
  EXPECT_EQ(s["steps"], 120);
}

TEST_F(View, ScreenshotShowsTheClothWhereTheCameraSaysItIs) {
  const fs::path png = dir_ / "shot.png";
  const nlohmann::json events = {{{"frame", 0}, {"event", "screenshot"}, {"file", png.string()}}};
  const fs::path script = write("shot.json", nlohmann::json{{"events", events}}.dump());
  const Result r = view("--pipeline cpu --steps-per-frame 1 --max-frames 2 --script " + script.string());
  ASSERT_EQ(r.code, 0) << r.err;
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load(png.string().c_str(), &w, &h, &n, 4);
  ASSERT_NE(px, nullptr);
  EXPECT_GT(w, kW);  // the view and the panel
  EXPECT_EQ(h, kH);
  auto at = [&](double x, double y) {
    const unsigned char* q = px + (std::size_t(y) * w + std::size_t(x)) * 4;
    return std::array<int, 3>{q[0], q[1], q[2]};
  };
  const Model m = model();
  const gl::Camera c = camera();
  for (int node : {8 * 16 + 8, 4 * 16 + 11, 12 * 16 + 3}) {
    const auto p = c.pixel(m.rest_position[node], kW, kH);
    const auto rgb = at(p[0], p[1]);
    EXPECT_TRUE(rgb[0] > 80 && rgb[0] > rgb[1] && rgb[1] > rgb[2]) << "the cloth's orange at node " << node << " at " << p[0] << ","
                                                                     << p[1] << ": " << rgb[0] << " " << rgb[1] << " "
                                                                     << rgb[2];
  }
  const auto bg = at(5, 5);
  EXPECT_TRUE(bg[0] < 60 && bg[2] >= bg[0]) << "background in the corner: " << bg[0] << " " << bg[1] << " " << bg[2];
  stbi_image_free(px);
}

TEST_F(View, RecordsAPlayableMp4OfTheFramesAsked) {
  if (!have("ffprobe")) GTEST_SKIP() << "ffmpeg is not installed";
  const fs::path mp4 = dir_ / "run.mp4";
  const Result r = view("--pipeline cpu --steps-per-frame 2 --record " + mp4.string() + " --seconds 1");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string cmd = "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames,codec_name "
                          "-of csv=p=0 " + mp4.string() + " > " + (dir_ / "probe.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(slurp(dir_ / "probe.txt"), "h264,30\n");
  for (const auto& f : fs::directory_iterator(dir_))
    EXPECT_EQ(f.path().filename().string().find(".partial"), std::string::npos) << "left behind: " << f.path();
}

TEST_F(View, KeysTakeScreenshotsAndRecordingsIntoTheWorkingFolder) {
  if (!have("ffprobe")) GTEST_SKIP() << "ffmpeg is not installed";
  const nlohmann::json events = {{{"frame", 1}, {"event", "key"}, {"key", "p"}},
                                 {{"frame", 2}, {"event", "key"}, {"key", "v"}},
                                 {{"frame", 12}, {"event", "key"}, {"key", "v"}}};
  const fs::path script = write("keys.json", nlohmann::json{{"events", events}}.dump());
  const Result r = run_wrapped("cd " + dir_.string() + " && xvfb-run -a -s '-screen 0 1600x1000x24' ",
                               "view --scene " + scene_.string() + " --pipeline cpu --max-frames 15 --script " +
                                   script.string() + " --summary " + (dir_ / "summary.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "deformlab-view-1.png"));
  const nlohmann::json s = summary();
  ASSERT_EQ(s["recordings"].size(), 1u) << s.dump();
  EXPECT_EQ(s["recordings"][0]["frames"], 10) << "frames 2 to 11";
  const std::string cmd = "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames "
                          "-of csv=p=0 " + (dir_ / "deformlab-view-2.mp4").string() + " > " + (dir_ / "probe.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(slurp(dir_ / "probe.txt"), "10\n");
}

TEST_F(View, RefusesBadInputWithOneLine) {
  const fs::path bad = write("bad.json", R"({"events": [{"frame": 1, "event": "teleport"}]})");
  const fs::path shot = write("shot.json", nlohmann::json{{"events", {{{"frame", 1}, {"event", "screenshot"},
                                                                       {"file", (bad / "x.png").string()}}}}}.dump());
  const std::string same = (dir_ / "same.json").string();
  for (const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
           {"--steps-per-frame 0", "--steps-per-frame"},
           {"--summary " + (bad / "s.json").string(), "--summary '" + (bad / "s.json").string() + "': '" + bad.string() +
                                                           "' is not a folder"},
           {"--summary " + same + " --save-script " + same, "--save-script '" + same + "' is a file another flag names too"},
           {"--script " + bad.string() + " --summary " + bad.string(), "is a file another flag names too"},
           {"--summary ''", "--summary: an empty file name"},
           {"--script " + shot.string(), "screenshot '" + (bad / "x.png").string() + "': '" + bad.string() + "' is not a folder"},
           {"--seconds 2", "--seconds needs --record"},
           {"--size 640", "--size"},
           {"--script " + bad.string(), "unknown event 'teleport'"},
           {"--pipeline nope", "unknown pipeline"}}) {
    const Result r = view(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("deformlab: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
  }
}

// SIGTERM (as SIGINT, which a background job ignores) ends a session as closing its window
// does: its recording and summary are written, exit 0. The signal comes once the session draws
// (its scripted screenshot is there), however long a busy machine takes to start it.
TEST_F(View, SigtermEndsTheSessionWithItsFiles) {
  if (!have("ffmpeg")) GTEST_SKIP() << "ffmpeg is not installed";
  const fs::path movie = dir_ / "session.mp4", shot = dir_ / "drawn.png";
  const fs::path script = write("shot.json", nlohmann::json{{"events", {{{"frame", 2}, {"event", "screenshot"},
                                                                         {"file", shot.string()}}}}}.dump());
  const fs::path sh = write("signal.sh", "\"$@\" & pid=$!\n"
                                         "for i in $(seq 600); do [ -f '" + shot.string() + "' ] && break; sleep 0.1; done\n"
                                         "kill -TERM $pid; wait $pid\n");
  const Result r = run_wrapped("xvfb-run -a -s '-screen 0 1600x1000x24' sh " + sh.string() + " ",
                               "view --scene " + scene_.string() + " --size 320x240 --script " + script.string() +
                                   " --record " + movie.string() + " --summary " + (dir_ / "summary.json").string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("deformlab: note: SIGTERM at frame "), std::string::npos) << r.err;
  EXPECT_GT(summary()["frames"].get<int>(), 0);
  ASSERT_EQ(summary()["recordings"].size(), 1u) << summary().dump();
  EXPECT_GT(fs::file_size(movie), 0u);
}

// With no display: stderr of `deformlab view ARGS`, which must exit 2 with one line.
std::string view_without_display(const std::string& args) {
  const fs::path file = fs::temp_directory_path() / ("deformlab-nodisplay-" + std::to_string(::getpid()) + ".txt");
  const std::string cmd =
      std::string("env -u DISPLAY -u WAYLAND_DISPLAY ") + DEFORMLAB_EXE + " view " + args + " 2>" + file.string();
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2) << args;
  std::ifstream in(file);
  const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(file);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  return err;
}

TEST(ViewWithoutDisplay, SaysSoInOneLineAndExits2) {
  const std::string err = view_without_display("--grid 8x8");
  EXPECT_NE(err.find("view needs a display"), std::string::npos) << err;
  EXPECT_NE(err.find("run --frames"), std::string::npos) << err;
  // A bad flag is named first, before any window is asked for.
  EXPECT_NE(view_without_display("--grid 0x5").find("--grid '0x5'"), std::string::npos);
}

}  // namespace
}  // namespace deformlab::test
