#include "load.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/DefaultLogger.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/Importer.hpp>
#include <assimp/commonMetaData.h>
#include <assimp/importerdesc.h>
#include <assimp/metadata.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>
#include <gmsh.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "child_read.hpp"
#include "gmsh_session.hpp"
#include "read_guards.hpp"

namespace deformlab {

namespace {

// What assimp refused, after "assimp:", its runs of spaces made one (it names a mesh without
// a name as "Mesh  contains no faces").
[[noreturn]] void refused_by_assimp(const std::string& file, const Assimp::Importer& importer) {
  std::string why;
  for (const char* c = importer.GetErrorString(); *c; ++c)
    if (!(*c == ' ' && !why.empty() && why.back() == ' ')) why += *c;
  // assimp's words for an OBJ `f` line of one or two vertices among an object's polygons.
  if (why.find("is a LINE but") != std::string::npos || why.find("is a POINT but") != std::string::npos)
    why += " (a face of fewer than 3 vertices among polygons: an OBJ writes lines with `l`, points with `p`)";
  bad_mesh_file(file, "assimp: " + why);
}

// assimp also opens the files a mesh names (an OBJ's mtllib, a glTF's buffers): regular files
// only, so that a FIFO or a device named there cannot block the read.
// (Its Exists opens the file too.)
class RegularFilesOnly : public Assimp::DefaultIOSystem {
 public:
  bool Exists(const char* file) const override { return regular(file); }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    return regular(file) ? DefaultIOSystem::Open(file, mode) : nullptr;
  }

