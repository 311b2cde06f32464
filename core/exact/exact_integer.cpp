#include "core/exact/exact_integer.h"
#include "core/exact/exact_number.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace twinray::exact {

namespace {

// A finite double as (signed integer mantissa, exponent): x = mantissa * 2^exponent.
struct Decomposed {
  std::int64_t mantissa;
  long exponent;
};

Decomposed decompose(double x) {
  const auto bits = std::bit_cast<std::uint64_t>(x);
  const auto biased = static_cast<long>((bits >> 52) & 0x7FFu);
  const std::uint64_t fraction = bits & ((std::uint64_t{1} << 52) - 1);
  if (biased == 0x7FF) throw std::domain_error("exact arithmetic on a non-finite value");
  const std::uint64_t m = biased == 0 ? fraction : (fraction | (std::uint64_t{1} << 52));
  const long e = biased == 0 ? -1074 : biased - 1075;
  const auto signed_m = static_cast<std::int64_t>(m);
  return {(bits >> 63) != 0 ? -signed_m : signed_m, e};
}

}  // namespace

double to_double_exact(float x) {
  const auto bits = std::bit_cast<std::uint32_t>(x);
  const std::uint64_t sign = static_cast<std::uint64_t>(bits >> 31) << 63;
  const std::uint32_t biased = (bits >> 23) & 0xFFu;
  const std::uint64_t fraction = bits & 0x7FFFFFu;
  if (biased == 0xFFu) {
    // Infinity or NaN: same class, same sign (the payload is not needed by any caller).
    return std::bit_cast<double>(sign | (std::uint64_t{0x7FF} << 52) | (fraction << 29));
  }
  if (biased == 0) {
    if (fraction == 0) return std::bit_cast<double>(sign);
    // Subnormal float fraction * 2^-149: normal as a double. k = position of the leading bit.
    const int k = static_cast<int>(std::bit_width(fraction)) - 1;
    const std::uint64_t exponent = static_cast<std::uint64_t>(k - 149 + 1023);
    const std::uint64_t mantissa = (fraction << (52 - k)) & ((std::uint64_t{1} << 52) - 1);
    return std::bit_cast<double>(sign | (exponent << 52) | mantissa);
  }
  return std::bit_cast<double>(sign | (static_cast<std::uint64_t>(biased - 127 + 1023) << 52) | (fraction << 29));
}

glm::dvec3 to_double_exact(const glm::vec3& v) { return {to_double_exact(v.x), to_double_exact(v.y), to_double_exact(v.z)}; }

ScaledIntegers::ScaledIntegers(std::initializer_list<double> values) {
  std::vector<Decomposed> parts;
  parts.reserve(values.size());
  long scale = std::numeric_limits<long>::max();
  for (const double v : values) {
    parts.push_back(decompose(v));
    if (parts.back().mantissa != 0) scale = std::min(scale, parts.back().exponent);
  }
  scale_ = scale == std::numeric_limits<long>::max() ? 0 : scale;
  ints_.reserve(parts.size());
  for (const Decomposed& p : parts) {
    mpz_class z(static_cast<long>(p.mantissa));  // |mantissa| < 2^53 fits a long
    if (p.mantissa != 0) z <<= static_cast<mp_bitcnt_t>(p.exponent - scale_);
    ints_.push_back(std::move(z));
  }
}

IVec3 operator-(const IVec3& a, const IVec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

IVec3 cross(const IVec3& a, const IVec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

mpz_class dot(const IVec3& a, const IVec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

float float_from_exact_mpfr(mpfr_srcptr x) {
  if (mpfr_nan_p(x)) return std::numeric_limits<float>::quiet_NaN();
  const bool negative = mpfr_signbit(x) != 0;
  const std::uint32_t sign = negative ? 0x80000000u : 0u;
  if (mpfr_zero_p(x)) return std::bit_cast<float>(sign);
  if (mpfr_inf_p(x)) return std::bit_cast<float>(sign | 0x7F800000u);
  mpz_class m;
  long e = mpfr_get_z_2exp(m.get_mpz_t(), x);  // x = m * 2^e
  m = abs(m);
  const mp_bitcnt_t zeros = mpz_scan1(m.get_mpz_t(), 0);
  m >>= zeros;
  e += static_cast<long>(zeros);
  if (mpz_sizeinbase(m.get_mpz_t(), 2) > 24) throw std::logic_error("float_from_exact_mpfr: more than 24 bits");
  const auto mantissa = static_cast<std::uint32_t>(m.get_ui());
  const int width = static_cast<int>(std::bit_width(mantissa));
  const long leading = e + width - 1;  // x = 1.f * 2^leading
  if (leading > 127) return std::bit_cast<float>(sign | 0x7F800000u);
  if (leading >= -126) {
    const std::uint32_t normalized = mantissa << (24 - width);  // leading bit at position 23
    const auto biased = static_cast<std::uint32_t>(leading + 127);
    return std::bit_cast<float>(sign | (biased << 23) | (normalized & 0x7FFFFFu));
  }
  // Subnormal: x = F * 2^-149, F < 2^23 (representability means e >= -149).
  if (e < -149) throw std::logic_error("float_from_exact_mpfr: below the float grid");
  return std::bit_cast<float>(sign | (mantissa << (e + 149)));
}

float round_quotient_to_float(const mpz_class& num, const mpz_class& den) {
  if (den == 0) throw std::domain_error("round_quotient_to_float: zero denominator");
  if (num == 0) return 0.0f;
  const bool negative = (sgn(num) < 0) != (sgn(den) < 0);
  const mpz_class n = abs(num), d = abs(den);
  Mpfr numerator(static_cast<mpfr_prec_t>(std::max<std::size_t>(2, mpz_sizeinbase(n.get_mpz_t(), 2))));
  mpfr_set_z(numerator.get(), n.get_mpz_t(), MPFR_RNDN);  // exact: the precision is the integer's width
  // The exponent of the exact quotient, from a division toward zero (never rounds up to the next power of 2).
  Mpfr q(24);
  mpfr_div_z(q.get(), numerator.get(), d.get_mpz_t(), MPFR_RNDZ);
  const long e = mpfr_get_exp(q.get());
  float magnitude = 0.0f;
  if (e > 128) {
    magnitude = std::numeric_limits<float>::infinity();
  } else if (const long p = float_precision_at_exponent(e); p <= 0) {
    // |q| < 2^-149: 0 or the smallest subnormal, whichever is nearer; the tie 2^-150 goes to the even 0.
    const mpz_class twice = n << 150;
    magnitude = cmp(twice, d) > 0 ? std::numeric_limits<float>::denorm_min() : 0.0f;
  } else {
    mpfr_set_prec(q.get(), static_cast<mpfr_prec_t>(p));
    mpfr_div_z(q.get(), numerator.get(), d.get_mpz_t(), MPFR_RNDN);
    magnitude = float_from_exact_mpfr(q.get());  // a carry to 2^128 comes out as infinity
  }
  return negative ? -magnitude : magnitude;
}

double quotient_to_double(const mpz_class& num, const mpz_class& den) {
  if (num == 0) return 0.0;
  Mpfr numerator(static_cast<mpfr_prec_t>(std::max<std::size_t>(2, mpz_sizeinbase(num.get_mpz_t(), 2))));
  mpfr_set_z(numerator.get(), num.get_mpz_t(), MPFR_RNDN);
  Mpfr q(53);
  mpfr_div_z(q.get(), numerator.get(), den.get_mpz_t(), MPFR_RNDN);
  return mpfr_get_d(q.get(), MPFR_RNDN);
}

}  // namespace twinray::exact
