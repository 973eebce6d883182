#include "number_text.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace deformlab {

std::string significant(double v, int digits) {
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
  if (v == 0) return "0";
  // Round first, so that 9.9996 to 4 digits counts its decimals from 10.00, not 9.9996.
  const int exponent = int(std::floor(std::log10(std::fabs(v))));
  int decimals = digits - 1 - exponent;
  const double rounded = decimals >= 0 ? std::round(v * std::pow(10.0, decimals)) / std::pow(10.0, decimals) : v;
  if (rounded != 0 && int(std::floor(std::log10(std::fabs(rounded)))) > exponent) --decimals;
  decimals = std::max(decimals, 0);
  std::string out(std::size_t(std::snprintf(nullptr, 0, "%.*f", decimals, v)), '\0');
  std::snprintf(out.data(), out.size() + 1, "%.*f", decimals, v);
  return out;
}

std::string significant_trimmed(double v, int digits) {
  std::string s = significant(v, digits);
  if (s.find('.') == std::string::npos) return s;
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s;
}

double shortest_decimal(float f) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, f).ptr;
  double d = 0;
  std::from_chars(text, end, d);
  return float(d) == f ? d : double(f);
}

std::string duration_text(double s) {
  char out[48];
  if (s == 0 || !std::isfinite(s)) return significant(s, 3) + " s";
  if (s < 0) return duration_text(-s).insert(0, 1, '-');
  // Each unit up to where its three digits would round to 1000 (or to a minute).
  if (s < 59.95) {
    const auto [scale, unit] = s < 999.5e-9   ? std::pair{1e9, " ns"}
                               : s < 999.5e-6 ? std::pair{1e6, " µs"}
                               : s < 0.9995   ? std::pair{1e3, " ms"}
                                              : std::pair{1.0, " s"};
    return significant(s * scale, 3) + unit;
  }
  if (s < 3599.5) {
    const long r = std::lround(s);
    std::snprintf(out, sizeof out, "%ld min %02ld s", r / 60, r % 60);
  } else if (s < 3.6e15) {  // minutes a long holds
    const long m = std::lround(s / 60);
    std::snprintf(out, sizeof out, "%ld h %02ld min", m / 60, m % 60);
  } else {
    return significant(s / 3600, 3) + " h";
  }
  return out;
}

std::string counted(std::int64_t n, std::string_view noun, std::string_view plural) {
  std::string out = std::to_string(n) + " ";
  if (n == 1) return out.append(noun);
  return plural.empty() ? out.append(noun).append("s") : out.append(plural);
}

}  // namespace deformlab