 private:
  static bool regular(const char* file) {
    std::error_code ec;
    return std::filesystem::is_regular_file(file, ec);
  }
};

// f(node) for each node of the file's scene graph: its objects. assimp splits an object into a
// mesh per material (OBJ) or per primitive (glTF), all of them under its node.
template <class F>
void for_each_object(const aiScene& scene, F f) {
  std::vector<const aiNode*> todo{scene.mRootNode};
  while (!todo.empty()) {
    const aiNode* n = todo.back();
    todo.pop_back();
    f(*n);
    todo.insert(todo.end(), n->mChildren, n->mChildren + n->mNumChildren);
  }
}

Vec3f position_of(const aiVector3D& p) { return {p.x, p.y, p.z}; }

std::int64_t distinct_positions(const std::vector<Vec3f>& p) {
  const std::vector<std::int32_t> first = first_at_same_position(p);
  std::int64_t n = 0;
  for (std::size_t v = 0; v < p.size(); ++v) n += first[v] == std::int32_t(v);
  return n;
}

// The positions of an object's vertices that no face of it uses, over its meshes (none, at
// once, where every vertex is used).
std::int64_t unused_positions(const aiScene& scene, const aiNode& object) {
  std::vector<Vec3f> all, used;
  bool some_unused = false;
  for (unsigned k = 0; k < object.mNumMeshes; ++k) {
    const aiMesh& a = *scene.mMeshes[object.mMeshes[k]];
    std::vector<char> is_used(a.mNumVertices);
    for (unsigned f = 0; f < a.mNumFaces; ++f)
      for (unsigned i = 0; i < a.mFaces[f].mNumIndices; ++i)
        if (a.mFaces[f].mIndices[i] < a.mNumVertices) is_used[a.mFaces[f].mIndices[i]] = 1;
    for (unsigned v = 0; v < a.mNumVertices; ++v) {
      all.push_back(position_of(a.mVertices[v]));
      if (is_used[v]) used.push_back(all.back());
      some_unused |= !is_used[v];
    }
  }
  return some_unused ? distinct_positions(all) - distinct_positions(used) : 0;
}

// Appends the triangles of an object's meshes to `m` with the vertices they use, those at one
// position once (0 and -0 as 0), in the order of its meshes and their first indices; counts
// the points and lines left out. (assimp's own aiProcess_JoinIdenticalVertices also joins
// vertices within about 1e-5 of a file unit, which turns a fine mesh's small triangles into
// degenerate ones.)
void append_object(const std::string& path, const aiScene& scene, const aiNode& object, Mesh& m,
                   std::int64_t& points, std::int64_t& lines) {
  std::vector<Vec3f> p;
  std::vector<std::vector<std::int32_t>> at(object.mNumMeshes);  // each mesh vertex's place in p
  for (unsigned k = 0; k < object.mNumMeshes; ++k) {
    const aiMesh& a = *scene.mMeshes[object.mMeshes[k]];
    if (!(a.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) {  // points or lines (SortByPType): no nodes
      for (unsigned f = 0; f < a.mNumFaces; ++f) ++(a.mFaces[f].mNumIndices == 2 ? lines : points);
      continue;
    }
    if (std::int64_t(p.size()) + a.mNumVertices > std::numeric_limits<std::int32_t>::max())
      bad_mesh_file(path, "more than 2^31 vertices before joining those at one position");
    at[k].assign(a.mNumVertices, -1);
    for (unsigned f = 0; f < a.mNumFaces; ++f)
      for (unsigned i = 0; i < 3; ++i) at[k][a.mFaces[f].mIndices[i]] = 0;
    for (unsigned v = 0; v < a.mNumVertices; ++v)
      if (at[k][v] == 0) {
        at[k][v] = std::int32_t(p.size());
        p.push_back(position_of(a.mVertices[v]) + Vec3f{});  // -0 + 0 is 0
      }
  }
  const std::vector<std::int32_t> first = first_at_same_position(p);
  std::vector<std::int32_t> node(p.size());
  for (std::size_t e = 0; e < p.size(); ++e) {
    if (first[e] != std::int32_t(e)) {
      node[e] = node[std::size_t(first[e])];
    } else {
      node[e] = std::int32_t(m.position.size());
      m.position.push_back(p[e]);
    }
  }
  if (m.position.size() > (std::size_t(1) << 30)) bad_mesh_file(path, "more than 2^30 vertices");
  for (unsigned k = 0; k < object.mNumMeshes; ++k) {
    const aiMesh& a = *scene.mMeshes[object.mMeshes[k]];
    if (at[k].empty()) continue;
    for (unsigned f = 0; f < a.mNumFaces; ++f) {
      auto corner = [&](int c) { return node[std::size_t(at[k][a.mFaces[f].mIndices[c]])]; };
      m.triangle.push_back({corner(0), corner(1), corner(2)});
    }
  }
}

// assimp reads on past some faults of a file, and says so only in its log: it clamps an OFF
// face's index out of range, and drops a glTF's faces with one or its vertices beyond a whole
// triangle. The first of those lines of its log while it reads, kept to refuse the file with
// (other lines that say "out of range" or "dropped" are of what is not read: materials,
// colours, lines).
class DataLost : public Assimp::LogStream {
 public:
  DataLost() {
    Assimp::DefaultLogger::create("", Assimp::Logger::NORMAL, 0);
    Assimp::DefaultLogger::get()->attachStream(this, Assimp::Logger::Warn | Assimp::Logger::Err);
  }
  ~DataLost() override {
    Assimp::DefaultLogger::get()->detachStream(this, Assimp::Logger::Warn | Assimp::Logger::Err);
    Assimp::DefaultLogger::kill();
  }
  void write(const char* message) override {
    const std::string m = message;
    if (first.empty() && (m.find("Vertex index is out of range") != std::string::npos ||
                          m.find("faces had out-of-range indices") != std::string::npos ||
                          m.find("not compatible with the TRIANGLES mode") != std::string::npos))
      first = m.substr(m.find(": ") == std::string::npos ? 0 : m.find(": ") + 2);
  }
  std::string first;  // without assimp's "Warn, T0: " and its line end
};

Mesh load_with_assimp(const std::string& path, std::vector<std::string>& notes) {
  DataLost lost;
  Assimp::Importer importer;
  require_ply_header(path, importer);
  importer.SetIOHandler(new RegularFilesOnly);  // the importer owns it
  // Positions only: the other components are dropped before the other steps.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                                          aiComponent_COLORS | aiComponent_TEXCOORDS |
                                                          aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                                          aiComponent_TEXTURES | aiComponent_LIGHTS |
                                                          aiComponent_CAMERAS | aiComponent_MATERIALS);
  // Meshes kept under their objects: vertices shared across objects are left for repair() to
  // weld and count.
  importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
  // Read first and checked for coordinates that are not finite, those of vertices no face uses
  // too, then processed.
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  // Read by the OBJ reader, as it says, or (refused) named as OBJ: checked for the lines the
  // reader skipped, which may be why it refused the file.
  aiString format;
  const aiImporterDesc* obj_reader = importer.GetImporterInfo(importer.GetImporterIndex(".obj"));
  const bool obj = scene ? scene->mMetaData && scene->mMetaData->Get(AI_METADATA_SOURCE_FORMAT, format) &&
                               obj_reader && std::string(format.C_Str()) == obj_reader->mName
                         : extension_of(path) == ".obj";
  if (obj) require_obj_lines_read(path);
  if (!scene) refused_by_assimp(path, importer);
  if (!lost.first.empty()) {
    while (!lost.first.empty() && std::isspace(static_cast<unsigned char>(lost.first.back()))) lost.first.pop_back();
    bad_mesh_file(path, "assimp: " + lost.first);
  }
  for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
    const aiMesh* a = scene->mMeshes[k];
    for (unsigned v = 0; v < a->mNumVertices; ++v)
      if (const Vec3f p = position_of(a->mVertices[v]); !finite_vertex(p)) bad_mesh_file(path, non_finite_vertex(p));
  }
  // Positions no face uses are left out below: counted here, an object at a time.
  std::int64_t unused = 0;
  for_each_object(*scene, [&](const aiNode& object) { unused += unused_positions(*scene, object); });
  if (unused) notes.push_back("dropped " + std::to_string(unused) + " unreferenced vertices");
  scene = importer.ApplyPostProcessing(aiProcess_RemoveComponent | aiProcess_Triangulate |
                                       aiProcess_PreTransformVertices | aiProcess_SortByPType |
                                       aiProcess_ValidateDataStructure);
  if (!scene) refused_by_assimp(path, importer);
  Mesh m;
  std::int64_t points = 0, lines = 0;
  // Objects in the order of their first meshes.
  std::vector<const aiNode*> object(scene->mNumMeshes, scene->mRootNode);  // each mesh's
  for_each_object(*scene, [&](const aiNode& n) {
    for (unsigned k = 0; k < n.mNumMeshes; ++k) object[n.mMeshes[k]] = &n;
  });
  std::unordered_set<const aiNode*> appended;
  for (const aiNode* o : object)
    if (appended.insert(o).second) append_object(path, *scene, *o, m, points, lines);
  if (points || lines)
    notes.push_back("left out " + std::to_string(points) + " points and " + std::to_string(lines) + " lines");
  if (m.triangle.empty()) bad_mesh_file(path, "no triangles");
  return m;
}

