// Correctly rounded 1/x and sqrt(x), and the dot product in C++'s order, for the GL pipelines'
// exact math (sim.glsl): GLSL lets a driver approximate 1/x (2.5 ulp) and sqrt (more), and
// evaluate dot() as it likes.
//
// The method: x is read by its bits as a 24-bit significand m and an exponent. The driver's 1/x
// or inversesqrt of the significand is only a starting value y (it may be 30 ulp off, which
// keeps sqrt's residual within an int; GLSL allows 2.5 and 2). Its residual (1/x: 2^47 - m y;
// sqrt: m 2^23 - y^2), exact in integers (umulExtended), corrects it by an exact integer step
// (a division; for sqrt a Newton step, which lands on the root or just above it, then one
// check) to the floor of the exact result, whose remainder then rounds it to nearest (the exact
// result is never a midpoint). The exponent goes back by the bits, a subnormal 1/x rounded
// there by the same remainder. GLSL's fma() would not do: it need not round once (llvmpipe's
// does not).
// Results: IEEE round to nearest even for every finite x, subnormal x included (read by its
// bits, whatever the hardware flushes); 1/+-0 = +-inf, 1/+-inf = +-0, sqrt(+-0) = +-0,
// sqrt(x < 0) = NaN, sqrt(+inf) = +inf, NaN stays NaN.
// DL_GUESS_ULPS (tests): ulps added to the driver's starting values, which must not matter.

#ifndef DL_GUESS_ULPS
#define DL_GUESS_ULPS 0
#endif

float dl_guess(float a) { return uintBitsToFloat(uint(int(floatBitsToUint(a)) + DL_GUESS_ULPS)); }

// floor(a / b) for 2^23 <= b < 2^26: a float quotient, within 2^-13 of a / b (below 256 in
// magnitude) however GLSL's division rounds, then one correction by the remainder, which is
// exact (int * and - wrap). With integer divisions instead, glsl-compute's exact step took 23%
// longer on an H100; handing the remainder back (for dl_recip_floor, which computes it again)
// took 1-4% longer there, with branches or selects.
int dl_floor_div(int a, int b) {
  int k = int(floor(float(a) / float(b))), r = a - k * b;
  return r < 0 ? k - 1 : (r >= b ? k + 1 : k);
}

// A finite non-zero magnitude's bits as m 2^(e - 23), m = 2^23 + f in [2^23, 2^24).
void dl_split(uint mag, out int e, out uint f) {
  if (mag >= 0x00800000u) {
    e = int(mag >> 23) - 127;
    f = mag & 0x007fffffu;
  } else {  // subnormal
    int s = 23 - findMSB(mag);
    e = -126 - s;
    f = (mag << s) & 0x007fffffu;
  }
}

// floor(2^47 / m) for m in [2^23, 2^24), and r, the remainder.
uint dl_recip_floor(uint m, out uint r) {
  uint y = uint(dl_guess(1.0 / (float(m) * 1.1920928955078125e-7)) * 16777216.0), hi, lo;
  umulExtended(m, y, hi, lo);
  int d = int(0u - lo);  // 2^47 - m y, whose magnitude is below 2^31
  int k = dl_floor_div(d, int(m));
  r = uint(d - k * int(m));
  return uint(int(y) + k);
}

float dl_recip(float x) {
  uint b = floatBitsToUint(x), sign = b & 0x80000000u, mag = b & 0x7fffffffu;
  if (mag >= 0x7f800000u) return mag == 0x7f800000u ? uintBitsToFloat(sign) : x;
  if (mag == 0u) return uintBitsToFloat(sign | 0x7f800000u);
  int e;
  uint f, r;
  dl_split(mag, e, f);
  uint m = 0x00800000u | f, y = dl_recip_floor(m, r);  // 1/|x| = (y + r/m) 2^(-24 - e)
  if (y == 0x01000000u) {  // x a power of two
    y = 0x00800000u;
    e -= 1;
  }
  int biased = 126 - e;  // the exponent field of y 2^(-24 - e)
  uint q;
  if (biased >= 255) {
    q = 0x7f800000u;
  } else if (biased >= 1) {
    q = (uint(biased) << 23) + (y & 0x007fffffu) + (2u * r > m ? 1u : 0u);  // a carry may give inf
  } else {
    // Subnormal: y's 24 bits shifted right by sh, to nearest (even on a tie, where r = 0).
    int sh = 1 - biased;
    uint kept = y >> sh, dropped = y - (kept << sh), tie = 1u << (sh - 1);
    q = kept + (dropped > tie || (dropped == tie && (r > 0u || (kept & 1u) != 0u)) ? 1u : 0u);
  }
  return uintBitsToFloat(sign | q);
}

// floor(sqrt(n)) for n = m 2^23, m in [2^23, 2^25), and d = n - floor(sqrt(n))^2.
uint dl_sqrt_floor(uint m, out uint d) {
  float g = float(m) * 1.1920928955078125e-7;
  uint y = uint(g * dl_guess(inversesqrt(g)) * 8388608.0), hi, lo;
  umulExtended(y, y, hi, lo);
  int t = int((m << 23) - lo);  // n - y^2, whose magnitude is below 2^31
  y = uint(int(y) + dl_floor_div(t, int(2u * y)));
  umulExtended(y, y, hi, lo);
  t = int((m << 23) - lo);
  if (t < 0) {
    y -= 1u;
    t += int(2u * y + 1u);
  }
  d = uint(t);
  return y;
}

float dl_sqrt(float x) {
  uint b = floatBitsToUint(x), mag = b & 0x7fffffffu;
  if (mag == 0u || mag > 0x7f800000u || b == 0x7f800000u) return x;
  if (b != mag) return uintBitsToFloat(0x7fc00000u);
  int e;
  uint f, d;
  dl_split(mag, e, f);
  // x = m 2^(2h - 23), h = e >> 1, m in [2^23, 2^25): sqrt(x) = sqrt(m 2^23) 2^(h - 23).
  uint m = (0x00800000u | f) << (e & 1), y = dl_sqrt_floor(m, d);
  y += d > y ? 1u : 0u;  // above y + 1/2 iff n > y^2 + y + 1/4
  return uintBitsToFloat((uint(127 + (e >> 1)) << 23) + y - 0x00800000u);
}

// a.b as C++ evaluates it: (a.x b.x + a.y b.y) + a.z b.z, every operation rounded.
float dl_dot(vec3 a, vec3 b) {
  precise float d = a.x * b.x + a.y * b.y + a.z * b.z;
  return d;
}

float dl_length(vec3 a) { return dl_sqrt(dl_dot(a, a)); }
