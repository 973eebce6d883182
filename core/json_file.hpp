// The JSON files a user names (scenes, experiments, calibrations), read alike: anything but a
// regular file of at most kMaxJsonFileBytes holding valid JSON is refused with one
// std::invalid_argument naming the file and the problem (no library text unexplained).
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

namespace deformlab {

inline constexpr std::int64_t kMaxJsonFileBytes = std::int64_t(16) << 20;

// `what`: how the message names the file ("scene file", "experiment file", ...).
nlohmann::json read_json_file(const std::string& path, const std::string& what);
// Text from elsewhere (a built-in file): `source` names it in the message.
nlohmann::json parse_json(const std::string& text, const std::string& source);
// Refuses a value read from such a file: std::invalid_argument "where: what", `where` the value's
// key path ("x.sweep.sizes").
[[noreturn]] void bad_value(const std::string& where, const std::string& what);

}  // namespace deformlab
