#include "json_file.hpp"

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace deformlab {

namespace fs = std::filesystem;

nlohmann::json parse_json(const std::string& text, const std::string& source) {
  // The keys of each object still open, innermost last: a key given twice in one object is
  // refused, where the library would keep the last.
  std::vector<std::set<std::string>> open;
  auto once = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) open.emplace_back();
    if (event == Event::object_end) open.pop_back();
    if (event == Event::key && !open.back().insert(parsed.get<std::string>()).second)
      throw std::invalid_argument(source + " gives the key '" + parsed.get<std::string>() + "' twice in one object");
    return true;
  };
  try {
    return nlohmann::json::parse(text, once);
  } catch (const nlohmann::json::exception& e) {
    // The library's text without its "[json.exception.parse_error.101] " tag.
    std::string why = e.what();
    if (const auto end = why.find("] "); why.rfind("[json.exception.", 0) == 0 && end != std::string::npos)
      why.erase(0, end + 2);
    throw std::invalid_argument(source + " is not valid JSON: " + why);
  }
}

nlohmann::json read_json_file(const std::string& path, const std::string& what) {
  const std::string name = what + " '" + path + "'";
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw std::invalid_argument("cannot open " + name + ": no such file");
  if (fs::is_directory(st)) throw std::invalid_argument(name + " is a directory, not a JSON file");
  if (!fs::is_regular_file(st)) throw std::invalid_argument(name + " is not a regular file");
  const auto bytes = fs::file_size(path, ec);
  if (ec) throw std::invalid_argument("cannot read " + name + ": " + ec.message());
  if (std::int64_t(bytes) > kMaxJsonFileBytes)
    throw std::invalid_argument(name + " is " + std::to_string(bytes >> 20) + " MiB, more than the " +
                                std::to_string(kMaxJsonFileBytes >> 20) + " MiB a JSON file may have");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot open " + name);
  std::ostringstream text;
  text << in.rdbuf();
  return parse_json(text.str(), name);
}

}  // namespace deformlab
