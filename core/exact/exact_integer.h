#pragma once
// Big-number helpers of core/exact/ (private to its .cpp files: they pull in gmpxx.h and mpfr.h).
//
//  - ScaledIntegers: finite doubles as integers at one common scale 2^s, read from their bits.
//  - IVec3: a 3-vector of such integers, with the exact vector operations the tests need.
//  - round_quotient_to_float: num / den rounded to the nearest float (ties to even), with IEEE gradual
//    underflow, built from bits.
//  - Mpfr: an RAII mpfr_t; float_from_exact_mpfr assembles a float from an MPFR value that is one.
//
// Rounding to float across the subnormal range. mpfr_set_q / mpfr_div at precision 24 followed by
// mpfr_get_flt is not enough: MPFR's exponent range is far wider than float's, so a quotient below
// 2^-126 would be rounded to 24 significant bits and then rounded *again* to the subnormal grid (a double
// rounding, wrong for values just off a subnormal midpoint), and mpfr_get_flt may itself go through the
// FPU. Instead the target precision is chosen per value: the quotient's exponent E (2^(E-1) <= |q| < 2^E,
// found with one round-toward-zero division, which never carries across a power of two) fixes how many of
// float's bits are available at that magnitude, p = min(24, E + 149), because float's grid is 2^-149
// below 2^-126. One round-to-nearest division at precision p then rounds the exact quotient once, onto
// exactly the float grid; a carry to 2^E stays representable. Values below 2^-149 (p <= 0) round to 0 or
// to the smallest subnormal by comparison with 2^-150 (a tie goes to the even 0). This needs no change of
// MPFR's global exponent range (mpfr_set_emin / mpfr_subnormalize), so it is trivially thread-safe.

#include <gmpxx.h>
#include <mpfr.h>

#include <cstddef>
#include <initializer_list>
#include <vector>

namespace twinray::exact {

// value_i = at(i) * 2^scale exactly, for finite inputs.
class ScaledIntegers {
 public:
  explicit ScaledIntegers(std::initializer_list<double> values);
  const mpz_class& at(std::size_t i) const { return ints_[i]; }
  long scale() const { return scale_; }

 private:
  std::vector<mpz_class> ints_;
  long scale_ = 0;
};

struct IVec3 {
  mpz_class x, y, z;
  const mpz_class& operator[](int k) const { return k == 0 ? x : (k == 1 ? y : z); }
};
IVec3 operator-(const IVec3& a, const IVec3& b);
IVec3 cross(const IVec3& a, const IVec3& b);
mpz_class dot(const IVec3& a, const IVec3& b);

class Mpfr {
 public:
  explicit Mpfr(mpfr_prec_t precision) { mpfr_init2(value_, precision); }
  ~Mpfr() { mpfr_clear(value_); }
  Mpfr(const Mpfr&) = delete;
  Mpfr& operator=(const Mpfr&) = delete;
  mpfr_ptr get() { return value_; }
  mpfr_srcptr get() const { return value_; }

 private:
  mpfr_t value_;
};

// The float equal to x, which must be zero, infinite, or representable as a float (at most 24 significant
// bits, on float's grid). Assembled from bits.
float float_from_exact_mpfr(mpfr_srcptr x);

// num / den (den != 0) rounded to the nearest float, ties to even; +-inf on overflow.
float round_quotient_to_float(const mpz_class& num, const mpz_class& den);
// num / den to double precision (rounded to nearest), for error figures.
double quotient_to_double(const mpz_class& num, const mpz_class& den);

// The float precision available at exponent E (2^(E-1) <= |x| < 2^E): 24 for normal floats, fewer in the
// subnormal range, <= 0 below the smallest subnormal.
inline long float_precision_at_exponent(long e) { return e + 149 < 24 ? e + 149 : 24; }

}  // namespace twinray::exact
