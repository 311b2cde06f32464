#include "backends/simd/isa.h"

#include <fmt/core.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace twinray {

std::string_view to_string(Isa isa) {
  switch (isa) {
    case Isa::Sse2: return "sse2";
    case Isa::Avx2: return "avx2";
    case Isa::Avx512: return "avx512";
  }
  return "?";
}

std::optional<Isa> parse_isa(std::string_view name) {
  for (Isa isa : {Isa::Sse2, Isa::Avx2, Isa::Avx512})
    if (name == to_string(isa)) return isa;
  return std::nullopt;
}

Isa cpu_isa() {
  static const Isa isa = [] {
    __builtin_cpu_init();
    const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi") &&
                      __builtin_cpu_supports("bmi2") && __builtin_cpu_supports("popcnt");
    const bool avx512 = avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw");
    return avx512 ? Isa::Avx512 : avx2 ? Isa::Avx2 : Isa::Sse2;
  }();
  return isa;
}

Isa selected_isa() {
  const char* env = std::getenv("TWINRAY_ISA");
  if (env == nullptr || *env == '\0') return cpu_isa();
  const std::optional<Isa> wanted = parse_isa(env);
  if (!wanted)
    throw std::invalid_argument(fmt::format("TWINRAY_ISA='{}': expected sse2, avx2 or avx512", env));
  if (*wanted > cpu_isa())
    throw std::invalid_argument(
        fmt::format("TWINRAY_ISA={}: this CPU supports at most {}", env, to_string(cpu_isa())));
  return *wanted;
}

std::vector<Isa> runnable_isas() {
  std::vector<Isa> isas;
  for (Isa isa : {Isa::Sse2, Isa::Avx2, Isa::Avx512})
    if (isa <= cpu_isa()) isas.push_back(isa);
  return isas;
}

}  // namespace twinray
