#include "core/exact/exact_sphere.h"

#include "core/exact/exact_integer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace twinray::exact {

namespace {

// The quadratic's coefficients as integers (A t^2 + 2 B t + C = 0, D = B^2 - A C).
struct Quadratic {
  mpz_class a, b, c, disc;
};

Quadratic quadratic(const RaySphere& in) {
  const ScaledIntegers s{in.org.x, in.org.y, in.org.z, in.dir.x, in.dir.y, in.dir.z, in.center.x, in.center.y,
                         in.center.z, in.radius};
  const IVec3 o{s.at(0), s.at(1), s.at(2)}, d{s.at(3), s.at(4), s.at(5)}, c{s.at(6), s.at(7), s.at(8)};
  const IVec3 f = o - c;
  Quadratic q;
  q.a = dot(d, d);
  q.b = dot(f, d);
  q.c = dot(f, f) - s.at(9) * s.at(9);
  q.disc = q.b * q.b - q.a * q.c;
  return q;
}

// The roots (-B -+ s) / A when D = s^2 is a perfect square.
void rational_roots(const Quadratic& q, const mpz_class& root, SphereCrossing& out) {
  const mpz_class near_num = -q.b - root, far_num = -q.b + root;
  out.t_near = round_quotient_to_float(near_num, q.a);
  out.t_far = round_quotient_to_float(far_num, q.a);
  out.near_double = quotient_to_double(near_num, q.a);
  out.far_double = quotient_to_double(far_num, q.a);
}

void set_integer(mpfr_ptr x, const mpz_class& z) { mpfr_set_z(x, z.get_mpz_t(), MPFR_RNDN); }

// The near and far roots at precision P, each with relative error below 2^(3-P) (see the header).
void approximate_roots(const Quadratic& q, mpfr_prec_t precision, Mpfr& near_root, Mpfr& far_root) {
  Mpfr a(precision), b(precision), c(precision), s(precision), sum(precision);
  set_integer(a.get(), q.a);
  set_integer(b.get(), q.b);
  set_integer(c.get(), q.c);
  set_integer(s.get(), q.disc);
  mpfr_sqrt(s.get(), s.get(), MPFR_RNDN);
  // q = -(B + sign(B) sqrt(D)) adds magnitudes; sign(0) counts as +.
  if (sgn(q.b) >= 0) mpfr_add(sum.get(), b.get(), s.get(), MPFR_RNDN);
  else mpfr_sub(sum.get(), b.get(), s.get(), MPFR_RNDN);
  mpfr_neg(sum.get(), sum.get(), MPFR_RNDN);
  // B >= 0: q < 0, q/A = (-B - sqrt(D))/A is the near root and C/q the far one; B < 0 the other way round.
  Mpfr& by_a = sgn(q.b) >= 0 ? near_root : far_root;
  Mpfr& by_c = sgn(q.b) >= 0 ? far_root : near_root;
  mpfr_div(by_a.get(), sum.get(), a.get(), MPFR_RNDN);
  mpfr_div(by_c.get(), c.get(), sum.get(), MPFR_RNDN);
}

// The float nearest to the irrational value x approximates (|x - value| < 2^(EXP(x) - err_bits)), if that
// error proves it; nothing otherwise.
bool round_certified(mpfr_srcptr x, mpfr_exp_t err_bits, float& out) {
  const mpfr_exp_t e = mpfr_get_exp(x);
  if (e > 128) {  // |x| >= 2^128: the value (within 2^-60 relative of x) exceeds FLT_MAX + ulp/2, so rounds to inf
    out = mpfr_signbit(x) ? -std::numeric_limits<float>::infinity() : std::numeric_limits<float>::infinity();
    return true;
  }
  const long p = float_precision_at_exponent(e);
  if (p <= 0) {
    // Below the smallest subnormal: 0 or 2^-149, by comparison with 2^-150 (the value is never equal to it).
    Mpfr threshold(2);
    mpfr_set_ui_2exp(threshold.get(), 1, -150, MPFR_RNDN);
    Mpfr magnitude(mpfr_get_prec(x));
    mpfr_abs(magnitude.get(), x, MPFR_RNDN);
    Mpfr gap(mpfr_get_prec(x) + 200);
    mpfr_sub(gap.get(), magnitude.get(), threshold.get(), MPFR_RNDN);
    // Decided when |gap| > 2^(e - err_bits), the error bound (conservatively by one more binade).
    if (mpfr_zero_p(gap.get()) || mpfr_get_exp(gap.get()) <= e - err_bits + 1) return false;
    const float m = mpfr_sgn(gap.get()) > 0 ? std::numeric_limits<float>::denorm_min() : 0.0f;
    out = mpfr_signbit(x) ? -m : m;
    return true;
  }
  if (!mpfr_can_round(x, err_bits, MPFR_RNDN, MPFR_RNDZ, static_cast<mpfr_prec_t>(p + 1))) return false;
  Mpfr rounded(static_cast<mpfr_prec_t>(p));
  mpfr_set(rounded.get(), x, MPFR_RNDN);
  out = float_from_exact_mpfr(rounded.get());  // a carry to 2^128 comes out as infinity
  return true;
}

// x rounded to the nearest float (x itself taken as exact), with the float precision of its exponent.
float round_to_float(mpfr_srcptr x) {
  if (mpfr_zero_p(x) || mpfr_inf_p(x) || mpfr_nan_p(x)) {
    Mpfr copy(2);
    mpfr_set(copy.get(), x, MPFR_RNDN);
    return float_from_exact_mpfr(copy.get());
  }
  const mpfr_exp_t e = mpfr_get_exp(x);
  if (e > 128) return mpfr_signbit(x) ? -std::numeric_limits<float>::infinity() : std::numeric_limits<float>::infinity();
  const long p = float_precision_at_exponent(e);
  if (p <= 0) {
    Mpfr threshold(2);
    mpfr_set_ui_2exp(threshold.get(), 1, -150, MPFR_RNDN);
    const bool above = mpfr_cmpabs(x, threshold.get()) > 0;
    const float m = above ? std::numeric_limits<float>::denorm_min() : 0.0f;
    return mpfr_signbit(x) ? -m : m;
  }
  Mpfr rounded(static_cast<mpfr_prec_t>(p));
  mpfr_set(rounded.get(), x, MPFR_RNDN);
  return float_from_exact_mpfr(rounded.get());
}

constexpr mpfr_prec_t kZivStart = 64;
constexpr mpfr_prec_t kZivLimit = mpfr_prec_t{1} << 16;

}  // namespace