// How many of `triangles` are no face of a tetrahedron of `m` (a volume): the triangles sorted
// (each by its vertices, then all), each tetrahedron's faces looked up among them.
std::int64_t triangles_bounding_no_tetrahedron(const Mesh& m, std::vector<std::array<std::int32_t, 3>> triangles) {
  std::vector<char> on_one(m.position.size());  // the nodes of the triangles
  for (auto& f : triangles) {
    std::sort(f.begin(), f.end());
    for (std::int32_t v : f) on_one[std::size_t(v)] = 1;
  }
  std::sort(triangles.begin(), triangles.end());
  std::vector<char> bounds(triangles.size());
  for (const auto& t : m.tetrahedron) {
    if (on_one[t[0]] + on_one[t[1]] + on_one[t[2]] + on_one[t[3]] < 3) continue;  // most: none of its faces
    for (int skip = 0; skip < 4; ++skip) {
      std::array<std::int32_t, 3> f;
      for (int c = 0, o = 0; c < 4; ++c)
        if (c != skip) f[o++] = t[c];
      std::sort(f.begin(), f.end());
      const auto [lo, hi] = std::equal_range(triangles.begin(), triangles.end(), f);
      std::fill(bounds.begin() + (lo - triangles.begin()), bounds.begin() + (hi - triangles.begin()), 1);
    }
  }
  return std::count(bounds.begin(), bounds.end(), 0);
}

}  // namespace

namespace {

// Whether a .msh file Gmsh wrote ends with its last section's end tag: Gmsh does not say when a
// write fails (on a full disk it left an empty file).
bool ends_whole(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  const std::streamoff size = in.tellg();
  std::string tail(64, '\0');
  const std::streamoff n = std::min<std::streamoff>(std::max<std::streamoff>(size, 0), std::streamoff(tail.size()));
  in.seekg(size - n);
  in.read(tail.data(), std::streamsize(n));
  return in && tail.find("$EndElements") != std::string::npos;
}

}  // namespace

