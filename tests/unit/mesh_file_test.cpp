// Mesh files (mesh/load.hpp, mesh/scene_model.hpp): each format read through its library,
// counts against the mesh written, Gmsh volumes and filling, the committed bunny, scenes
// that pick nodes by position, and runs reported in the file's order whatever the internal one.
#include <gtest/gtest.h>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <gmsh.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <nlohmann/json.hpp>

#include "core/cpu_backend.hpp"
#include "core/scene.hpp"
#include "mesh/load.hpp"
#include "mesh/scene_model.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

namespace fs = std::filesystem;

class MeshFile : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("deformlab-mesh-" + std::to_string(::getpid()) + "-" +
                                        testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return (dir_ / name).string();
  }
  Mesh load(const std::string& path) {
    std::vector<std::string> notes;
    Mesh m = load_mesh(path, notes);
    notes_ = notes;
    return m;
  }
  fs::path dir_;
  std::vector<std::string> notes_;
};

// A 3 x 2 grid of squares as OBJ quads: assimp splits them into triangles.
const char* kQuads = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 0 0 1\nv 1 0 1\nv 2 0 1\nv 3 0 1\n"
                     "v 0 0 2\nv 1 0 2\nv 2 0 2\nv 3 0 2\n"
                     "f 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 5 9 10 6\nf 6 10 11 7\nf 7 11 12 8\n";

TEST_F(MeshFile, ObjPolygonsBecomeTriangles) {
  Mesh m = load(write("q.obj", kQuads));
  EXPECT_EQ(m.position.size(), 12u);
  EXPECT_EQ(m.triangle.size(), 12u);
  EXPECT_TRUE(repair(m).empty());
  const Model model = mesh_model(m, Material{}, 0.f);
  EXPECT_EQ(model.spring_count(), 17 + 6 + (17 + 6 - 10));  // 17 grid edges + 6 diagonals, bending on interior edges
}

// The `v` lines assimp's OBJ reader keeps pass the check for those it skips (read_guards.hpp):
// w and vertex colours, tabs, signs before a point, a comment, a line continued, CR line ends.
TEST_F(MeshFile, ObjVertexLinesAssimpKeepsAreRead) {
  Mesh m = load(write("k.obj", "v 0 0 0 1\nv\t1\t0\t0\nv 0 1 0 0.5 0.5 0.5\nv -.5 +.5 0 # a note\nv 1 \\\n1 0\n"
                               "f 1 2 3\nf 2 5 3\nf 1 3 4\n"));
  std::vector<std::array<float, 3>> got;
  for (const Vec3f& p : m.position) got.push_back({p.x, p.y, p.z});
  std::sort(got.begin(), got.end());
  const std::vector<std::array<float, 3>> want = {{-0.5f, 0.5f, 0.f}, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}};
  EXPECT_EQ(got, want);
  EXPECT_EQ(m.triangle.size(), 3u);
  // Lines that end in a carriage return alone.
  EXPECT_EQ(load(write("cr.obj", "v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r")).position.size(), 3u);
}

TEST_F(MeshFile, ObjectsSharingPositionsAreWeldedAndCounted) {
  Mesh m = load(write("two.obj", "o a\nv 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n"
                                 "o b\nv 1 0 0\nv 0 0 1\nv 1 0 1\nf 4 6 5\n"));
  EXPECT_EQ(m.position.size(), 6u);
  EXPECT_EQ(repair(m), std::vector<std::string>{"welded 2 duplicate vertices"});
  EXPECT_EQ(m.position.size(), 4u);
  EXPECT_EQ(mesh_model(m, Material{}, 0.f).spring_count(), 5 + 1);  // 5 edges, one bending pair
}

