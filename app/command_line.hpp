// What deformlab's and deformlab-bench's command lines take and say beyond CLI11's defaults.
//
// CLI11 reads "0x10" as 16 (and "0b11" into some types): a number on a command line is taken
// only as a decimal, so that a typo is refused rather than read in another base. The words nan
// and inf pass to the options' own range checks, which name what the option takes.
#pragma once
#include <CLI/CLI.hpp>
#include <omp.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <thread>

#include "core/one_line.hpp"

namespace deformlab::app {

// What is wrong with `v` as a decimal number (whole: digits only, and an int), or "": one
// optional sign, all of it read by from_chars, which reads no other base unless asked, and
// "inf" and "nan" only as reals.
inline std::string decimal_problem(const std::string& v, bool whole) {
  const char* at = v.data() + (v.starts_with('+') ? 1 : 0);
  const char* end = v.data() + v.size();
  long long n = 0;
  double d = 0;
  std::from_chars_result r{at, std::errc::invalid_argument};
  if (at != end && !(at != v.data() && *at == '-')) r = whole ? std::from_chars(at, end, n) : std::from_chars(at, end, d);
  if (r.ptr != end || r.ec == std::errc::invalid_argument)
    return "'" + v + "' is not " + (whole ? "a whole decimal number" : "a decimal number");
  // Every whole-number flag is an int; its own check names its range where it has a narrower one.
  if (whole && (r.ec != std::errc() || n < std::numeric_limits<int>::min() || n > std::numeric_limits<int>::max()))
    return v.starts_with('-')
               ? "'" + v + "' is less than " + std::to_string(std::numeric_limits<int>::min()) +
                     ", the least a whole-number option takes"
               : "'" + v + "' is more than " + std::to_string(std::numeric_limits<int>::max()) +
                     ", the most a whole-number option takes";
  return "";
}

// A number option's range check, after the decimal check (CLI::Range would call a word out of
// range): whole numbers from `lo` to `hi`, or reals (NaN is in no range).
inline CLI::Validator whole_in(long long lo, long long hi) {
  return CLI::Validator(
      [lo, hi](std::string& v) {
        if (std::string problem = decimal_problem(v, true); !problem.empty()) return problem;
        const long long n = std::stoll(v);
        return n < lo || n > hi ? "'" + v + "' is not in " + std::to_string(lo) + " to " + std::to_string(hi) : std::string();
      },
      "");
}
inline CLI::Validator real_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& v) {
        if (std::string problem = decimal_problem(v, false); !problem.empty()) return problem;
        const double d = std::strtod(v.c_str(), nullptr);  // an overflow is infinite: out of range
        std::ostringstream range;
        range << std::setprecision(15) << lo << " to " << hi;
        return !(d >= lo && d <= hi) ? "'" + v + "' is not in " + range.str() : std::string();
      },
      "");
}

// Checks every whole-number and real option of `app`'s subcommands (and their vectors' items).
inline void decimal_numbers_only(CLI::App& app) {
  for (CLI::App* sub : app.get_subcommands({}))
    for (CLI::Option* opt : sub->get_options()) {
      const std::string type = opt->get_type_name();  // "INT", or "INT:" and a check's description
      const bool whole = type.starts_with("INT") || type.starts_with("UINT");
      if (whole || type.starts_with("FLOAT"))
        opt->check(CLI::Validator([whole](std::string& v) { return decimal_problem(v, whole); }, ""));
    }
}

// OpenMP's threads at most 4 a hardware thread, with a note where more were asked for
// (OMP_NUM_THREADS=100000 ended in a crash inside the OpenMP runtime).
inline void cap_openmp_threads(const std::string& program) {
  const int hardware = int(std::max(1u, std::thread::hardware_concurrency()));
  if (omp_get_max_threads() <= 4 * hardware) return;
  std::cerr << program << ": note: OMP_NUM_THREADS asks for " << omp_get_max_threads() << " threads on " << hardware
            << " hardware threads; using " << hardware << "\n";
  omp_set_num_threads(hardware);
}

// `code`, once what the program printed has reached its standard output; where it could not
// (a full disk, a closed pipe), one line saying so and `code`, or 1 for a success.
inline int flush_output(const std::string& program, int code) {
  if (std::cout.flush()) return code;
  std::cerr << program << ": error: standard output could not be written (a full disk, a closed pipe?)\n";
  return code ? code : 1;
}

// Parses `argv` into `cli`: help is printed (0); an unknown command, or a parse error, is one
// line on stderr, the latter naming the help of the command it was in, "program command --help"
// (2). Else -1.
inline int parse_command_line(CLI::App& cli, int argc, char** argv) {
  if (argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : cli.get_subcommands({})) {
      known = known || sub->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::cerr << cli.get_name() << ": error: unknown command '" << one_line(argv[1]) << "' (valid: " << names << ")\n";
      return 2;
    }
  }
  try {
    cli.parse(argc, argv);
    return -1;
  } catch (const CLI::Success& e) {  // --help
    return cli.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string what = one_line(e.what());
    const std::string many = ": At Most 1 required but received ";  // CLI11's words for a repeated option
    if (const auto at = what.find(many); at != std::string::npos)
      what = what.substr(0, at) + " is given " + what.substr(at + many.size()) + " times; it takes one value";
    std::string help = cli.get_name();
    if (argc > 1 && argv[1][0] != '-') help.append(" ").append(argv[1]);  // a command (unknown ones are refused above)
    std::cerr << cli.get_name() << ": error: " << what << " (see " << help << " --help)\n";
    return 2;
  }
}

}  // namespace deformlab::app