void write_gmsh_model(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path to(path);
  std::string name = to.filename().string();
  name.insert(0, 1, '.');
  const fs::path partial = to.parent_path() / (name += ".partial.msh");
  gmsh::option::setNumber("Mesh.Binary", 1);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  std::error_code ec;
  try {
    if (!to.parent_path().empty()) fs::create_directories(to.parent_path());
    gmsh::write(partial.string());
    if (!ends_whole(partial)) {
      fs::remove(partial, ec);
      throw WriteError("writing '" + path + "': the file came out short (is the disk full?)");
    }
    fs::rename(partial, to);
  } catch (const WriteError&) {
    throw;
  } catch (const fs::filesystem_error& e) {
    fs::remove(partial, ec);
    throw WriteError("writing '" + path + "': " + e.code().message());
  } catch (...) {
    fs::remove(partial, ec);
    std::string error;
    gmsh::logger::getLastError(error);
    throw WriteError("writing '" + path + "': " + (error.empty() ? "Gmsh failed" : error));
  }
}

Mesh read_gmsh_model(const std::string& what, std::vector<std::string>* notes) {
  std::vector<std::size_t> tags;
  std::vector<double> coord, param;
  gmsh::model::mesh::getNodes(tags, coord, param, -1, -1, false, false);
  Mesh m;
  if (tags.size() > (std::size_t(1) << 30)) throw std::invalid_argument(what + ": more than 2^30 nodes");
  std::unordered_map<std::size_t, std::int32_t> index;
  index.reserve(tags.size());
  m.position.resize(tags.size());
  for (std::size_t k = 0; k < tags.size(); ++k) {
    index[tags[k]] = std::int32_t(k);
    m.position[k] = {float(coord[3 * k]), float(coord[3 * k + 1]), float(coord[3 * k + 2])};
  }
  std::vector<int> types;
  gmsh::model::mesh::getElementTypes(types);
  const bool volume = std::find(types.begin(), types.end(), 4) != types.end();
  for (int t : types) {
    std::string name;
    int dim = 0, order = 0, nodes = 0, primary = 0;
    std::vector<double> local;
    gmsh::model::mesh::getElementProperties(t, name, dim, order, nodes, local, primary);
    if (dim == 3 && t != 4) throw std::invalid_argument(what + ": holds " + name + " elements (only 4-node tetrahedra are read)");
    if (dim == 2 && !volume && t != 2)
      throw std::invalid_argument(what + ": holds " + name + " elements (only 3-node triangles are read)");
    if (dim == 2 && volume && t != 2 && notes) {  // beside tetrahedra: left out, as triangles that bound none
      std::vector<std::size_t> tags, element_nodes;
      gmsh::model::mesh::getElementsByType(t, tags, element_nodes);
      notes->push_back("left out " + std::to_string(tags.size()) + " " + name + " elements");
    }
  }
  std::vector<std::size_t> elements, nodes;
  gmsh::model::mesh::getElementsByType(volume ? 4 : 2, elements, nodes);
  auto at = [&](std::size_t tag) {
    const auto it = index.find(tag);
    if (it == index.end()) throw std::invalid_argument(what + ": an element refers to node " + std::to_string(tag) + ", which is not in the file");
    return it->second;
  };
  auto triangles = [&](const std::vector<std::size_t>& node_tags) {
    std::vector<std::array<std::int32_t, 3>> out(node_tags.size() / 3);
    for (std::size_t e = 0; e < out.size(); ++e)
      for (int c = 0; c < 3; ++c) out[e][c] = at(node_tags[3 * e + c]);
    return out;
  };
  if (volume) {
    m.tetrahedron.resize(elements.size());
    for (std::size_t e = 0; e < elements.size(); ++e)
      for (int c = 0; c < 4; ++c) m.tetrahedron[e][c] = at(nodes[4 * e + c]);
  } else {
    m.triangle = triangles(nodes);
  }
  if (elements.empty()) throw std::invalid_argument(what + ": no tetrahedra or triangles");
  if (volume && notes) {
    std::vector<std::size_t> triangle_tags, triangle_nodes;  // (Gmsh does not shrink vectors it is given)
    gmsh::model::mesh::getElementsByType(2, triangle_tags, triangle_nodes);
    if (const std::int64_t n = triangles_bounding_no_tetrahedron(m, triangles(triangle_nodes)))
      notes->push_back("left out " + std::to_string(n) + " triangles that bound no tetrahedron");
  }
  return m;
}