SphereCrossing intersect_sphere_exact(const RaySphere& in) {
  const Quadratic q = quadratic(in);
  SphereCrossing out;
  const int disc_sign = sgn(q.disc);
  if (disc_sign < 0) return out;
  out.real = true;
  if (disc_sign == 0) {
    out.tangent = true;
    rational_roots(q, mpz_class(0), out);
    return out;
  }
  if (mpz_perfect_square_p(q.disc.get_mpz_t()) != 0) {
    rational_roots(q, sqrt(q.disc), out);
    return out;
  }
  bool near_done = false, far_done = false;
  for (mpfr_prec_t precision = kZivStart; precision <= kZivLimit && !(near_done && far_done); precision *= 2) {
    Mpfr near_root(precision), far_root(precision);
    approximate_roots(q, precision, near_root, far_root);
    const mpfr_exp_t err_bits = precision - 3;
    if (!near_done) near_done = round_certified(near_root.get(), err_bits, out.t_near);
    if (!far_done) far_done = round_certified(far_root.get(), err_bits, out.t_far);
    out.near_double = mpfr_get_d(near_root.get(), MPFR_RNDN);
    out.far_double = mpfr_get_d(far_root.get(), MPFR_RNDN);
    if (precision == kZivLimit) {
      // Not reached (see the header); the nearest float of the last approximation is within an ulp.
      if (!near_done) out.t_near = round_to_float(near_root.get());
      if (!far_done) out.t_far = round_to_float(far_root.get());
      break;
    }
  }
  return out;
}

