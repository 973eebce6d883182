// Numbers as a person reads them in a summary: fixed notation with a set number of significant
// digits (no exponents), durations in the unit that suits them, counts with their noun.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>

namespace deformlab {

// `v` with `digits` significant digits in fixed notation: 0.003146, 0.0000430, 1235.
std::string significant(double v, int digits);
// The same without trailing zeros (as %g writes it, never with an exponent): 0.5, 0.000043.
std::string significant_trimmed(double v, int digits);
// The double of the shortest decimal that reads back as `f` (0.002 for the float nearest it,
// whose exact value is 0.0020000000949949026), or f's exact value where that decimal, read as
// a double first, does not round to `f` (a few floats).
double shortest_decimal(float f);
// A duration of `s` seconds: "69.0 ns", "45.3 µs", "9.06 ms", "1.23 s", "2 min 03 s", "1 h 02 min".
std::string duration_text(double s);
// "1 node", "4096 nodes"; `plural` where adding "s" is wrong.
std::string counted(std::int64_t n, std::string_view noun, std::string_view plural = {});

}  // namespace deformlab
