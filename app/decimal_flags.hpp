// CLI11 reads "0x10" as 16 (and "0b11" into some types): a number on a command line (deformlab's,
// deformlab-bench's) is taken only as a decimal, so that a typo is refused rather than read in
// another base. The words nan and inf pass to the options' own range checks, which name what
// the option takes.
#pragma once
#include <CLI/CLI.hpp>
#include <charconv>
#include <limits>
#include <string>

namespace deformlab::app {

// Whether `v` is a decimal number (whole: digits only) in full, with one optional sign; from_chars
// reads no other base unless asked, and "inf" and "nan" only as reals.
inline bool is_decimal(const std::string& v, bool whole) {
  const char* at = v.data() + (v.starts_with('+') ? 1 : 0);
  const char* end = v.data() + v.size();
  if (at == end || (at != v.data() && *at == '-')) return false;
  if (whole) {
    long long n = 0;
    const auto r = std::from_chars(at, end, n);
    return r.ptr == end && (r.ec == std::errc() || r.ec == std::errc::result_out_of_range);
  }
  double d = 0;
  const auto r = std::from_chars(at, end, d);
  return r.ptr == end && (r.ec == std::errc() || r.ec == std::errc::result_out_of_range);
}

// Checks every whole-number and real option of `app`'s subcommands (and their vectors' items).
inline void decimal_numbers_only(CLI::App& app) {
  for (CLI::App* sub : app.get_subcommands({}))
    for (CLI::Option* opt : sub->get_options()) {
      const std::string type = opt->get_type_name();  // "INT", or "INT:" and a check's description
      const bool is_int = type.starts_with("INT") || type.starts_with("UINT");
      if (!is_int && !type.starts_with("FLOAT")) continue;
      opt->check(CLI::Validator(
          [is_int](std::string& v) -> std::string {
            if (!is_decimal(v, is_int))
              return "'" + v + "' is not " + (is_int ? "a whole decimal number" : "a decimal number");
            if (!is_int) return "";
            // Every whole-number flag is an int.
            long long n = 0;
            const auto [end, err] = std::from_chars(v.data() + (v[0] == '+'), v.data() + v.size(), n);
            if (err == std::errc() && n >= std::numeric_limits<int>::min() && n <= std::numeric_limits<int>::max())
              return "";
            return "'" + v + "' is out of range (" + std::to_string(std::numeric_limits<int>::min()) + " to " +
                   std::to_string(std::numeric_limits<int>::max()) + ")";
          },
          ""));
    }
}

}  // namespace deformlab::app
