#include "core/sampling/sampler.h"

namespace twinray {

std::string_view to_string(SamplerKind k) {
  switch (k) {
    case SamplerKind::Independent: return "independent";
    case SamplerKind::Sobol: return "sobol";
    case SamplerKind::Sobol4d: return "sobol4d";
  }
  return "unknown";
}

std::optional<SamplerKind> parse_sampler_kind(std::string_view name) {
  if (name == "sobol") return SamplerKind::Sobol;
  if (name == "sobol4d") return SamplerKind::Sobol4d;
  if (name == "independent") return SamplerKind::Independent;
  return std::nullopt;
}

}  // namespace twinray
