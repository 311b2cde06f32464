#include "core/sampling/sampler.h"

namespace twinray {

std::string_view to_string(SamplerKind k) { return k == SamplerKind::Sobol ? "sobol" : "independent"; }

std::optional<SamplerKind> parse_sampler_kind(std::string_view name) {
  if (name == "sobol") return SamplerKind::Sobol;
  if (name == "independent") return SamplerKind::Independent;
  return std::nullopt;
}

}  // namespace twinray