Mesh load_mesh(const std::string& path, std::vector<std::string>& notes) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  // A link loop, a name too long:
  if (ec && ec != std::errc::no_such_file_or_directory) bad_mesh_file(path, ec.message());
  if (ec || !std::filesystem::exists(st)) bad_mesh_file(path, "no such file");
  if (std::filesystem::is_directory(st)) bad_mesh_file(path, "a directory, not a mesh file");
  if (!std::filesystem::is_regular_file(st)) bad_mesh_file(path, "not a regular file");
  const auto size = std::filesystem::file_size(path, ec);
  if (size == 0) bad_mesh_file(path, "the file is empty");
  const std::string what = "mesh file '" + path + "'";
  return read_in_child(what, child_read_limits(std::int64_t(size)), [&](std::vector<std::string>& read_notes) {
    if (extension_of(path) != ".msh") return load_with_assimp(path, read_notes);
    if (!starts_as_gmsh_mesh(path))
      bad_mesh_file(path, "not a Gmsh mesh: it does not start with $MeshFormat or another section Gmsh reads as a "
                          "mesh (Gmsh would read it as a .geo script)");
    GmshSession gmsh;
    Mesh m;
    GmshSession::run(what, [&] {
      try {
        gmsh::open(path);
      } catch (const std::bad_alloc&) {
        throw;
      } catch (...) {
        std::string error;  // Gmsh says no more than this of a file it could not read (MSH 2):
        if (gmsh::logger::getLastError(error), error.starts_with("Error loading"))
          bad_mesh_file(path, "Gmsh could not read it (" + error + "): a file cut short, a count that its data "
                              "disagrees with, or a damaged section");
        throw;
      }
      m = read_gmsh_model(what, &read_notes);
    });
    return m;
  }, notes);
}

bool starts_as_gmsh_mesh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(11, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  for (const char* section : {"$MeshFormat", "$Comments", "$NO", "$ELM", "$PTS", "$PARA"})
    if (head.starts_with(section)) return true;
  return false;
}

Mesh fill_tetrahedra(const Mesh& surface, float cell_size, const std::string& save_to) {
  GmshSession gmsh;
  Mesh m;
  GmshSession::run("filling the surface with tetrahedra", [&] {
    gmsh::model::add("fill");
    const int s = gmsh::model::addDiscreteEntity(2);
    std::vector<std::size_t> tags(surface.position.size()), nodes;
    std::vector<double> coord;
    for (std::size_t v = 0; v < tags.size(); ++v) {
      tags[v] = v + 1;
      for (int c = 0; c < 3; ++c) coord.push_back(surface.position[v][c]);
    }
    for (const auto& t : surface.triangle)
      for (auto v : t) nodes.push_back(std::size_t(v) + 1);
    gmsh::model::mesh::addNodes(2, s, tags, coord);
    gmsh::model::mesh::addElementsByType(s, 2, {}, nodes);
    gmsh::model::geo::addVolume({gmsh::model::geo::addSurfaceLoop({s})});
    gmsh::model::geo::synchronize();
    if (cell_size > 0) gmsh::option::setNumber("Mesh.MeshSizeMax", cell_size);
    gmsh::option::setNumber("General.NumThreads", 0);  // all cores
    // An open surface bounds no volume: Gmsh then fails ("No elements in volume 1") or makes none.
    const std::string none = "Gmsh made no tetrahedra (is the surface closed?)";
    try {
      gmsh::model::mesh::generate(3);
    } catch (...) {
      std::string error;
      gmsh::logger::getLastError(error);
      if (error.find("No elements in volume") != std::string::npos) throw std::invalid_argument(none);
      // TetGen's boundary recovery: its message ends before the point it names.
      if (error.find("PLC Error") != std::string::npos)
        throw std::invalid_argument(error + " (the surface crosses itself: a fill takes a closed surface whose "
                                            "triangles meet only at shared edges)");
      throw;
    }
    m = read_gmsh_model("filling the surface with tetrahedra");
    if (!m.volume()) throw std::invalid_argument(none);
    if (!save_to.empty()) write_gmsh_model(save_to);
  });
  return m;
}

std::string mesh_library_versions() {
  return "assimp " + std::to_string(aiGetVersionMajor()) + "." + std::to_string(aiGetVersionMinor()) + "." +
         std::to_string(aiGetVersionPatch()) + ", Gmsh " + GMSH_API_VERSION;
}

}  // namespace deformlab
