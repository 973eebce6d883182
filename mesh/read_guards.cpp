#include "read_guards.hpp"

#include <assimp/Importer.hpp>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace deformlab {

namespace {

[[noreturn]] void bad_line(const std::string& file, std::int64_t line, const std::string& what) {
  bad_mesh_file(file, "line " + std::to_string(line) + ": " + what);
}

bool blank(char c) { return c == ' ' || c == '\t'; }

// Whether assimp's OBJ reader counts the word at `at` as a number: one that starts with a
// digit, '+' or '-', or with "nan" or "inf" in any case.
bool counted_as_number(const std::string& line, std::size_t at) {
  const auto c = static_cast<unsigned char>(line[at]);
  if (std::isdigit(c) || c == '+' || c == '-') return true;
  std::string head = line.substr(at, 3);
  for (char& h : head) h = char(std::tolower(static_cast<unsigned char>(h)));
  return head == "nan" || head == "inf";
}

// One logical OBJ line (continuations joined), first at physical line `number`.
void check_obj_line(const std::string& path, const std::string& line, std::int64_t number) {
  const bool bom = number == 1 && line.starts_with("\xEF\xBB\xBF");  // UTF-8's byte-order mark
  std::size_t at = bom ? 3 : 0;
  while (at < line.size() && blank(line[at])) ++at;
  // A keyword ends at a blank or the line's end ("v" alone is a vertex of no numbers).
  auto keyword = [&](char k) { return line[at] == k && (at + 1 == line.size() || blank(line[at + 1])); };
  if (at == line.size()) return;
  // A vertex or face keyword in capitals, or its first number run into it.
  const bool v_or_f = line[at] == 'v' || line[at] == 'V' || line[at] == 'f' || line[at] == 'F';
  const bool capital = (line[at] == 'V' || line[at] == 'F') && (at + 1 == line.size() || blank(line[at + 1]));
  const bool run_in = v_or_f && at + 1 < line.size() &&
                      (std::isdigit(static_cast<unsigned char>(line[at + 1])) || line[at + 1] == '-' ||
                       line[at + 1] == '+' || line[at + 1] == '.');
  if (capital || run_in)
    bad_line(path, number, std::string("a `") + (capital ? std::string(1, line[at]) : line.substr(at, 2) + "...") +
                               "` line, which assimp's OBJ reader " +
                               (line[at] == 'f' ? "reads without its first index" : "skips") + " (" +
                               (line[at] == 'F' || line[at] == 'f' ? "a face is `f a b c`" : "a vertex is `v x y z`") +
                               ")");
  const bool vertex = keyword('v'), face = keyword('f');
  if (!vertex && !face) return;
  if (at > 0)
    bad_line(path, number, std::string(bom ? "a byte-order mark before a `" : "an indented `") + line[at] +
                               "` line, which assimp's OBJ reader skips");
  if (!vertex) return;
  int numbers = 0;
  for (std::size_t k = 1; k < line.size(); ++k)
    if (blank(line[k - 1]) && !blank(line[k]))
      numbers += counted_as_number(line, k);
  if (numbers != 3 && numbers != 4 && numbers != 6)
    bad_line(path, number, "a vertex of " + std::to_string(numbers) + " numbers, which assimp's OBJ reader skips (it "
             "keeps 3, 4 or 6, counting the words that start with a digit, + or -: write .5 as 0.5)");
}

// Each property value takes at least one byte in a binary PLY and two in an ASCII one (a digit
// and a blank or line end, but for the file's last), so an element count that the rest of the
// file cannot hold is refused before assimp's reader, which takes the count as it stands, spends
// its CPU cap on it (a minute on 10^8 promised vertices). A count is read as assimp reads it:
// its leading digits, in 32 bits (wrapping).
void require_ply_counts_fit(const std::string& path, const std::string& header, std::uintmax_t body_bytes) {
  std::string text = header;  // lines end at "\n", "\r\n" or "\r", as assimp reads them
  std::replace(text.begin(), text.end(), '\r', '\n');
  std::istringstream lines(text);
  bool ascii = false;
  std::uint32_t count = 0;  // of the element whose properties follow
  std::uint64_t need = 0;   // bytes: at most 2 (2^32 - 1) a property line, exact in 64 bits
  std::string line, word, declared;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    if (!(words >> word)) continue;
    if (word == "format") ascii = words >> word && word == "ascii";
    if (word == "property") need += std::uint64_t(count) * (ascii ? 2 : 1);
    if (word != "element") continue;
    std::string name, number;
    words >> name >> number;
    count = 0;
    for (std::size_t k = 0; k < number.size() && std::isdigit(static_cast<unsigned char>(number[k])); ++k)
      count = count * 10 + std::uint32_t(number[k] - '0');
    declared += (declared.empty() ? "" : ", ") + std::to_string(count) + " " + name;
  }
  if (ascii && need > 0) need -= 1;
  if (need > body_bytes)
    bad_mesh_file(path, "its PLY header declares " + declared + " elements, whose values take at least " +
                            std::to_string(need) + " bytes, where " + std::to_string(body_bytes) +
                            " follow the header (a truncated or damaged file)");
}

}  // namespace

