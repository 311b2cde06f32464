#pragma once
// Exact numbers for the exact intersection routines (core/exact/): finite doubles as GMP integers at one
// common power-of-two scale, and correctly rounded conversion of exact values to float with MPFR.
//
// Why GMP and MPFR (docs/exact-backend.md): every float and double is a dyadic rational m * 2^e, so the
// determinants of the intersection tests are integers once all inputs share the smallest exponent. GMP's
// mpz is the reference implementation of big integers (fast multiplication, perfect-square test), and
// MPFR is the reference for correctly rounded arithmetic (division, square root, trigonometry) with a
// documented error model and mpfr_can_round for Ziv's strategy. Rationals (mpq) are not needed: every
// quantity is a quotient of two integers that is rounded once.
//
// Nothing here reads the FPU's view of a float: conversions go through the bits, and results are
// assembled as bits, so flush-to-zero and denormals-are-zero (set by the renderer and the harness on every
// querying thread) cannot change an exact value or a rounding.
//
// This header is free of GMP and MPFR types so that it can be included anywhere; the big-number helpers
// are in exact_integer.h, included only by the .cpp files of core/exact/.

#include <glm/vec3.hpp>

namespace twinray::exact {

// The value of a float as a double, read from its bits: exact, and unaffected by denormals-are-zero (under
// DAZ, static_cast<double> of a subnormal float gives 0).
double to_double_exact(float x);
glm::dvec3 to_double_exact(const glm::vec3& v);

}  // namespace twinray::exact