// A PLY lists vertices no face uses; the reader's joining of identical vertices drops them,
// and they are counted as repair() counts those it drops.
TEST_F(MeshFile, UnreferencedVerticesOfAPlyAreCounted) {
  Mesh m = load(write("u.ply", "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                               "9 9 9\n0 0 0\n1 0 0\n0 1 0\n5 5 5\n3 1 2 3\n"));
  EXPECT_EQ(m.position.size(), 3u);
  EXPECT_EQ(notes_, std::vector<std::string>{"dropped 2 unreferenced vertices"});
}

// A PLY's element counts against the bytes after its header: values of one character and one
// blank each, the last without, are read; one byte fewer is refused before assimp reads it.
TEST_F(MeshFile, PlyCountsAreCheckedAgainstTheLeastBytesTheyTake) {
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3";  // 25 bytes, 4 x 3 + 1 values: 2 x 13 - 1
  EXPECT_NO_THROW(load(write("at.ply", header + body)));  // (assimp takes the face's missing indices as 0)
  try {
    load(write("short.ply", header + body.substr(1)));
    ADD_FAILURE() << "read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("whose values take at least 25 bytes, where 24 follow the header"),
              std::string::npos) << e.what();
  }
}

// Files that the guards before the readers must let through: a PLY whose lines end in a lone CR
// (assimp reads them as line ends), and a .msh that starts with $Comments (Gmsh reads it as a
// mesh too).
TEST_F(MeshFile, UnusualFilesTheReadersTakeAreRead) {
  struct Case {
    const char* name;
    std::string text;
    std::size_t nodes, elements;
  };
  for (const Case& c : {Case{"cr.ply",
                             "ply\rformat ascii 1.0\relement vertex 3\rproperty float x\rproperty float y\r"
                             "property float z\relement face 1\rproperty list uchar int vertex_indices\r"
                             "end_header\r0 0 0\r1 0 0\r0 1 0\r3 0 1 2\r",
                             3, 1},
                        Case{"c.msh",
                             "$Comments\nfrom a mesher\n$EndComments\n$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                             "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                             "$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n",
                             4, 1}}) {
    const Mesh m = load(write(c.name, c.text));
    EXPECT_EQ(m.position.size(), c.nodes) << c.name;
    EXPECT_EQ(m.triangle.size() + m.tetrahedron.size(), c.elements) << c.name;
  }
}

// An STL repeats each vertex per facet: those at one position (0 and -0 alike) are joined
// without a repair, and vertices 5e-6 apart stay apart (assimp's own joining took them for one).
TEST_F(MeshFile, StlVerticesJoinOnlyAtOnePosition) {
  auto facet = [](const char* a, const char* b, const char* c) {
    return std::string("facet normal 0 0 1\nouter loop\nvertex ") + a + "\nvertex " + b + "\nvertex " + c +
           "\nendloop\nendfacet\n";
  };
  Mesh m = load(write("j.stl", "solid j\n" + facet("0 0 0", "1 0 0", "-0 1 0") + facet("1 0 0", "1 1 0", "0 1 0") +
                                   "endsolid j\n"));
  EXPECT_EQ(m.position.size(), 4u);
  EXPECT_EQ(m.triangle.size(), 2u);
  EXPECT_TRUE(notes_.empty());
  EXPECT_TRUE(repair(m).empty());
  EXPECT_EQ(m.position[2], (Vec3f{0, 1, 0}));
  EXPECT_FALSE(std::signbit(m.position[2].x));

  Mesh fine = load(write("f.stl", "solid f\n" + facet("0 0 1", "0.000005 0 1", "0 0.000005 1") + "endsolid f\n"));
  EXPECT_EQ(fine.position.size(), 3u);
  EXPECT_TRUE(repair(fine).empty());
}

// A line left out does not add its vertices: nodes keep the order in which faces use them.
TEST_F(MeshFile, ALineLeftOutAddsNoNodes) {
  Mesh m = load(write("l.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 2 2\nf 1 2 3\nl 3 4\n"));
  EXPECT_EQ(m.position.size(), 3u);
  EXPECT_EQ(m.position[0], (Vec3f{0, 0, 0}));
  EXPECT_EQ(notes_, std::vector<std::string>{"left out 0 points and 1 lines"});
  EXPECT_TRUE(repair(m).empty());
}

// An object split by assimp (an OBJ's materials, a glTF mesh's primitives over one accessor)
// is one object: its vertices are joined, not welded, and none of them is unreferenced.
TEST_F(MeshFile, AnObjectSplitByMaterialOrPrimitiveIsOneObject) {
  Mesh obj = load(write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl red\nf 1 2 3\nusemtl blue\nf 2 4 3\n"));
  EXPECT_EQ(obj.position.size(), 4u);
  EXPECT_TRUE(notes_.empty());
  EXPECT_TRUE(repair(obj).empty());
  Mesh gltf = load(write("p.gltf", R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1},
                                                       {"attributes": {"POSITION": 0}, "indices": 2}]}],
    "buffers": [{"uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAACAPwAAgD8AAAAAAAABAAIAAQADAAIA",
                 "byteLength": 60}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                  {"bufferView": 1, "byteOffset": 0, "componentType": 5123, "count": 3, "type": "SCALAR"},
                  {"bufferView": 1, "byteOffset": 6, "componentType": 5123, "count": 3, "type": "SCALAR"}]})"));
  EXPECT_EQ(gltf.position.size(), 4u);
  EXPECT_EQ(gltf.triangle.size(), 2u);
  EXPECT_TRUE(notes_.empty()) << notes_.front();
  EXPECT_TRUE(repair(gltf).empty());
}