void sphere_attributes_exact(const RaySphere& in, bool use_far_root, glm::vec3& ng, float& u, float& v) {
  const Quadratic q = quadratic(in);
  if (sgn(q.disc) < 0) throw std::invalid_argument("sphere_attributes_exact: the line misses the sphere");
  // Precision: org - center (floats, so at most 277 significant bits) is exact, and 200 bits survive the
  // cancellation in f + t d, whose terms can exceed the result (of size r) by the ratio |f| / r.
  const glm::dvec3 f = in.org - in.center;
  const double largest = std::max({std::fabs(f.x), std::fabs(f.y), std::fabs(f.z), in.radius});
  int spread = 0;
  std::frexp(largest / in.radius, &spread);
  const auto precision = static_cast<mpfr_prec_t>(320 + 2 * std::max(0, spread));

  Mpfr t(precision + 64);
  if (sgn(q.disc) == 0) {
    // Tangent: the rational double root -B/A (the formulas below would divide 0 by 0 when B = 0).
    Mpfr num(precision + 64), den(precision + 64);
    set_integer(num.get(), -q.b);
    set_integer(den.get(), q.a);
    mpfr_div(t.get(), num.get(), den.get(), MPFR_RNDN);
  } else {
    Mpfr near_root(precision + 64), far_root(precision + 64);
    approximate_roots(q, precision + 64, near_root, far_root);
    mpfr_set(t.get(), use_far_root ? far_root.get() : near_root.get(), MPFR_RNDN);
  }

  // n = (org - center + t dir) / r.
  const double org[3] = {in.org.x, in.org.y, in.org.z}, center[3] = {in.center.x, in.center.y, in.center.z},
               dir[3] = {in.dir.x, in.dir.y, in.dir.z};
  Mpfr n[3] = {Mpfr(precision), Mpfr(precision), Mpfr(precision)};
  Mpfr radius(precision), term(precision), c_k(precision);
  mpfr_set_d(radius.get(), in.radius, MPFR_RNDN);
  for (int k = 0; k < 3; ++k) {
    mpfr_set_d(n[k].get(), org[k], MPFR_RNDN);
    mpfr_set_d(c_k.get(), center[k], MPFR_RNDN);
    mpfr_sub(n[k].get(), n[k].get(), c_k.get(), MPFR_RNDN);
    mpfr_mul_d(term.get(), t.get(), dir[k], MPFR_RNDN);
    mpfr_add(n[k].get(), n[k].get(), term.get(), MPFR_RNDN);
    mpfr_div(n[k].get(), n[k].get(), radius.get(), MPFR_RNDN);
  }
  ng = glm::vec3(round_to_float(n[0].get()), round_to_float(n[1].get()), round_to_float(n[2].get()));

  // u = phi / 2 pi with phi = atan2(n.z, n.x) in [0, 2 pi), kept below 1; v = acos(n.y) / pi.
  Mpfr phi(precision), pi(precision), scaled(precision);
  mpfr_const_pi(pi.get(), MPFR_RNDN);
  mpfr_atan2(phi.get(), n[2].get(), n[0].get(), MPFR_RNDN);
  if (mpfr_sgn(phi.get()) < 0) {
    mpfr_mul_2ui(scaled.get(), pi.get(), 1, MPFR_RNDN);
    mpfr_add(phi.get(), phi.get(), scaled.get(), MPFR_RNDN);
  }
  mpfr_div(scaled.get(), phi.get(), pi.get(), MPFR_RNDN);
  mpfr_div_2ui(scaled.get(), scaled.get(), 1, MPFR_RNDN);
  u = std::min(round_to_float(scaled.get()), std::nextafter(1.0f, 0.0f));

  Mpfr cos_theta(precision);
  mpfr_set(cos_theta.get(), n[1].get(), MPFR_RNDN);
  if (mpfr_cmp_si(cos_theta.get(), 1) > 0) mpfr_set_si(cos_theta.get(), 1, MPFR_RNDN);
  if (mpfr_cmp_si(cos_theta.get(), -1) < 0) mpfr_set_si(cos_theta.get(), -1, MPFR_RNDN);
  mpfr_acos(scaled.get(), cos_theta.get(), MPFR_RNDN);
  mpfr_div(scaled.get(), scaled.get(), pi.get(), MPFR_RNDN);
  v = round_to_float(scaled.get());
}

}  // namespace twinray::exact