void bad_mesh_file(const std::string& file, const std::string& what) {
  throw std::invalid_argument("mesh file '" + file + "': " + what);
}

std::string extension_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// assimp's PLY reader loops for ever on a header without an end_header line, one whose first
// word is end_header ("end_headers" or "comment end_header" is none). The header is text, within
// its first 64 KiB in any file we know; a file that only holds "ply" further on fails assimp's
// PLY reader at once.
void require_ply_header(const std::string& path, const Assimp::Importer& importer) {
  std::ifstream in(path, std::ios::binary);
  std::string head(64 * 1024, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(std::size_t(in.gcount()));
  const std::string ext = extension_of(path);
  const bool magic = head.starts_with("ply") || head.starts_with("PLY");
  const bool ply = ext == ".ply" || (!importer.IsExtensionSupported(ext) && magic);
  if (!ply) return;
  for (std::size_t at = 0; at < head.size();) {  // lines end at "\n", "\r\n" or "\r"
    const std::size_t line_end = std::min(head.find_first_of("\r\n", at), head.size());
    const std::size_t next = std::min(line_end + (head.compare(line_end, 2, "\r\n") == 0 ? 2 : 1), head.size());
    std::istringstream words(head.substr(at, line_end - at));
    if (std::string first; words >> first && first == "end_header") {
      std::error_code ec;
      const std::uintmax_t size = std::filesystem::file_size(path, ec);
      if (!ec) require_ply_counts_fit(path, head.substr(0, at), size - next);
      return;
    }
    at = next;
  }
  bad_mesh_file(path, "its PLY header has no end_header line in its first 64 KiB (a truncated or damaged file)");
}

// A skipped `v` line gives the vertices after it the numbers before, so that faces join other
// vertices; a skipped `f` line drops a face. Lines end at "\n", "\r\n" or "\r", and one ending
// with a backslash goes on with the next, both joined with nothing between, as assimp reads them.
void require_obj_lines_read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string logical, chunk(1 << 20, '\0');
  std::int64_t number = 0, first = 1;
  bool after_cr = false;  // "\r\n" ends one line
  auto end_line = [&](bool at_end) {
    ++number;
    const bool continued = !logical.empty() && logical.back() == '\\';
    if (continued) logical.pop_back();
    if (continued && !at_end) return;
    check_obj_line(path, logical, first);
    logical.clear();
    first = number + 1;
  };
  while (in.read(chunk.data(), std::streamsize(chunk.size())) || in.gcount() > 0) {
    for (std::streamsize k = 0; k < in.gcount(); ++k) {
      const char c = chunk[std::size_t(k)];
      if (c == '\n' && after_cr) {
        after_cr = false;
        continue;
      }
      after_cr = c == '\r';
      if (c == '\n' || c == '\r')
        end_line(false);
      else
        logical += c;
    }
  }
  if (!logical.empty()) end_line(true);
}

}  // namespace deformlab
