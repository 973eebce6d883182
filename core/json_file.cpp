#include "json_file.hpp"

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace deformlab {

namespace fs = std::filesystem;

namespace {

// A pass over JSON text, before the library builds its tree, that finds
// - a key given twice in one object (the library keeps the last) and where that object is
//   ("spheres[1]"): the keys of each object still open, and where each open container sits in
//   its parent;
// - a key or string with a NUL character in it, which no name or value needs and which would
//   cut short any message that quotes it;
// - a key longer than kMaxKeyBytes, which no name is and which a message would quote whole;
// - arrays and objects nested deeper than kMaxDepth, which the library's tree would copy,
//   compare and write out by recursion, as deep as the nesting (a stack overflow at 100 000
//   levels).
class JsonCheck : public nlohmann::json_sax<nlohmann::json> {
 public:
  static constexpr std::size_t kMaxDepth = 256, kMaxKeyBytes = 256;
  std::string found;  // "gives the key 'key' twice in one object (at path)", or empty

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t& s) override { return value() && no_nul(s, "a string", open_.size()); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(true); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    if (!no_nul(k, "a key", open_.size() - 1)) return false;
    if (k.size() > kMaxKeyBytes) {  // no name is this long, and a message would quote it whole
      found = "holds a key of " + std::to_string(k.size()) + " bytes" + where(open_.size() - 1) +
              ", longer than any name it can have";
      return false;
    }
    Frame& f = open_.back();
    f.key = k;
    if (f.keys.insert(k).second) return true;
    found = "gives the key '" + k + "' twice in one object" + where(open_.size() - 1);
    return false;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override { return false; }

 private:
  struct Frame {
    bool object;
    std::set<std::string> keys = {};
    std::string key = {};       // an object's: the last key read
    std::size_t elements = 0;   // an array's: values read so far
  };
  bool value() {
    if (!open_.empty() && !open_.back().object) ++open_.back().elements;
    return true;
  }
  // " (at spheres[1].centre)": the place of the value read last, through the first `depth`
  // containers still open; empty at the top.
  std::string where(std::size_t depth) const {
    std::string at;
    for (std::size_t i = 0; i < depth; ++i) {
      if (!open_[i].object) {
        at += '[';
        at += std::to_string(open_[i].elements - 1);
        at += ']';
        continue;
      }
      if (!at.empty()) at += '.';
      at += open_[i].key;
    }
    return at.empty() ? "" : " (at " + at + ")";
  }
  bool no_nul(const string_t& s, const char* what, std::size_t depth) {
    if (s.find('\0') == string_t::npos) return true;
    found = std::string("holds ") + what + " with a NUL character in it" + where(depth);
    return false;
  }
  bool open(bool object) {
    value();
    open_.push_back({object});
    if (open_.size() <= kMaxDepth) return true;
    found = "nests arrays and objects more than " + std::to_string(kMaxDepth) + " deep";
    return false;
  }
  bool close() {
    open_.pop_back();
    return true;
  }
  std::vector<Frame> open_;
};

}  // namespace

nlohmann::json parse_json(const std::string& text, const std::string& source) {
  // The library reads a NUL byte as the end of the text and would ignore what follows it.
  if (const auto at = text.find('\0'); at != std::string::npos)
    throw std::invalid_argument(source + " is not valid JSON: a NUL byte at byte " + std::to_string(at + 1));
  JsonCheck check;
  nlohmann::json::sax_parse(text, &check);
  if (!check.found.empty()) throw std::invalid_argument(source + " " + check.found);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // The library's text without its "[json.exception.parse_error.101] " tag.
    std::string why = e.what();
    if (const auto end = why.find("] "); why.rfind("[json.exception.", 0) == 0 && end != std::string::npos)
      why.erase(0, end + 2);
    throw std::invalid_argument(source + " is not valid JSON: " + why);
  }
  return j;
}

nlohmann::json read_json_file(const std::string& path, const std::string& what) {
  const std::string name = what + " '" + path + "'";
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory)  // a link loop, a name too long
    throw std::invalid_argument("cannot open " + name + ": " + ec.message());
  if (ec || !fs::exists(st)) throw std::invalid_argument("cannot open " + name + ": no such file");
  if (fs::is_directory(st)) throw std::invalid_argument(name + " is a directory, not a JSON file");
  if (!fs::is_regular_file(st)) throw std::invalid_argument(name + " is not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot open " + name);
  // Read to its end, whatever its size says (a file of /proc says 0), up to the cap.
  std::string text, chunk(1 << 16, '\0');
  errno = 0;
  while (in.read(chunk.data(), std::streamsize(chunk.size())) || in.gcount() > 0) {
    text.append(chunk.data(), std::size_t(in.gcount()));
    if (std::int64_t(text.size()) > kMaxJsonFileBytes)
      throw std::invalid_argument(name + " holds more than the " + std::to_string(kMaxJsonFileBytes >> 20) +
                                  " MiB a JSON file may have");
  }
  if (in.bad())
    throw std::invalid_argument("cannot read " + name + ": " +
                                (errno ? std::generic_category().message(errno) : std::string("a read failed")));
  return parse_json(text, name);
}

void bad_value(const std::string& where, const std::string& what) { throw std::invalid_argument(where + ": " + what); }

}  // namespace deformlab
