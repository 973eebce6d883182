// Checks of a mesh file before assimp reads it, for what its readers would do without a word:
// loop for ever, or skip lines of an OBJ so that vertices take other numbers. Each throws
// std::invalid_argument naming the file and the line.
#pragma once
#include <string>

namespace Assimp {
class Importer;
}

namespace deformlab {

// Throws std::invalid_argument("mesh file '<file>': <what>").
[[noreturn]] void bad_mesh_file(const std::string& file, const std::string& what);

// A file's extension in lower case (".PLY" and ".ply" name one format).
std::string extension_of(const std::string& path);

// A PLY file (by its extension or, where assimp knows no reader for its extension, by PLY's
// magic word at its start) whose header has no end_header line in its first 64 KiB, or declares
// more elements than the bytes after it can hold.
void require_ply_header(const std::string& path, const Assimp::Importer& importer);

// A line of an OBJ file (read by assimp's OBJ reader) that the reader skips: a `v` line whose
// words that it counts as numbers (those starting with a digit, '+', '-', "nan" or "inf") are not
// 3, 4 or 6 (".5", a missing coordinate), a `v` or `f` line that starts with a space, a tab or
// (the first line) UTF-8's byte-order mark, or one written `V` or `F`, or `v5 0 0`.
void require_obj_lines_read(const std::string& path);

}  // namespace deformlab