TEST_F(MeshFile, PlyStlAndGltfGiveTheObjsMesh) {
  // The same closed surface (a tetrahedron) exported by assimp in each format, read back.
  const std::string obj = write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(obj, 0);
  ASSERT_NE(scene, nullptr);
  Assimp::Exporter exporter;
  for (const auto& [id, ext] : {std::pair{"plyb", "ply"}, {"stl", "stl"}, {"stlb", "stl"}, {"gltf2", "gltf"}, {"glb2", "glb"}}) {
    const std::string file = (dir_ / (std::string("t_") + id + "." + ext)).string();
    ASSERT_EQ(exporter.Export(scene, id, file), aiReturn_SUCCESS) << exporter.GetErrorString();
    Mesh m = load(file);
    repair(m);
    EXPECT_EQ(m.position.size(), 4u) << id;
    EXPECT_EQ(m.triangle.size(), 4u) << id;
    EXPECT_EQ(mesh_model(m, Material{}, 0.f).spring_count(), 6) << id << ": 6 edges; bending pairs are edges";
  }
}

TEST_F(MeshFile, BrokenFilesAreRefusedWithTheFileName) {
  auto error = [&](const std::string& name, const std::string& text) {
    try {
      Scene s;
      apply_json(s, nlohmann::json{{"model", {{"type", "mesh"}, {"file", name}, {"pins", "none"}}}}, "s", dir_.string());
      if (!text.empty() || name != "none.obj") write(name, text);
      build_model(s);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string at = "mesh file '" + (dir_ / "").string();
  EXPECT_EQ(error("none.obj", ""), at + "none.obj': no such file");
  std::filesystem::create_symlink("loop.obj", dir_ / "loop.obj");  // a link to itself: named as such
  Scene loop;
  apply_json(loop, nlohmann::json{{"model", {{"type", "mesh"}, {"file", "loop.obj"}, {"pins", "none"}}}}, "s", dir_.string());
  try {
    build_model(loop);
    ADD_FAILURE() << "a link loop was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), at + "loop.obj': Too many levels of symbolic links");
  }
  EXPECT_EQ(error("e.obj", ""), at + "e.obj': the file is empty");
  EXPECT_EQ(error("n.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), at + "n.obj': a vertex has a NaN or infinite coordinate (nan, 0, 0)");
  EXPECT_EQ(error("l.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n"), at + "l.obj': no triangles");
  std::string stl(80, ' ');
  stl += std::string("\x0c\0\0\0", 4) + std::string(50, '\0');  // 12 triangles announced, one there
  EXPECT_EQ(error("cut.stl", stl).rfind(at + "cut.stl': ", 0), 0u);
  // A glTF face with an index out of range: assimp drops it and says so only in its log.
  EXPECT_EQ(error("oor.gltf", R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "buffers": [{"uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAACAPwAAgD8AAAAAAAABAAIAAQADAAkA",
                 "byteLength": 60}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}]})"),
            at + "oor.gltf': assimp: Some faces had out-of-range indices. Those faces were dropped.");
  EXPECT_EQ(error("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "accepted");
}

// Files a mesh names (an OBJ's material library, a glTF's buffer) are opened only where they
// are regular files: a FIFO there blocked the read for ever.
TEST_F(MeshFile, FilesAMeshNamesAreOpenedOnlyWhereRegular) {
  ASSERT_EQ(mkfifo((dir_ / "fifo.bin").c_str(), 0600), 0);
  EXPECT_EQ(load(write("m.obj", "mtllib fifo.bin\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).triangle.size(), 1u);
  const std::string gltf = write("m.gltf", R"({"asset": {"version": "2.0"}, "buffers": [{"uri": "fifo.bin", "byteLength": 36}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}], "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3,
    "type": "VEC3", "max": [1, 1, 0], "min": [0, 0, 0]}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})");
  try {
    load(gltf);
    ADD_FAILURE() << "read";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "mesh file '" + gltf + "': assimp: GLTF: could not open referenced file \"fifo.bin\"");
  }
}

// A 0.3 x 0.2 x 0.1 m box meshed by Gmsh and written as .msh (binary where asked).
void write_gmsh_box(const std::string& msh, bool binary) {
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("Mesh.Binary", binary);
  gmsh::model::add("box");
  gmsh::model::occ::addBox(0, 0, 0, 0.3, 0.2, 0.1);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.05);
  gmsh::model::mesh::generate(3);
  gmsh::write(msh);
  gmsh::finalize();
}

// The box read back: linear tetrahedra, the box's volume.
TEST_F(MeshFile, GmshVolumesAreRead) {
  const std::string msh = (dir_ / "box.msh").string();
  write_gmsh_box(msh, false);
  Mesh m = load(msh);
  ASSERT_TRUE(m.volume());
  EXPECT_TRUE(notes_.empty()) << notes_.front();  // the box's boundary triangles are its tetrahedra's faces
  EXPECT_TRUE(repair(m).empty());
  const Model model = mesh_model(m, Material{}, 1000.f);
  double mass = 0;
  for (float w : model.inv_mass) mass += 1.0 / w;
  EXPECT_NEAR(mass, 1000.0 * 0.3 * 0.2 * 0.1, 1e-3);
  EXPECT_GT(std::count(model.kind.begin(), model.kind.end(), SpringKind::flexion), 0);
}

// A volume with a sheet beside it: the sheet's triangles, which bound no tetrahedron, are left
// out and counted (its nodes are then unreferenced, and repair drops them).
TEST_F(MeshFile, AVolumesTrianglesThatBoundNoTetrahedronAreCounted) {
  const std::string msh = (dir_ / "box-and-sheet.msh").string();
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("box-and-sheet");
  gmsh::model::occ::addBox(0, 0, 0, 0.3, 0.2, 0.1);
  const int sheet = gmsh::model::occ::addRectangle(0, 0, 0.5, 0.3, 0.2);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.05);
  gmsh::model::mesh::generate(3);
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> tags, nodes;
  gmsh::model::mesh::getElements(types, tags, nodes, 2, sheet);
  ASSERT_EQ(types, std::vector<int>{2});
  const std::size_t sheet_triangles = tags[0].size();
  gmsh::write(msh);
  gmsh::finalize();
  Mesh m = load(msh);
  ASSERT_TRUE(m.volume());
  EXPECT_GT(sheet_triangles, 10u);
  EXPECT_EQ(notes_, std::vector<std::string>{"left out " + std::to_string(sheet_triangles) +
                                             " triangles that bound no tetrahedron"});
}

// Gmsh and assimp trust a file's counts: a damaged one could crash them or take all memory.
// Each is read in a child process (mesh/child_read.hpp), so any damage ends in a mesh or one line.
TEST_F(MeshFile, DamagedFilesEndInAMeshOrOneLine) {
  const std::string msh = (dir_ / "box.msh").string();
  write_gmsh_box(msh, true);
  std::string bytes;
  {
    std::ifstream in(msh, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  // MSH 4.1's binary $Nodes section opens with four 8-byte counts: blocks, nodes, least and
  // largest tag. A node count 2^36 too large asks for terabytes.
  std::string huge = bytes;
  const std::size_t nodes = huge.find("$Nodes\n") + 7 + 8;
  huge[nodes + 4] = char(huge[nodes + 4] | 0x10);
  const std::string error = [&] {
    try {
      load(write("huge.msh", huge));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("read");
  }();
#if defined(__SANITIZE_ADDRESS__)
  EXPECT_EQ(error.rfind("mesh file '" + (dir_ / "huge.msh").string() + "': ", 0), 0u) << error;
#else
  EXPECT_EQ(error, "mesh file '" + (dir_ / "huge.msh").string() +
                       "': reading it took more than the 2 GiB of memory allowed for a file of its size (damaged counts? "
                       "DEFORMLAB_MESH_READ_GIB=N allows N GiB)");
#endif
  // Cut short and overwritten at random (a fixed seed): each a mesh or std::invalid_argument.
  std::mt19937 random(7);
  int cut_refused = 0;
  for (int k = 0; k < 40; ++k) {
    std::string damaged = bytes;
    const bool cut = k % 2;
    if (cut) {
      damaged.resize(random() % damaged.size());
    } else {
      for (int b = 0; b < 4; ++b) damaged[random() % damaged.size()] = char(random());
    }
    try {
      load(write("damaged.msh", damaged));
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("mesh file '", 0), 0u) << e.what();
      cut_refused += cut;
    }
  }
  EXPECT_EQ(cut_refused, 20) << "every file cut short is refused";
}

// An open surface bounds no volume: one line that says so, not Gmsh's own message.
TEST_F(MeshFile, AnOpenSurfaceIsNotFilled) {
  Mesh quad;
  quad.position = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
  quad.triangle = {{0, 1, 2}, {0, 2, 3}};
  try {
    fill_tetrahedra(quad, 0.f);
    ADD_FAILURE() << "an open surface was filled";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "Gmsh made no tetrahedra (is the surface closed?)");
  }
}

// A Gmsh file is one by its extension in any case.
TEST_F(MeshFile, AnUpperCaseMshIsGmshs) {
  const std::string msh = (dir_ / "BOX.MSH").string();
  write_gmsh_box((dir_ / "box.msh").string(), false);  // Gmsh writes by the extension in lower case
  fs::rename(dir_ / "box.msh", msh);
  EXPECT_TRUE(load(msh).volume());
}

TEST_F(MeshFile, TheBunnyIsClosedAndFillsWithTetrahedra) {
  Mesh surface = load(DEFORMLAB_SOURCE_DIR "/data/bunny/bunny.obj");
  EXPECT_TRUE(repair(surface).empty());
  EXPECT_EQ(surface.position.size(), 1839u);
  EXPECT_EQ(surface.triangle.size(), 3674u);
  const Model s = mesh_model(surface, Material{}, 0.f);
  // Closed and of genus 0: V - E + F = 2, and every edge is interior.
  const auto edges = std::count(s.kind.begin(), s.kind.end(), SpringKind::structural);
  EXPECT_EQ(1839 - edges + 3674, 2);
  Mesh volume = fill_tetrahedra(surface, 0.f);
  EXPECT_TRUE(repair(volume).empty());
  const Model v = mesh_model(volume, Material{}, 1.f);
  EXPECT_GE(v.node_count(), 1839);
  EXPECT_EQ(v.triangle.size(), 3u * 3674) << "the boundary is the bunny's surface";
  double filled = 0;
  for (float w : v.inv_mass) filled += 1.0 / w;  // density 1: the volume
  // The divergence theorem on the surface gives its enclosed volume.
  double enclosed = 0;
  for (const auto& t : surface.triangle)
    enclosed += dot(Vec3d(surface.position[t[0]]), cross(Vec3d(surface.position[t[1]]), Vec3d(surface.position[t[2]]))) / 6.0;
  EXPECT_NEAR(filled, std::abs(enclosed), 1e-4 * std::abs(enclosed));
}

// deformlab mesh's filled meshes: a surface filled with tetrahedra and written out reads back
// as the same mesh, and a model naming that file without "fill", "scale" and "transform" is
// built from it node for node.
TEST_F(MeshFile, AFilledMeshWrittenOutBuildsTheSameModel) {
  Scene filling;
  apply_json(filling, nlohmann::json::parse(R"({"model": {"type": "mesh", "file": ")" DEFORMLAB_SOURCE_DIR
                                            R"(/data/bunny/bunny.obj", "scale": 0.02,
      "transform": {"translate": [0.03, 0.3, 0]}, "fill": "tetrahedra", "density": 1000, "pins": "none"}})"),
             "s", dir_.string());
  const fs::path file = dir_ / "meshes" / "soft.msh";
  const Mesh filled = filled_mesh(filling.model.mesh, file.string());
  ASSERT_TRUE(filled.volume());
  EXPECT_GT(filled.position.size(), 1839u) << "the surface's nodes and the interior's";
  const Mesh read = load(file.string());
  EXPECT_EQ(read.position, filled.position);
  EXPECT_EQ(read.tetrahedron, filled.tetrahedron);
  EXPECT_FALSE(fs::exists(dir_ / "meshes" / ".soft.msh.partial.msh"));

  Scene reading;
  apply_json(reading, nlohmann::json::parse(R"({"model": {"type": "mesh", "file": "meshes/soft.msh", "density": 1000,
      "pins": "none"}})"), "s", dir_.string());
  const Model m = build_model(reading);
  ASSERT_EQ(m.node_count(), int(filled.position.size()));
  for (int v = 0; v < m.node_count(); ++v) ASSERT_EQ(m.rest_position[v], filled.position[v]) << v;
  EXPECT_THROW(filled_mesh(reading.model.mesh, (dir_ / "x.msh").string()), std::logic_error);
}

