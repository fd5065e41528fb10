// sin/cos of an angle given in turns (1 turn = 2 pi), from + - * / only, so that generated
// coordinates are bit-identical on every platform (libm's sin/cos may differ in the last bit
// between C libraries). Accurate to a few ulp of double, far below the float output precision.
#pragma once

#include <cmath>

namespace octolod::samplegen {

struct SinCos {
  double sin = 0;
  double cos = 1;
};

// `turns` any finite value; exact multiples of a quarter turn give exact 0 / +-1.
inline SinCos sincos_turns(double turns) {
  // Reduce to the nearest quarter turn q and a remainder r in [-1/8, 1/8] turn.
  const double quarters = std::floor(turns * 4.0 + 0.5);
  const double r = turns - quarters * 0.25;
  const double a = r * 6.283185307179586476925;  // |a| <= pi/4
  const double a2 = a * a;
  // Taylor series to a^15 / a^14 in Horner form: the first omitted term is below 1e-17 for
  // |a| <= pi/4.
  double s = 1.0, c = 1.0;
  for (int k = 7; k >= 1; --k) {
    s = 1.0 - a2 / static_cast<double>((2 * k) * (2 * k + 1)) * s;
    c = 1.0 - a2 / static_cast<double>((2 * k - 1) * (2 * k)) * c;
  }
  s *= a;
  // sin(a + q pi/2) for q mod 4.
  const double q = quarters - 4.0 * std::floor(quarters * 0.25);
  if (q == 0.0) return {s, c};
  if (q == 1.0) return {c, -s};
  if (q == 2.0) return {-s, -c};
  return {-c, s};
}

}  // namespace octolod::samplegen
