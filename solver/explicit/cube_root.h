// x^(1/3) inline, for the explicit kernel, which takes one per element and
// step (glibc's cbrt, a call through frexp and scalbn, was a fifth of the
// force evaluation's time).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

namespace pba {

// The real cube root of finite x > 0, within one ulp of the exact value
// (tests/unit/solver/explicit/cube_root_test.cc); other x go to std::cbrt.
// Kahan's first guess through the bit pattern (the exponent divided by 3,
// with fdlibm's bias B1 = (1023 - 1023/3 - 0.03306235651) 2^20 in the high
// word; relative error < 1/32), two steps of Halley's iteration
// y <- y (y^3 + 2x) / (2 y^3 + x) (cubic: to about 3e-5, then 3e-14) and
// one of Newton's y <- y - (y^3 - x) / (3 y^2) for the last bits.
inline double CubeRoot(double x) {
  if (!(x > 1e-290 && x < 1e290)) return std::cbrt(x);
  constexpr std::uint64_t kBias = std::uint64_t{715094163} << 32;
  double y = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) / 3 + kBias);
  double y3 = y * y * y;
  y = y * (y3 + 2 * x) / (2 * y3 + x);
  y3 = y * y * y;
  y = y * (y3 + 2 * x) / (2 * y3 + x);
  return y - (y * y * y - x) / (3 * y * y);
}

}  // namespace pba