// One scene in two node orders: the pins and the drag node are the same nodes, and the
// trajectories agree node by node in the file's order.
TEST_F(MeshFile, NodeOrderChangesNothingButSpeed) {
  write("sheet.obj", kQuads);
  auto scene = [&](const char* order) {
    Scene s;
    apply_json(s, nlohmann::json::parse(std::string(R"({"model": {"type": "mesh", "file": "sheet.obj", "scale": 0.1,
        "order": ")") + order + R"(", "pins": [{"box": [[-1, -1, -1], [0.01, 1, 1]]}]},
        "dt": 0.001, "ground": null, "spheres": [], "drag": {"node": {"nearest": [0.3, 0, 0.2]}, "path": [[0, 0, 0, 0], [1, 0, 0.1, 0]]}})"),
               "s", dir_.string());
    return s;
  };
  const Scene a = scene("file"), b = scene("shuffled");
  const Model ma = build_model(a), mb = build_model(b);
  const Params pa = resolve_params(a, ma), pb = resolve_params(b, mb);
  EXPECT_EQ(mb.file_index(pb.drag.node), pa.drag.node);
  EXPECT_EQ(ma.rest_position[pa.drag.node], (Vec3f{0.3f, 0.f, 0.2f}));
  int pins = 0;
  for (int v = 0; v < mb.node_count(); ++v) {
    EXPECT_EQ(mb.pinned(v), ma.pinned(mb.file_index(v)));
    EXPECT_EQ(ma.pinned(v), ma.rest_position[v].x == 0.f);
    pins += ma.pinned(v);
  }
  EXPECT_EQ(pins, 3);
  auto run = [](const Model& m, const Params& p) {
    auto cpu = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler, {}}, Precision::f64, false);
    return advance(*cpu, rest_state(m), 100);
  };
  const State sa = run(ma, pa), sb = run(mb, pb);
  double d = 0;
  for (int v = 0; v < mb.node_count(); ++v) d = std::max(d, double(norm(sb.x[v] - sa.x[mb.file_index(v)])));
  EXPECT_LT(d, 1e-6);
  EXPECT_GT(max_position_diff(sa, rest_state(ma)), 1e-3) << "the sheet must move";
}

}  // namespace
}  // namespace deformlab::test
