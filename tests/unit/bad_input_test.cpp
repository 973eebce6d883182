// Every kind of bad input, one row each: flags, scene files (malformed, out of range, not a
// file), experiment and calibration files. Each must exit 2 with one line naming the flag or
// the file and key path, write nothing and leave an existing output folder as it was.
// In the arguments and the files, {dir} is the test's folder; the files of a row are written
// there first, and must be there as they were after the command.
#include <set>
#include <vector>

#include "cli_support.hpp"

namespace deformlab::test {
namespace {

struct BadInput {
  const char* name;
  std::string args;
  std::string needle;
  std::vector<std::pair<std::string, std::string>> files = {};
};

// A scene file s.json holding `json`, run on cpu: its error names the key path `key`.
BadInput scene(const char* name, const std::string& json, const std::string& key) {
  return {name, "run --pipeline cpu --steps 3 --scene {dir}/s.json", key, {{"s.json", json}}};
}

// A scene with a mesh model (`model` holds its other keys; pins none unless it gives them)
// beside a mesh file `name` holding `text` (an open triangle unless given).
BadInput mesh(const char* name, const std::string& model, const std::string& key,
              const std::string& text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", const std::string& file = "m.obj") {
  const bool pins = model.find("\"pins\"") != std::string::npos;  // else none: a JSON key is given once
  const std::string scene =
      "{\"model\": {\"type\": \"mesh\", " + std::string(pins ? "" : "\"pins\": \"none\", ") + model.substr(1) + "}";
  return {name, "run --pipeline cpu --steps 3 --scene {dir}/s.json", key, {{"s.json", scene}, {file, text}}};
}

// `s`, n times over.
std::string repeated(const std::string& s, int n) {
  std::string out;
  for (int k = 0; k < n; ++k) out += s;
  return out;
}

// A scene whose mesh model is generated from `generate` (its JSON, which may go on with more keys of the model).
std::string G(const std::string& generate) {
  return "{\"model\": {\"type\": \"mesh\", \"pins\": \"none\", \"generate\": " + generate + "}}";
}

// A binary PLY header of x, y and z vertices and faces, up to its face property's type.
std::string ply_header(const std::string& vertices, const std::string& faces) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + vertices +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + faces + "\nproperty ";
}

const std::vector<BadInput>& cases() {
  static const std::vector<BadInput> all = {
      // flags
      {"unknown_pipeline", "run --pipeline warp", "unknown pipeline 'warp' (valid: best, "},
      {"sweep_cell_limit_tiny", "experiment {dir}/x.json", "x.json.sweep.cell_limit_s: expected a number of seconds from 0.01 to 1e6",
       {{"x.json", R"({"base": "quick", "sweep": {"sizes": [8], "pipelines": ["cpu"], "cell_limit_s": 1e-300}})"}}},
      {"experiment_unknown_pipeline", "experiment {dir}/x.json", "x.json.pipeline: unknown pipeline 'warp' (valid: best, ",
       {{"x.json", R"({"base": "quick", "pipeline": "warp"})"}}},
      {"unknown_integrator", "run --integrator leapfrog", "unknown integrator 'leapfrog' (valid: explicit-euler, "},
      {"grid_zero", "run --grid 0x5", "--grid '0x5'"},
      {"grid_negative", "run --grid -3x4", "--grid"},
      {"grid_letters", "run --grid abcx4", "--grid 'abcx4'"},
      {"grid_one_number", "run --grid 5", "expected WxH"},
      {"grid_trailing_x", "run --grid 5x", "expected WxH"},
      {"lattice_two_numbers", "run --lattice 2x2", "expected WxHxD"},
      {"lattice_zero", "run --lattice 0x2x2", "--lattice"},
      {"dt_zero", "run --dt 0", "--dt must be a positive"},
      {"dt_negative", "run --dt -1", "--dt"},
      {"dt_nan", "run --dt nan", "--dt"},
      {"dt_inf", "run --dt inf", "--dt"},
      {"dt_letters", "run --dt abc", "--dt"},
      {"dt_subnormal", "run --dt 1e-45", "--dt must be a positive number of seconds from 1.18e-38"},
      {"steps_zero", "run --steps 0", "--steps"},
      {"steps_negative", "run --steps -5", "--steps"},
      {"steps_letters", "run --steps abc", "--steps"},
      {"dt_hexadecimal", "run --dt 0x10", "--dt: '0x10' is not a decimal number"},
      {"gl_device_word", "run --gl-device abc", "--gl-device: 'abc' is not a whole decimal number"},
      {"gl_device_range", "run --gl-device 2000", "--gl-device: '2000' is not in 0 to 1023"},
      {"grid_twice", "run --grid 8x8 --grid 9x9", "--grid is given 2 times; it takes one value (see deformlab run --help)"},
      {"unknown_command", "runn --grid 4x4", "unknown command 'runn' (valid: run, experiment, list, view, calibrate, mesh)"},
      {"steps_past_int", "run --steps 99999999999",
       "--steps: '99999999999' is more than 2147483647, the most a whole-number option takes (see deformlab run --help)"},
      {"steps_zero_padded", "run --steps +0000000000000", "--steps must be at least 1"},
      {"steps_hexadecimal", "run --steps 0x10", "--steps: '0x10' is not a whole decimal number"},
      {"steps_exponent", "run --steps 1e3", "--steps: '1e3' is not a whole decimal number"},
      {"max_size_hexadecimal", "experiment table2 --max-size 0x40", "--max-size: '0x40' is not a whole decimal number"},
      {"steps_over_memory", "run --pipeline cpu --grid 4x4 --steps 2147483647", "2147483647 steps keep 192 GiB of step records"},
      {"warmup_negative", "run --warmup-ms -1", "--warmup-ms must be between 0"},
      {"warmup_nan", "run --warmup-ms nan", "--warmup-ms must be between 0"},
      {"warmup_letters", "run --warmup-ms abc", "--warmup-ms"},
      {"threshold_zero", "run --pipeline cpu --threshold 0", "threshold"},
      {"threshold_inf", "run --pipeline cpu --threshold inf", "--threshold must be a positive number of metres from 1.18e-38"},
      {"threshold_subnormal", "run --pipeline cpu --threshold 1e-40", "--threshold must be a positive number of metres from 1.18e-38"},
      {"threshold_without_convergence", "run --pipeline cpu --steps 5 --threshold 0.01",
       "--threshold applies to a run until converged (--until-converged); this one takes a fixed number of steps"},
      {"steps_under_min_steps", "run --pipeline cpu --until-converged --steps 50 --scene {dir}/s.json",
       "--steps 50 with --until-converged: the stop rule starts at step 100 (min_steps), so give at least that many",
       {{"s.json", "{\"model\": {\"size\": [4, 4]}}"}}},
      {"steps_before_the_drag_ends", "run --pipeline cpu --until-converged --steps 500",
       "--steps 500 with --until-converged: the stop rule starts at step 1000 (min_steps and the drag path's end at t = 2 s)"},
      {"check_every_zero", "run --pipeline cpu --check-every 0", "--check-every must be at least 1"},
      {"compare_unknown", "run --compare gpu", "--compare"},
      {"compare_itself", "run --pipeline reference --compare reference",
       "--compare reference: the pipeline run is 'reference' itself"},
      {"compare_float_cpu", "run --compare cpu", "--compare 'cpu': the only pipeline to compare with is 'reference'"},
      {"option_not_read", "run --pipeline cpu --option tile=8x8", "option 'tile' is not an option of cpu (it has none)"},
      {"option_no_value", "run --option tile", "expected NAME=VALUE"},
      {"option_twice", "run --pipeline cpu --option tile=8x8 --option tile=4x4", "option 'tile' is given twice"},
      {"gl_device_negative", "run --gl-device -1", "--gl-device: '-1' is not in 0 to 1023"},
      {"unknown_flag", "run --colour red", "--colour"},
      {"out_name_too_long", "run --grid 4x4 --steps 2 --out {dir}/" + std::string(300, 'q'),
       "a name of 300 bytes, longer than 230 (255, the most a file name takes, less room for its temporary's suffix)"},
      {"out_folder_name_too_long", "run --grid 4x4 --steps 2 --out {dir}/" + std::string(256, 'q') + "/run",
       "a name of 256 bytes, longer than 255, the most a file name takes"},
      // 19 names of 200 bytes: a path of over 3800 bytes, whose files' paths would pass 4095
      {"out_path_too_long_for_its_files",
       "run --grid 4x4 --steps 2 --out {dir}" + repeated("/" + std::string(200, 'q'), 19),
       "bytes, which leaves less than the 256 its files' paths may need within the 4095 a path may be"},
      {"experiment_out_name_too_long", "experiment quick --out {dir}/" + std::string(300, 'q'),
       "a name of 300 bytes, longer than 230 (255, the most a file name takes, less room for its temporary's suffix)"},
      {"mesh_out_where_no_file_can_be_made", "mesh --experiment meshes --model bunny-shell --out /proc/x.msh",
       "--out '/proc/x.msh': no file can be made there ("},
      {"mesh_out_name_too_long", "mesh --experiment meshes --model bunny-shell --out {dir}/" + std::string(300, 'q') + ".msh",
       ".msh': a name of 304 bytes, longer than 230 (255, the most a file name takes, less room"},
      {"experiment_name_too_long", "experiment {dir}/x.json",
       "x.json.name: expected a name of up to 64 letters, digits, '-', '_' and '.'",
       {{"x.json", R"({"name": ")" + std::string(65, 'n') + R"(", "base": "quick"})"}}},
      {"sweep_cell_name_too_long", "experiment {dir}/x.json",
       "x.json.sweep: cell 'glsl-compute__semi-implicit-euler__8__window-" + std::string(200, '0') +
           "64' has a name of 247 bytes, more than 200 (its file's name)",
       {{"x.json", R"({"base": "quick", "sweep": {"sizes": [8], "pipelines": ["glsl-compute"], "options": [{"window": ")" +
                       std::string(200, '0') + R"(64"}]}})"}}},
      {"grid_too_large", "run --grid 100000x100000", "--grid (cloth 100000x100000): a model of about 1e+10 nodes exceeds"},
      {"lattice_too_large", "run --lattice 2000x2000x2000", "exceeds the limit of 2^30 nodes"},
      // 2^22 x 2^21 x 2^21 nodes: 2^64, 0 in 64 bits
      {"lattice_past_64_bits", "run --lattice 4194304x2097152x2097152",
       "a model of about 1.84e+19 nodes exceeds the limit of 2^30 nodes"},
      scene("lattice_past_64_bits_in_a_scene", R"({"model": {"type": "lattice", "size": [4194304, 2097152, 2097152]}})",
            "s.json.model (lattice 4194304x2097152x2097152): a model of about 1.84e+19 nodes exceeds the limit"),
      {"host_memory", "run --pipeline reference --grid 32000x32000", "GiB of host memory"},
      {"out_is_a_file", "run --pipeline cpu --steps 3 --out {dir}/f.txt", "exists and is not a folder", {{"f.txt", "x"}}},
      {"out_empty", "run --pipeline cpu --steps 3 --out ''", "--out '': an empty path names no folder"},
      {"out_under_a_file", "run --pipeline cpu --steps 3 --out {dir}/f.txt/sub", "f.txt' is not a folder", {{"f.txt", "x"}}},
      {"out_no_storage", "run --pipeline cpu --steps 3 --out /proc/deformlab-out", "'/proc' is on one of the kernel's file systems (such as proc or sysfs)"},
      // scene files that are no JSON file
      {"scene_missing", "run --scene {dir}/missing.json", "cannot open scene file"},
      {"scene_directory", "run --scene {dir}", "is a directory, not a JSON file"},
      {"scene_device", "run --scene /dev/zero", "scene file '/dev/zero' is not a regular file"},
      // A regular file whose read fails (and whose size, 0, says nothing).
      {"scene_read_fails", "run --scene /proc/self/mem", "cannot read scene file '/proc/self/mem': Input/output error"},
      {"scene_empty", "run --scene {dir}/s.json", "is not valid JSON: parse error", {{"s.json", ""}}},
      {"scene_binary", "run --scene {dir}/s.json", "is not valid JSON", {{"s.json", std::string("\x01\xff\x00\x7f", 4)}}},
      {"scene_truncated", "run --scene {dir}/s.json", "is not valid JSON", {{"s.json", "{\"dt\": "}}},
      {"scene_nul_then_text", "run --scene {dir}/s.json", "s.json' is not valid JSON: a NUL byte at byte 14",
       {{"s.json", std::string("{\"dt\": 0.001}\0{{{", 17)}}},
      {"scene_overflow", "run --scene {dir}/s.json", "is not valid JSON: number overflow parsing '1e999'",
       {{"s.json", "{\"dt\": 1e999}"}}},
      {"scene_duplicate_key", "run --scene {dir}/s.json", "s.json' gives the key 'dt' twice in one object",
       {{"s.json", "{\"model\": {\"size\": [4, 4]}, \"dt\": 0.003, \"dt\": 0.001}"}}},
      {"scene_duplicate_key_inside", "run --scene {dir}/s.json",
       "s.json' gives the key 'radius' twice in one object (at spheres[1])",
       {{"s.json", "{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}, {\"center\": [0, 1, 0], \"radius\": 1, "
                   "\"radius\": 2}]}"}}},
      // A NUL would cut short every message that quotes the string or key (mesh_file_nul below).
      {"scene_nul_in_a_key", "run --scene {dir}/s.json", "s.json' holds a key with a NUL character in it (at spheres[0])",
       {{"s.json", R"({"spheres": [{"cent\u0000er": [0, 0, 0]}]})"}}},
      {"scene_is_an_experiment", "run --scene {dir}/s.json", "s.json: an experiment file (it has \"scene\", \"sweep\" or "
       "\"base\"), not a scene: give it as --experiment", {{"s.json", R"({"base": "quick"})"}}},
      {"scene_long_key", "run --scene {dir}/s.json", "s.json' holds a key of 100000 bytes (at model), longer than any "
       "name it can have", {{"s.json", "{\"model\": {\"" + std::string(100000, 'k') + "\": 1}}"}}},
      {"scene_nested_deep", "run --scene {dir}/s.json", "s.json' nests arrays and objects more than 256 deep",
       {{"s.json", "{\"model\": {\"pins\": " + std::string(100000, '[') + std::string(100000, ']') + "}}"}}},
      // scene values
      scene("unknown_key", "{\"dtt\": 1}", "s.json.dtt: unknown key"),
      scene("unknown_model_key", "{\"model\": {\"colour\": 1}}", "s.json.model.colour: unknown key"),
      scene("mesh_without_source", "{\"model\": {\"type\": \"mesh\"}}",
            "s.json.model: a mesh model needs a file (\"file\") or a shape (\"generate\")"),
      scene("dt_negative_in_file", "{\"dt\": -0.001}", "s.json.dt: expected a number > 0"),
      scene("dt_string", "{\"dt\": \"fast\"}", "s.json.dt: expected a number"),
      scene("dt_float_range", "{\"dt\": 1e308}", "s.json.dt: expected a number of magnitude at most 3e38 (it is read as a float)"),
      scene("gravity_two", "{\"gravity\": [0, 1]}", "s.json.gravity: expected [x, y, z]"),
      scene("wind_string", "{\"wind\": [0, \"a\", 0]}", "s.json.wind[1]: expected a number"),
      scene("damping_negative", "{\"damping\": -1}", "s.json.damping: expected a number >= 0"),
      scene("ground_string", "{\"ground\": \"low\"}", "s.json.ground: expected a number"),
      scene("model_type", "{\"model\": {\"type\": \"sphere\"}}", "s.json.model.type"),
      scene("size_zero", "{\"model\": {\"size\": [0, 4]}}", "s.json.model.size[0]: expected an integer >= 1"),
      scene("size_one_number", "{\"model\": {\"size\": [4]}}", "s.json.model.size: expected [nx, ny]"),
      scene("size_fraction", "{\"model\": {\"size\": [4.5, 4]}}", "s.json.model.size[0]: expected an integer"),
      scene("size_huge", "{\"model\": {\"size\": [4, 9999999999]}}", "s.json.model.size[1]: integer out of range"),
      scene("stiffness_negative", "{\"model\": {\"stiffness\": {\"structural\": -200}}}",
            "s.json.model.stiffness.structural: expected a number > 0"),
      scene("stiffness_zero", "{\"model\": {\"stiffness\": 0}}", "s.json.model.stiffness: expected a number > 0"),
      scene("stiffness_subnormal", "{\"model\": {\"stiffness\": 1e-46}}",
            "s.json.model.stiffness: expected a number of at least 1.18e-38 (the smallest normal float)"),
      scene("stiffness_string", "{\"model\": {\"stiffness\": {\"shear\": \"x\"}}}",
            "s.json.model.stiffness.shear: expected a number"),
      scene("stiffness_kind", "{\"model\": {\"stiffness\": {\"bend\": 1}}}", "s.json.model.stiffness.bend: unknown key"),
      scene("spring_damping_negative", "{\"model\": {\"damping\": -5}}", "s.json.model.damping: expected a number >= 0"),
      scene("flexion_damping_negative", "{\"model\": {\"damping\": {\"flexion\": -1}}}",
            "s.json.model.damping.flexion: expected a number >= 0"),
      scene("mass_zero", "{\"model\": {\"node_mass\": 0}}", "s.json.model.node_mass: expected a number > 0"),
      scene("mass_negative", "{\"model\": {\"node_mass\": -1}}", "s.json.model.node_mass: expected a number > 0"),
      scene("width_negative", "{\"model\": {\"width\": -1}}", "s.json.model.width: expected a number > 0"),
      scene("spacing_negative", "{\"model\": {\"spacing\": -0.1}}", "s.json.model.spacing: expected a number >= 0"),
      scene("spacing_and_width", "{\"model\": {\"spacing\": 0.1, \"width\": 2}}",
            "s.json.model.width: give spacing or width, not both"),
      scene("pins_duplicate", "{\"model\": {\"pins\": [0, 0]}}", "s.json.model.pins[1]: the same selector as pins[0]"),
      scene("pins_duplicate_nearest",
            "{\"model\": {\"pins\": [{\"nearest\": [0.1, 0, 0]}, 3, {\"nearest\": [0.1000000001, 0, 0]}]}}",
            "s.json.model.pins[2]: the same selector as pins[0]"),
      scene("pins_negative", "{\"model\": {\"pins\": [-1]}}", "s.json.model.pins[0]: expected an integer >= 0"),
      scene("pins_outside", "{\"model\": {\"size\": [8, 8], \"pins\": [99999]}}", "s.json.model.pins[0]: node 99999 is outside the model (0..63)"),
      scene("pins_name", "{\"model\": {\"pins\": \"bottom\"}}", "s.json.model.pins: expected \"none\""),
      scene("sphere_no_radius", "{\"spheres\": [{\"center\": [0, 0, 0]}]}", "s.json.spheres[0]: needs center and radius"),
      scene("sphere_radius_zero", "{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 0}]}",
            "s.json.spheres[0].radius: expected a number > 0"),
      scene("spheres_not_list", "{\"spheres\": 5}", "s.json.spheres: expected a list"),
      scene("drag_node_negative", "{\"drag\": {\"node\": -1, \"path\": [[0, 0, 0, 0]]}}",
            "s.json.drag.node: expected an integer >= 0"),
      scene("drag_node_outside", "{\"model\": {\"size\": [4, 4]}, \"drag\": {\"node\": 99, \"path\": [[0, 0, 0, 0]]}}",
            "s.json.drag.node: node 99 is outside the model (0..15)"),
      scene("drag_mode", "{\"drag\": {\"mode\": \"soft\"}}", "s.json.drag.mode: expected \"hard\" or \"spring\""),
      scene("drag_stiffness", "{\"drag\": {\"stiffness\": -5}}", "s.json.drag.stiffness: expected a number > 0"),
      scene("drag_stiffness_hard", "{\"drag\": {\"mode\": \"hard\", \"stiffness\": 5}}",
            "s.json.drag.stiffness: the spring mode's (\"mode\": \"spring\"); the hard mode puts the node on its path"),
      scene("start_deep_in_the_ground", "{\"model\": {\"size\": [4, 4], \"height\": -3}, \"ground\": 0}",
            "node 1 starts 3 m below the ground, deeper than a step may move a node (runaway_factor x model extent: "
            "1.41 m); its first step would be taken for divergence"),
      scene("drag_jumps_from_rest", R"({"model": {"size": [8, 8]}, "drag": {"node": "center", "path": [[0.01, 0, 50, 0]]}})",
            "s.json.drag.path[0]: the handle moves 10 m in the step from t = 0 s (from the node's rest position), more "
            "than a step may move a node (runaway_factor x model extent: 1.41 m)"),
      scene("drag_jumps_onto_its_first_key",
            R"({"model": {"size": [8, 8]}, "drag": {"node": "center", "path_is": "position", "path": [[0, 0, 50, 0], [1, 0, 50, 0]]}})",
            "s.json.drag.path[0]: the handle moves 49 m in the step from t = 0 s (from the node's rest position)"),
      scene("drag_jumps_onto_its_only_key",
            R"({"model": {"size": [8, 8]}, "drag": {"node": "center", "path": [[0, 1000, 0, 0]]}})",
            "s.json.drag.path[0]: the handle moves 1000 m in the step from t = 0 s (from the node's rest position)"),
      scene("drag_passes_a_key_in_its_first_step",
            R"({"model": {"size": [8, 8]}, "drag": {"node": "center", "path": [[0, 0, 0, 0], [0.001, 100, 0, 0]]}})",
            "s.json.drag.path[1]: the handle moves 100 m in the step from t = 0 s"),
      scene("drag_jumps_between_keys",
            R"({"model": {"size": [8, 8]}, "drag": {"node": 27, "path": [[0, 0, 0, 0], [0.5, 0, 0, 0], [0.501, 0, 30, 0]]}})",
            "s.json.drag.path[2]: the handle moves 30 m in the step from t = 0.5 s"),
      // dt spans keys 1 m apart: 2.5 m in the first step
      scene("drag_step_spans_keys",
            R"({"model": {"size": [8, 8]}, "dt": 0.01, "drag": {"node": "center", "path": [[0.004, 1, 0, 0], [0.008, 2, 0, 0], [0.012, 3, 0, 0]]}})",
            "s.json.drag.path[2]: the handle moves 2.5 m in the step from t = 0 s"),
      {"drag_path_of_the_experiment", "run --pipeline cpu --steps 3 --experiment {dir}/x.json",
       "x.json.scene.drag.path[0]: the handle moves 10 m in the step from t = 0 s",
       {{"x.json", R"({"base": "paper-drag", "scene": {"model": {"size": [8, 8]}, "drag": {"path": [[0.01, 0, 50, 0]]}}})"}}},
      scene("start_deep_in_a_sphere",
            "{\"model\": {\"size\": [4, 4], \"width\": 0.2}, \"spheres\": [{\"center\": [0, 1, 0], \"radius\": 3}]}",
            "inside spheres[0], deeper than a step may move a node"),
      scene("drag_path_empty", "{\"drag\": {\"path\": []}}", "s.json.drag.path: expected a non-empty list"),
      scene("drag_keyframe_short", "{\"drag\": {\"path\": [[0, 0, 0]]}}", "s.json.drag.path[0]: expected [t, x, y, z]"),
      scene("drag_keyframes_backwards", "{\"drag\": {\"path\": [[1, 0, 0, 0], [0.5, 0, 0, 0]]}}",
            "s.json.drag.path[1][0]: keyframe times must increase"),
      scene("drag_keyframe_negative_time", "{\"drag\": {\"node\": 0, \"path\": [[-1, 0, 0, 0]]}}",
            "s.json.drag.path[0][0]: expected a number >= 0"),
      // mesh models: the file (named relative to the scene) and the keys
      mesh("mesh_transform_singular", "{\"file\": \"m.obj\", \"transform\": [[0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}",
           "s.json.model.transform: its 3 x 3 part is singular: it would flatten the mesh"),
      mesh("mesh_density_and_node_mass", "{\"file\": \"m.obj\", \"density\": 1, \"node_mass\": 0.01}",
           "s.json.model.node_mass: give density or node_mass, not both"),
      mesh("mesh_cell_size_unfilled", "{\"file\": \"m.obj\", \"cell_size\": 0.1}",
           "s.json.model.cell_size: the cell size of a tetrahedral fill, and this mesh is not filled"),
      mesh("mesh_seed_unshuffled", "{\"file\": \"m.obj\", \"order\": \"rcm\", \"seed\": 4}",
           "s.json.model.seed: seeds the shuffled order, and this mesh's order is rcm"),
      mesh("mesh_shear", "{\"file\": \"m.obj\", \"stiffness\": {\"shear\": 4}}",
           "s.json.model.stiffness.shear: a mesh has no shear springs"),
      mesh("mesh_file_missing", "{\"file\": \"none.obj\"}", "none.obj': no such file"),
      mesh("mesh_file_directory", "{\"file\": \"/\"}", "mesh file '/': a directory, not a mesh file"),
      mesh("mesh_file_empty", "{\"file\": \"m.obj\"}", "m.obj': the file is empty", ""),
      mesh("mesh_file_truncated", "{\"file\": \"m.stl\"}", "m.stl': assimp: Failed to determine STL storage",
           std::string(80, ' ') + std::string("\x0c\0\0\0", 4) + std::string(50, '\0'), "m.stl"),
      mesh("mesh_nan", "{\"file\": \"m.obj\"}", "m.obj': a vertex has a NaN or infinite coordinate (nan, 0, 0)",
           "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
      mesh("mesh_two_nans", "{\"file\": \"m.obj\"}", "m.obj': a vertex has a NaN or infinite coordinate",
           "v 0 0 0\nv 1 nan 0\nv nan 1 0\nf 1 2 3\n"),
      mesh("mesh_msh_nan", "{\"file\": \"m.msh\"}", "m.msh': a vertex has a NaN or infinite coordinate (0, nan, 0)",
           "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 nan 0\n0 0 1\n"
           "$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n",
           "m.msh"),
      mesh("mesh_scale_overflow", "{\"file\": \"m.obj\", \"scale\": 1e38}",
           "m.obj': its scale and transform take the vertex (10, 0, 0) more than 1e15 m from the origin along an "
           "axis, where squared lengths overflow float",
           "v 0 0 0\nv 10 0 0\nv 0 1 0\nf 1 2 3\n"),
      mesh("mesh_vertex_far", "{\"file\": \"m.obj\"}",
           "m.obj': the vertex (-3e+38, 0, 0) lies more than 1e15 m from the origin", "v -3e38 0 0\nv 3e38 0 0\nv 0 1 0\nf 1 2 3\n"),
      scene("grid_width_past_float", "{\"model\": {\"size\": [4, 4], \"width\": 3e38}}",
            "s.json.model.width: expected a length within [1e-6, 1e6] m"),
      scene("grid_spacing_from_width_too_short", R"({"model": {"size": [1001, 11], "width": 1e-6}})",
            "s.json.model (cloth 1001x11): its width, 1e-06 m across 1001 nodes, spaces them 1e-09 m apart: under the "
            "1e-6 m a model's lengths take"),
      // Floats 0.0078 m apart at 1e5 m, over a hundredth of the 0.0667 m springs: the cloth never moved.
      scene("grid_far_from_the_origin", R"({"model": {"size": [16, 16], "height": 1e5}})",
            "s.json.model (cloth 16x16): it lies up to 1e+05 m from the origin, where floats are 0.00781 m apart: more "
            "than a hundredth of its shortest spring (0.0667 m), so rounding would swallow its strains and small moves: "
            "place it nearer the origin, or make that spring longer"),
      mesh("mesh_far_from_the_origin", "{\"file\": \"m.obj\", \"transform\": {\"translate\": [0, 0, 30000]}}",
           "m.obj': it lies up to 3e+04 m from the origin, where floats are 0.00195 m apart: more than a hundredth of "
           "its shortest spring (0.1 m, between nodes 0 and 1)", "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n"),
      scene("grid_spacing_past_float", "{\"model\": {\"size\": [4, 4], \"spacing\": 2e38}}",
            "s.json.model.spacing: expected a length within [1e-6, 1e6] m"),
      scene("grid_height_far", "{\"model\": {\"size\": [4, 4], \"height\": -1e7}}",
            "s.json.model.height: expected a height within [-1e6, 1e6] m"),
      mesh("mesh_ply_nan", "{\"file\": \"m.ply\"}", "m.ply': a vertex has a NaN or infinite coordinate",
           "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
           "m.ply"),
      // Gmsh reads a .msh file that does not start as a mesh as a .geo script ("Unknown variable 'world'").
      mesh("mesh_msh_not_a_mesh", "{\"file\": \"m.msh\"}",
           "m.msh': not a Gmsh mesh: it does not start with $MeshFormat or another section Gmsh reads as a mesh (Gmsh "
           "would read it as a .geo script)",
           "hello world\n", "m.msh"),
      mesh("mesh_msh2_cut_short", "{\"file\": \"m.msh\"}",
           "m.msh': Gmsh could not read it (Error loading '",
           "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
           "$Elements\n1 4 2 0 1 1 2 3 4\n", "m.msh"),
      mesh("mesh_ply_truncated_header", "{\"file\": \"m.ply\"}", "m.ply': its PLY header has no end_header line",
           "ply\nformat ascii 1.0\n", "m.ply"),
      // assimp clamps an OFF face's index out of range and says so only in its log.
      mesh("mesh_off_index_out_of_range", "{\"file\": \"m.off\"}", "m.off': assimp: OFF: Vertex index is out of range",
           "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 9 2\n", "m.off"),
      // Read as PLY for its content where assimp knows no reader for its extension.
      mesh("mesh_ply_truncated_header_unnamed", "{\"file\": \"m.dat\"}",
           "m.dat': its PLY header has no end_header line", "ply\nformat ascii 1.0\nelement vertex 3\nprop", "m.dat"),
      // assimp 5.2 crashes on this header (a property line run into end_header: no end_header
      // line), or loops for ever on one whose end_header is misspelt or a comment's word; a crash
      // in the child process that reads a mesh is one line too (tests/unit/child_read_test.cpp).
      mesh("mesh_ply_end_header_run_into_a_property", "{\"file\": \"m.ply\"}", "m.ply': its PLY header has no end_header line",
           ply_header("3", "1") + "list uchar int vertex_indicesxend_header\n" + std::string(36, '\0') + "\3" +
               std::string(12, '\0'),
           "m.ply"),
      // A count is checked against the bytes after the header before assimp takes it as it stands.
      mesh("mesh_ply_end_header_misspelt", "{\"file\": \"m.ply\"}", "m.ply': its PLY header has no end_header line",
           "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_headers\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
           "m.ply"),
      mesh("mesh_ply_end_header_in_a_comment", "{\"file\": \"m.ply\"}", "m.ply': its PLY header has no end_header line",
           "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\ncomment end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
           "m.ply"),
      mesh("mesh_ply_no_body", "{\"file\": \"m.ply\"}",
           "m.ply': its PLY header declares 3 vertex, 1 face elements, whose values take at least 19 bytes, where 0 follow",
           "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header", "m.ply"),
      mesh("mesh_ply_count_huge", "{\"file\": \"m.ply\"}",
           "m.ply': its PLY header declares 4000000000 vertex, 1 face elements, whose values take at least "
           "12000000001 bytes, where 12 follow the header (a truncated or damaged file)",
           ply_header("4000000000", "1") + "list uchar int vertex_indices\nend_header\n" + std::string(12, '\0'), "m.ply"),
      // assimp reads a count's leading digits.
      mesh("mesh_ply_count_with_a_tail", "{\"file\": \"m.ply\"}",
           "m.ply': its PLY header declares 100000000 vertex, 1 face elements, whose values take at least "
           "600000001 bytes, where 26 follow the header (a truncated or damaged file)",
           "ply\nformat ascii 1.0\nelement vertex 100000000x\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
           "m.ply"),
      mesh("mesh_ply_ascii_count_huge", "{\"file\": \"m.ply\"}",
           "m.ply': its PLY header declares 100000000 vertex, 1 face elements, whose values take at least "
           "600000001 bytes, where 26 follow the header (a truncated or damaged file)",
           "ply\nformat ascii 1.0\nelement vertex 100000000\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
           "m.ply"),
      mesh("mesh_density_tiny", "{\"file\": \"m.obj\", \"density\": 1.2e-38}", "is too small for float arithmetic"),
      mesh("mesh_non_manifold", "{\"file\": \"m.obj\"}", "is shared by 3 triangles (non-manifold; node indices from 0",
           "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n"),
      mesh("mesh_degenerate", "{\"file\": \"m.obj\"}", "triangle 0 is degenerate: zero area",
           "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
      mesh("mesh_no_faces", "{\"file\": \"m.obj\"}", "m.obj': assimp: Validation failed: Mesh contains no faces",
           "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
      mesh("mesh_lines_only", "{\"file\": \"m.obj\"}", "m.obj': no triangles", "v 0 0 0\nv 1 0 0\nl 1 2\n"),
      mesh("mesh_obj_two_vertex_face", "{\"file\": \"m.obj\"}",
           "m.obj': assimp: Validation failed: aiMesh::mFaces[1] is a LINE but aiMesh::mPrimitiveTypes does not report "
           "the LINE flag (a face of fewer than 3 vertices among polygons: an OBJ writes lines with `l`, points with `p`)",
           "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n"),
      mesh("mesh_obj_vertex_skipped", "{\"file\": \"m.obj\"}",
           "m.obj': line 2: a vertex of 2 numbers, which assimp's OBJ reader skips (it keeps 3, 4 or 6, counting the "
           "words that start with a digit, + or -: write .5 as 0.5)",
           "v 0 0 0\nv .5 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n"),
      mesh("mesh_obj_vertex_number_run_in", "{\"file\": \"m.obj\"}",
           "m.obj': line 1: a `v5...` line, which assimp's OBJ reader skips (a vertex is `v x y z`)",
           "v5 5 5\nv 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n"),
      mesh("mesh_obj_vertex_capital", "{\"file\": \"m.obj\"}",
           "m.obj': line 1: a `V` line, which assimp's OBJ reader skips (a vertex is `v x y z`)",
           "V 5 5 5\nv 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n"),
      mesh("mesh_obj_face_capital", "{\"file\": \"m.obj\"}",
           "m.obj': line 5: a `F` line, which assimp's OBJ reader skips (a face is `f a b c`)",
           "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\nF 1 3 2\n"),
      mesh("mesh_obj_face_index_run_in", "{\"file\": \"m.obj\"}",
           "m.obj': line 5: a `f2...` line, which assimp's OBJ reader reads without its first index (a face is `f a b c`)",
           "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 1 0 1\nf2 4 3 1\n"),
      // Lines that end in a lone CR, as assimp reads them.
      mesh("mesh_ply_cr_line_ends", "{\"file\": \"m.ply\"}",
           "m.ply': its PLY header declares 30 vertex, 1 face elements, whose values take at least 181 bytes, where 26 "
           "follow the header",
           "ply\rformat ascii 1.0\relement vertex 30\rproperty float x\rproperty float y\rproperty float z\r"
           "element face 1\rproperty list uchar int vertex_indices\rend_header\r0 0 0\r1 0 0\r0 1 0\r3 0 1 2\r",
           "m.ply"),
      mesh("mesh_obj_vertex_continued", "{\"file\": \"m.obj\"}",
           "m.obj': line 2: a vertex of 2 numbers",  // "v 1\\" and "0 0" join as "v 10 0"
           "v 0 0 0\nv 1\\\n0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n"),
      mesh("mesh_obj_by_content", "{\"file\": \"m.txt\"}", "m.txt': line 2: a vertex of 2 numbers",
           "v 0 0 0\nv .5 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n", "m.txt"),
      mesh("mesh_obj_face_indented", "{\"file\": \"m.obj\"}",
           "m.obj': line 6: an indented `f` line, which assimp's OBJ reader skips",
           "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n\t f 2 4 3\n"),
      mesh("mesh_obj_byte_order_mark", "{\"file\": \"m.obj\"}",
           "m.obj': line 1: a byte-order mark before a `v` line, which assimp's OBJ reader skips",
           "\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 5 5 5\nf 1 2 3\nf 2 4 3\n"),
      mesh("mesh_fill_open", "{\"file\": \"m.obj\", \"fill\": \"tetrahedra\"}",
           "Gmsh made no tetrahedra (is the surface closed?)"),
      mesh("mesh_fill_self_crossing", "{\"file\": \"x.obj\", \"fill\": \"tetrahedra\", \"cell_size\": 0.2}",
           "x.obj': PLC Error:  A segment and a facet intersect at point (the surface crosses itself: a fill takes a "
           "closed surface whose triangles meet only at shared edges)",
           "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0.2 0.2 0.2\nv 1.2 0.2 0.2\nv 0.2 1.2 0.2\nv 0.2 0.2 1.2\n"
           "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n", "x.obj"),
      mesh("mesh_fill_too_fine", "{\"file\": \"t.obj\", \"fill\": \"tetrahedra\", \"cell_size\": 0.00001}",
           "filling with tetrahedra of cell_size 1e-05 m would make about 1e+14 nodes, over the limit of 2^30",
           "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n", "t.obj"),
      // Two parts wound against each other: their volumes add (they cancelled: no limit).
      mesh("mesh_fill_parts_wound_apart", "{\"file\": \"t.obj\", \"fill\": \"tetrahedra\", \"cell_size\": 0.00001}",
           "filling with tetrahedra of cell_size 1e-05 m would make about 2e+14 nodes, over the limit of 2^30",
           "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
           "v 5 0 0\nv 6 0 0\nv 5 1 0\nv 5 0 1\nf 5 6 7\nf 5 8 6\nf 5 7 8\nf 6 8 7\n",
           "t.obj"),
      mesh("mesh_order", "{\"file\": \"m.obj\", \"order\": \"hilbert\"}",
           "s.json.model.order: expected one of: file, shuffled, rcm, morton"),
      mesh("mesh_size_key", "{\"size\": [4, 4]}", "s.json.model.size: not a key of a mesh model"),
      mesh("mesh_scale_zero", "{\"file\": \"m.obj\", \"scale\": 0}", "s.json.model.scale: expected a number > 0"),
      mesh("mesh_transform_row", "{\"file\": \"m.obj\", \"transform\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [1, 0, 0, 1]]}",
           "s.json.model.transform[3]: the last row of an affine map is [0, 0, 0, 1]"),
      mesh("mesh_spring_too_short", "{\"file\": \"m.obj\", \"scale\": 1e-20}",
           "m.obj': the spring between nodes 0 and 1 is 1e-20 m long, shorter than the 1e-6 m a model's lengths take"),
      mesh("mesh_spring_too_short_in_the_file", "{\"file\": \"m.obj\"}", "the spring between nodes 0 and 2 is 5e-07 m long",
           "v 0 0 0\nv 1 0 0\nv 0 5e-7 0\nf 1 2 3\n"),
      mesh("mesh_pins_grid_set", "{\"file\": \"m.obj\", \"pins\": \"top-row\"}", "s.json.model.pins: pin set 'top-row' needs a grid or lattice"),
      {"mesh_pins_absent", "run --pipeline cpu --steps 3 --scene {dir}/s.json",
       "s.json.model.pins (absent: the default): pin set 'top-corners' needs a grid or lattice (pin meshes by position)",
       {{"s.json", "{\"model\": {\"type\": \"mesh\", \"file\": \"m.obj\"}}"}, {"m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}}},
      {"sweep_size_deep_in_the_ground", "experiment {dir}/x.json",
       "x.json.sweep.sizes[0]: size 4²: node 1 starts 9 m below the ground, deeper than a step may move a node",
       {{"x.json", R"({"base": "quick", "scene": {"model": {"height": 1}, "ground": 10},
                       "sweep": {"sizes": [4, 8], "pipelines": ["cpu"]}})"}}},
      {"sweep_size_drag_node_outside", "experiment {dir}/x.json",
       "x.json.sweep.sizes[1]: size 4²: ",
       {{"x.json", R"({"base": "quick", "scene": {"drag": {"node": 20}}, "sweep": {"sizes": [8, 4], "pipelines": ["cpu"]}})"}}},
      // 4096² is over kCheckedNodes and never built here: its spacing (1 m / 4095) at 40 m is checked from the spec.
      {"sweep_size_float_resolution", "experiment {dir}/x.json",
       "x.json.sweep.sizes[1]: size 4096²: it lies up to 40 m from the origin, where floats are 3.81e-06 m apart: more "
       "than a hundredth of its shortest spring (0.000244 m)",
       {{"x.json", R"({"base": "quick", "scene": {"model": {"height": 40}}, "sweep": {"sizes": [8, 4096], "pipelines": ["cpu"]}})"}}},
      {"sweep_size_float_resolution_past_max_size", "experiment {dir}/x.json --max-size 8",
       "x.json.sweep.sizes[1]: size 4096²: it lies up to 40 m from the origin",
       {{"x.json", R"({"base": "quick", "scene": {"model": {"height": 40}}, "sweep": {"sizes": [8, 4096], "pipelines": ["cpu"]}})"}}},
      // The frames' 128² cloth at 1500 m is refused; the 16² cells alone would hold there.
      {"sweep_frames_scene_float_resolution", "experiment {dir}/x.json",
       "x.json.scene.model (cloth 128x128, the experiment's own scene, whose frames its sweep draws): it lies up to 1.5e+03 m",
       {{"x.json", R"({"base": "quick", "scene": {"model": {"height": 1500}}, "sweep": {"sizes": [16], "pipelines": ["cpu"]}})"}}},
      {"sweep_size_past_the_node_limit", "experiment {dir}/x.json",
       "x.json.sweep.sizes[1]: size 32769²: a model of about",
       {{"x.json", R"({"base": "quick", "sweep": {"sizes": [16, 32769], "pipelines": ["cpu"]}})"}}},
      {"sweep_size_drag_node_pinned", "experiment {dir}/x.json",
       "x.json.sweep.sizes[0]: size 1²: built-in paper-drag.json.scene.drag.node: node 0 is pinned (model.pins)",
       {{"x.json", R"({"base": "quick", "sweep": {"sizes": [1, 8], "pipelines": ["cpu"]}})"}}},
      {"mesh_pins_inherited", "run --pipeline cpu --steps 3 --experiment {dir}/x.json",
       "x.json.scene.model.pins (absent: from built-in paper-drag.json.scene.model.pins): pin set 'top-corners' needs a grid",
       {{"x.json", R"({"base": "paper-drag", "scene": {"model": {"type": "mesh", "file": "m.obj"}}})"},
        {"m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}}},
      mesh("mesh_pins_box_empty", "{\"file\": \"m.obj\", \"pins\": {\"box\": [[5, 5, 5], [6, 6, 6]]}}",
           "s.json.model.pins: the box holds no node of the model"),
      mesh("mesh_pins_box_corners", "{\"file\": \"m.obj\", \"pins\": {\"box\": [[1, 1, 1], [0, 0, 0]]}}",
           "s.json.model.pins.box: the first corner must be the lowest"),
      // generated meshes
      scene("generate_size_tiny", G(R"({"shape": "sheet", "size": [1e-30, 1], "cell_size": 0.1})"),
            "s.json.model.generate.size[0]: expected a length within [1e-6, 1e6] m"),
      scene("generate_box_huge", G(R"({"shape": "box", "size": [3e38, 3e38, 3e38], "cell_size": 1e38})"),
            "s.json.model.generate.size[0]: expected a length within [1e-6, 1e6] m"),
      scene("generate_sides_far_apart", G(R"({"shape": "sheet", "size": [1000, 1e-6], "cell_size": 1})"),
            "s.json.model.generate.size: its longest side is more than 1e6 times its shortest"),
      scene("generate_shape", G(R"({"shape": "disc", "size": [1, 1], "cell_size": 0.1})"),
            "s.json.model.generate.shape: expected \"sheet\" or \"box\""),
      scene("generate_sheet_arity", G(R"({"shape": "sheet", "size": [1, 1, 1], "cell_size": 0.1})"),
            "s.json.model.generate.size: expected [w, d] (m) for a sheet"),
      scene("generate_box_arity", G(R"({"shape": "box", "size": [1, 1], "cell_size": 0.1})"),
            "s.json.model.generate.size: expected [w, h, d] (m) for a box"),
      scene("generate_size_zero", G(R"({"shape": "box", "size": [1, 0, 1], "cell_size": 0.1})"),
            "s.json.model.generate.size[1]: expected a number > 0"),
      scene("generate_size_negative", G(R"({"shape": "sheet", "size": [-1, 1], "cell_size": 0.1})"),
            "s.json.model.generate.size[0]: expected a number > 0"),
      scene("generate_cell_zero", G(R"({"shape": "sheet", "size": [1, 1], "cell_size": 0})"),
            "s.json.model.generate.cell_size: expected a number > 0"),
      scene("generate_no_cell", G(R"({"shape": "sheet", "size": [1, 1]})"), "s.json.model.generate: needs cell_size"),
      scene("generate_threads_zero", G(R"({"shape": "sheet", "size": [1, 1], "cell_size": 0.1, "threads": 0})"),
            "s.json.model.generate.threads: expected an integer >= 1"),
      scene("generate_threads_text", G(R"({"shape": "box", "size": [1, 1, 1], "cell_size": 0.1, "threads": "one"})"),
            "s.json.model.generate.threads: expected an integer"),
      scene("generate_threads_many", G(R"({"shape": "box", "size": [1, 1, 1], "cell_size": 0.1, "threads": 4096})"),
            "s.json.model.generate.threads: expected at most 1024 threads"),
      // about 985 M nodes: under the node limit, over any host's memory (some 950 GiB), refused before meshing
      scene("generate_over_memory", G(R"({"shape": "box", "size": [1, 1, 1], "cell_size": 0.00085})"),
            "generated box of about 9.85e+08 nodes: its model needs up to"),
      scene("generate_key", G(R"({"shape": "sheet", "size": [1, 1], "cell_size": 0.1, "algo": 5})"),
            "s.json.model.generate.algo: unknown key"),
      scene("generate_too_many_nodes", G(R"({"shape": "box", "size": [1, 1, 1], "cell_size": 0.0001})"),
            "s.json.model.generate.cell_size: would make about"),
      scene("generate_and_file", G(R"({"shape": "sheet", "size": [1, 1], "cell_size": 0.1}, "file": "m.obj")"),
            "s.json.model.generate: give either \"file\" or \"generate\", not both"),
      scene("drag_a_pinned_node", R"({"drag": {"node": 0, "path": [[0.01, 0, 0.5, 0]]}})",
            "s.json.drag.node: node 0 is pinned (model.pins), so the drag would not move it"),
      scene("generate_and_fill", G(R"({"shape": "box", "size": [1, 1, 1], "cell_size": 0.1}, "fill": "tetrahedra")"),
            "s.json.model.fill: fills a surface file"),
      // `deformlab mesh`: the file it would write is checked first, then the scene or model
      {"mesh_out_not_msh", "mesh --scene {dir}/s.json --out {dir}/m.obj", "m.obj': expected a file name ending in .msh",
       {{"s.json", G(R"({"shape": "sheet", "size": [1, 1], "cell_size": 0.1})")}}},
      {"mesh_not_generated", "mesh --scene {dir}/s.json --out {dir}/m.msh", ") is neither generated nor filled: only a model's \"generate\" or \"fill\"",
       {{"s.json", "{\"model\": {\"type\": \"mesh\", \"file\": \"m.obj\", \"pins\": \"none\"}}"}}},
      {"mesh_grid", "mesh --out {dir}/m.msh", "the scene's model (cloth 128x128) is neither generated nor filled"},
      {"mesh_model_unknown", "mesh --experiment meshes --model box-9m --out {dir}/m.msh",
       "--model 'box-9m': experiment 'meshes' has no such model (its models: bunny-shell, bunny-soft, sheet-1m"},
      {"mesh_model_missing", "mesh --experiment meshes --out {dir}/m.msh",
       "experiment 'meshes' sweeps mesh models: name one with --model (bunny-shell, "},
      {"mesh_model_without_sweep", "mesh --experiment table2 --model a --out {dir}/m.msh", "experiment 'table2' sweeps no mesh models"},
      {"mesh_over_memory", "mesh --scene {dir}/s.json --out {dir}/m.msh", "generated box of about 9.85e+08 nodes: its model needs",
       {{"s.json", G(R"({"shape": "box", "size": [1, 1, 1], "cell_size": 0.00085})")}}},
      {"mesh_out_under_a_file", "mesh --scene {dir}/s.json --out {dir}/f.txt/m.msh", "/f.txt' is not a folder",
       {{"s.json", G(R"({"shape": "sheet", "size": [0.1, 0.1], "cell_size": 0.05})")}, {"f.txt", "x"}}},
      {"filled_mesh_out_under_a_file", "mesh --scene {dir}/s.json --out {dir}/f.txt/m.msh", "/f.txt' is not a folder",
       {{"s.json", R"({"model": {"type": "mesh", "file": "t.obj", "fill": "tetrahedra", "pins": "none"}})"},
        {"t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"},
        {"f.txt", "x"}}},
      {"mesh_out_is_the_filled_file", "mesh --scene {dir}/s.json --out {dir}/t.msh",
       "t.msh' is the mesh file the model is filled from (model.file)",
       {{"s.json", R"({"model": {"type": "mesh", "file": "t.msh", "fill": "tetrahedra", "pins": "none"}})"},
        {"t.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                  "$Elements\n4\n1 2 2 0 1 1 3 2\n2 2 2 0 1 1 2 4\n3 2 2 0 1 1 4 3\n4 2 2 0 1 2 3 4\n$EndElements\n"}}},
      {"mesh_out_not_a_mesh", "mesh --scene {dir}/s.json --out {dir}/mine.msh",
       "mine.msh' holds a file that is not a Gmsh mesh",
       {{"s.json", G(R"({"shape": "sheet", "size": [0.1, 0.1], "cell_size": 0.05})")}, {"mine.msh", "my notes\n"}}},
      // `deformlab calibrate --out`: checked before the measurement, which takes seconds
      {"calibrate_out_under_a_file", "calibrate --out {dir}/s.json/deeper/c.json", "/s.json' is not a folder",
       {{"s.json", "{}"}}},
      {"calibrate_out_a_folder", "calibrate --out {dir}", "' is a folder"},
      {"calibrate_out_ends_in_slash", "calibrate --out {dir}/new/", "new/' names a folder (it ends in '/'), not a file"},
      scene("grid_mesh_key", "{\"model\": {\"file\": \"m.obj\"}}", "s.json.model.file: a key of mesh models"),
      scene("drag_node_box", "{\"drag\": {\"node\": {\"box\": [[0, 0, 0], [1, 1, 1]]}}}",
            "s.json.drag.node: expected a node index, \"center\" or {\"nearest\": [x, y, z]}"),
      scene("spheres_too_many", "{\"spheres\": [" + repeated("{\"center\": [0, 9, 0], \"radius\": 0.1}, ", 8) +
                                    "{\"center\": [0, 9, 0], \"radius\": 0.1}]}",
            "s.json.spheres: at most 8 spheres are supported, the scene has 9"),
      scene("threshold_zero_in_file", "{\"threshold\": 0}", "s.json.threshold: expected a number > 0"),
      scene("min_steps_negative", "{\"min_steps\": -1}", "s.json.min_steps: expected an integer >= 0"),
      scene("max_steps_zero", "{\"max_steps\": 0}", "s.json.max_steps: expected an integer >= 1"),
      scene("min_above_max", "{\"min_steps\": 500, \"max_steps\": 100}",
            "s.json.min_steps: min_steps (500) exceeds max_steps (100)"),
      scene("check_every_zero_in_file", "{\"check_every\": 0}", "s.json.check_every: expected an integer >= 1"),
      scene("runaway_zero", "{\"runaway_factor\": 0}", "s.json.runaway_factor: expected a number > 0"),
      // experiment and calibration files
      {"experiment_key", "run --experiment {dir}/x.json", "x.json.pipline: unknown key", {{"x.json", "{\"pipline\": \"cpu\"}"}}},
      {"experiment_base_missing", "run --experiment {dir}/x.json", "x.json.base: cannot open experiment file '",
       {{"x.json", "{\"base\": \"none.json\"}"}}},
      {"experiment_given_a_scene", "run --experiment {dir}/x.json",
       "x.json.dt: unknown key (expected name, description, pipeline, integrator, until_converged, base, scene, sweep); "
       "a scene's key: put it under \"scene\" (a file that is a scene goes to --scene)",
       {{"x.json", "{\"dt\": 0.001}"}}},
      {"experiment_scene_value", "run --experiment {dir}/x.json", "x.json.scene.dt: expected a number > 0",
       {{"x.json", "{\"scene\": {\"dt\": -1}}"}}},
      {"sweep_option_unread", "experiment {dir}/x.json", "x.json.sweep.options.tyle: no pipeline of this sweep reads option 'tyle'",
       {{"x.json", "{\"sweep\": {\"sizes\": [8], \"pipelines\": [\"cpu\"], \"options\": [{\"tyle\": \"8x8\"}]}}"}}},
      {"sweep_option_set_partly_read", "experiment {dir}/x.json",
       "x.json.sweep.options[1]: cuda-tiled reads tile but not interop, so it would run without this set",
       {{"x.json", R"({"sweep": {"sizes": [8], "pipelines": ["cuda-tiled", "hybrid"],
                                  "options": [{"tile": "16x8"}, {"tile": "16x8", "interop": "map"}]}})"}}},
      {"sweep_warmup_under_the_bounding_steps", "experiment {dir}/x.json",
       "x.json.sweep.warmup: expected at least 2 warm-up steps (a cell's first two steps bound its time",
       {{"x.json", R"({"sweep": {"sizes": [8], "pipelines": ["cpu"], "warmup": 1}})"}}},
      {"sweep_sizes_and_models", "experiment {dir}/x.json", "x.json.sweep: needs either sizes or models",
       {{"x.json", R"({"sweep": {"sizes": [8], "models": [{"name": "a", "model": {"file": "m.obj"}}], "pipelines": ["cpu"]}})"}}},
      {"sweep_steps_past_an_int", "experiment {dir}/x.json",
       "x.json.sweep.repetitions: 65536 batches of 65537 steps: a cell times at most 10000000 steps",
       {{"x.json", R"({"sweep": {"sizes": [8], "pipelines": ["cpu"], "steps": 65537, "repetitions": 65536}})"}}},
      {"sweep_model_name_joins", "experiment {dir}/x.json",
       "x.json.sweep.models[0].name: 's1__window-64' holds \"__\", which joins the parts of a cell's name",
       {{"x.json", R"({"sweep": {"models": [{"name": "s1__window-64", "model": {"file": "m.obj"}}], "pipelines": ["cpu"]}})"}}},
      {"experiment_integrator_beside_the_sweeps", "experiment {dir}/x.json",
       "x.json.integrator: unknown integrator 'bogus' (valid: ",
       {{"x.json", R"({"integrator": "bogus", "sweep": {"sizes": [8], "integrators": ["verlet"], "pipelines": ["cpu"]}})"}}},
      {"sweep_orders_without_models", "experiment {dir}/x.json", "x.json.sweep.orders: node orders go with models",
       {{"x.json", R"({"sweep": {"sizes": [8], "orders": ["rcm"], "pipelines": ["cpu"]}})"}}},
      {"sweep_order_unknown", "experiment {dir}/x.json", "x.json.sweep.orders: expected a list of: file, shuffled",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "m.obj"}}], "orders": ["hilbert"], "pipelines": ["cpu"]}})"}}},
      {"sweep_model_order_under_orders", "experiment {dir}/x.json",
       "x.json.sweep.models[0].model.order: the sweep's \"orders\" give every cell its order",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "m.obj", "order": "rcm"}}], "orders": ["file", "rcm"], "pipelines": ["cpu"]}})"}}},
      {"sweep_model_seed_unshuffled", "experiment {dir}/x.json",
       "x.json.sweep.models[0].model.seed: seeds the shuffled order, which the sweep's \"orders\" leave out",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "m.obj", "seed": 3}}], "orders": ["file", "rcm"], "pipelines": ["cpu"]}})"}}},
      {"sweep_model_name", "experiment {dir}/x.json", "x.json.sweep.models[0].name: expected a name of up to 64 letters",
       {{"x.json", R"({"sweep": {"models": [{"name": "a/b", "model": {"file": "m.obj"}}], "pipelines": ["cpu"]}})"}}},
      {"sweep_model_twice", "experiment {dir}/x.json", "x.json.sweep.models[1].name: model 'a' is named twice",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "m.obj"}}, {"name": "a", "model": {"file": "n.obj"}}], "pipelines": ["cpu"]}})"}}},
      {"sweep_model_key", "experiment {dir}/x.json", "x.json.sweep.models[0].model.generate.shape: expected",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"generate": {"shape": "cone", "size": [1, 1], "cell_size": 1}}}], "pipelines": ["cpu"]}})"}}},
      {"sweep_model_file_missing", "experiment {dir}/x.json", "x.json.sweep.models[0].model.file: '",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "none.obj"}}], "pipelines": ["cpu"]}})"}}},
      {"sweep_model_file_non_manifold", "experiment {dir}/x.json",
       "m.obj': edge 0-1 is shared by 3 triangles (non-manifold; node indices from 0, as pins take them)",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "m.obj", "pins": "none"}}], "pipelines": ["cpu"]}})"},
        {"m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 2 5\n"}}},
      {"sweep_model_pin_outside", "experiment {dir}/x.json", "x.json.sweep.models[0].model.pins[0]: node 99 is outside",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "m.obj", "pins": [99]}}], "pipelines": ["cpu"]}})"},
        {"m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}}},
      {"sweep_models_max_size", "experiment {dir}/x.json --max-size 8", "--max-size: this sweep has models",
       {{"x.json", R"({"sweep": {"models": [{"name": "a", "model": {"file": "m.obj"}}], "pipelines": ["cpu"]}})"}}},
      {"sweep_sizes_of_a_mesh", "experiment {dir}/x.json", "x.json.sweep.sizes: the scene's model is a mesh",
       {{"x.json", R"({"scene": {"model": {"type": "mesh", "file": "m.obj", "pins": "none"}, "drag": null},
                       "sweep": {"sizes": [4], "pipelines": ["cpu"]}})"},
        {"m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}}},
      {"run_experiment_bad_sweep", "run --experiment {dir}/x.json", "x.json.sweep: expected an object",
       {{"x.json", R"({"sweep": 5})"}}},
      {"experiment_base_empty", "run --experiment {dir}/x.json", "x.json.base: expected an experiment name",
       {{"x.json", R"({"base": ""})"}}},
      {"experiment_base_nul", "run --experiment {dir}/x.json", "x.json' holds a string with a NUL character in it (at base)",
       {{"x.json", R"({"base": "paper-drag\u0000x"})"}}},
      mesh("mesh_file_nul", R"({"file": "m.obj\u0000.txt"})", "s.json' holds a string with a NUL character in it (at model.file)"),
      {"experiment_without_a_name", "experiment '{dir}/first exp.json'",
       "first exp.json: has no \"name\", and its file name is not one (expected a name of up to 64 letters",
       {{"first exp.json", R"({"sweep": {"sizes": [8], "pipelines": ["cpu"]}})"}}},
      {"experiment_base_loop", "run --experiment {dir}/a.json", "experiments based on one another (a loop?)",
       {{"a.json", R"({"base": "{dir}/b.json"})"}, {"b.json", R"({"base": "{dir}/a.json"})"}}},
      {"experiment_base_unknown", "run --experiment {dir}/x.json",
       "x.json.base: no experiment file or built-in experiment 'paper-dragg'", {{"x.json", R"({"base": "paper-dragg"})"}}},
      {"sweep_integrator_of_the_experiment", "experiment {dir}/x.json", "x.json.integrator: unknown integrator 'rk5'",
       {{"x.json", R"({"integrator": "rk5", "sweep": {"sizes": [4], "pipelines": ["cpu"]}})"}}},
      {"drag_without_node", "run --experiment {dir}/x.json", "x.json.scene.drag: needs \"node\"",
       {{"x.json", R"({"scene": {"drag": {"path": [[0, 0, 0, 0]]}}})"}}},
      {"drag_without_path", "run --experiment {dir}/x.json", "x.json.scene.drag: needs \"path\"",
       {{"x.json", R"({"scene": {"drag": {"node": 0}}})"}}},
      {"experiment_name_path", "run --experiment {dir}/x.json", "x.json.name: expected a name of up to 64 letters",
       {{"x.json", R"({"name": "../escape"})"}}},
      {"experiment_name_empty", "experiment {dir}/x.json", "x.json.name: expected a name of up to 64 letters",
       {{"x.json", R"({"name": "", "sweep": {"sizes": [8], "pipelines": ["cpu"]}})"}}},
      scene("key_with_a_newline", "{\"d\\nt\": 1}", "s.json.d\\nt: unknown key"),
      // a folder holds one run's outputs or one experiment's results
      {"run_into_experiment_folder", "run --pipeline cpu --steps 3 --out {dir}",
       "holds an experiment's results: give this run another --out", {{"manifest.json", R"({"experiment": {"name": "quick"}})"}}},
      {"experiment_into_run_folder", "experiment quick --out {dir}", "holds a run's outputs: give this experiment another --out",
       {{"manifest.json", R"({"experiment": "paper-drag"})"}}},
      {"report_into_run_folder", "experiment quick --report-only --calibration {dir}/c.json --out {dir}",
       "holds a run's outputs", {{"manifest.json", R"({"experiment": "paper-drag"})"}, {"c.json", R"({"copy": {"GB_per_s": 5}})"}}},
      {"experiment_directory", "experiment {dir}", "is a directory, not a JSON file"},
      {"experiment_missing", "experiment {dir}/none.json", "cannot open experiment file"},
      {"experiment_unknown_name", "experiment nosuch", "no experiment file or built-in experiment 'nosuch' (built in: "},
      {"experiment_unknown_name_lists_scenes_apart", "experiment nosuch", "; without a sweep, for `run --experiment`: "
       "paper-drag)"},
      {"run_unknown_experiment", "run --experiment tabel2", "no experiment file or built-in experiment 'tabel2'"},
      {"report_max_size", "experiment quick --report-only --max-size 4", "--max-size limits the cells a run measures"},
      {"experiment_max_size_zero", "experiment quick --max-size 0", "--max-size: '0' is not in 1 to 1048576"},
      {"experiment_out_is_a_file", "experiment quick --out {dir}/f.txt", "exists and is not a folder", {{"f.txt", "x"}}},
      {"experiment_out_under_a_file", "experiment quick --out {dir}/f.txt/sub", "f.txt' is not a folder", {{"f.txt", "x"}}},
      {"experiment_out_empty", "experiment quick --out ''", "--out '': an empty path names no folder"},
      {"experiment_out_no_storage", "experiment quick --out /proc/deformlab-out", "'/proc' is on one of the kernel's file systems"},
      {"report_of_another_experiment", "experiment table2 --report-only --out {dir}", "holds experiment 'quick', not 'table2'",
       {{"manifest.json", R"({"experiment": {"name": "quick"}})"}}},
      {"calibration_missing", "experiment quick --calibration {dir}/none.json", "cannot open calibration file"},
      {"calibration_denormal", "experiment quick --calibration {dir}/c.json",
       "c.json.compute_copy.GB_per_s: expected a number from 0.001 to 1e+06", {{"c.json", R"({"compute_copy": {"GB_per_s": 5e-324}})"}}},
      {"calibration_text", "experiment quick --calibration {dir}/c.json",
       "c.json.copy.GB_per_s: expected a number from 0.001 to 1e+06", {{"c.json", R"({"copy": {"GB_per_s": "NaN"}})"}}},
      {"calibration_negative", "experiment quick --calibration {dir}/c.json",
       "c.json.floor.us_per_hand_off: expected a number from 0.001 to 1e+06",
       {{"c.json", R"({"copy": {"GB_per_s": 3000}, "floor": {"us_per_hand_off": -4}})"}}},
      {"calibration_not_an_object", "experiment quick --calibration {dir}/c.json", "c.json.copy: expected an object",
       {{"c.json", R"({"copy": 3000})"}}},
      // The report names these: a results folder's calibration they would break is refused before it is kept.
      {"calibration_device_text", "experiment quick --report-only --calibration {dir}/c.json --out {dir}/r",
       "c.json.device: expected an object whose \"name\" is text",
       {{"c.json", R"({"copy": {"GB_per_s": 100}, "device": "H100"})"}}},
      {"calibration_memory_number", "experiment quick --calibration {dir}/c.json",
       "c.json.compute_copy.memory: expected text (gl or cuda)",
       {{"c.json", R"({"copy": {"GB_per_s": 100}, "compute_copy": {"GB_per_s": 50, "memory": 7}})"}}},
      {"calibration_list", "experiment quick --calibration {dir}/c.json", "not a JSON object", {{"c.json", "[1, 2]"}}},
      {"calibration_empty", "experiment quick --calibration {dir}/c.json", "no ceilings in it",
       {{"c.json", "{\"copy\": {\"device\": \"none\"}}"}}},
  };
  return all;
}

class Refused : public Cli, public testing::WithParamInterface<BadInput> {};

TEST_P(Refused, WithOneLineAndNothingWritten) {
  const BadInput& c = GetParam();
  auto in_dir = [&](std::string text) {
    for (std::size_t at; (at = text.find("{dir}")) != std::string::npos;) text.replace(at, 5, dir_.string());
    return text;
  };
  std::vector<std::pair<fs::path, std::string>> files;
  for (const auto& [name, text] : c.files) {
    files.emplace_back(dir_ / name, in_dir(text));
    std::ofstream(files.back().first, std::ios::binary) << files.back().second;
  }
  expect_refused(in_dir(c.args), c.needle);
  for (const auto& [file, text] : files) EXPECT_EQ(slurp(file), text) << file << " changed";
}

TEST(BadInputTable, HasAtLeastSixtyRowsWithDistinctNames) {
  std::set<std::string> names;
  for (const BadInput& c : cases()) EXPECT_TRUE(names.insert(c.name).second) << c.name;
  EXPECT_GE(cases().size(), 60u);
}

INSTANTIATE_TEST_SUITE_P(Cli, Refused, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<BadInput>& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace deformlab::test
