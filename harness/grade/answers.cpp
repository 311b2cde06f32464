#include "harness/grade/answers.h"

#include "core/geometry/ray_text.h"
#include "harness/arbiter/arbiter.h"
#include "harness/crosscheck/hit_attributes.h"

#include <fmt/core.h>

#include <bit>
#include <utility>

namespace twinray::grade {

Answers trace_rays(const Backend& backend, std::span<const Ray> rays, Queries queries) {
  Answers a;
  if (queries != Queries::Any) {
    a.hits.resize(rays.size());
    backend.intersect(rays, std::span<Hit>(a.hits), &a.stats);
  }
  if (queries != Queries::Closest) {
    a.occluded.resize(rays.size());
    backend.occluded(rays, std::span<std::uint8_t>(a.occluded), &a.stats);
  }
  return a;
}

std::string describe_hit(const Hit& h) {
  if (!h.found()) return "a miss";
  return fmt::format("geom {} prim {} at t {:.9g} ({})", h.geom_id, h.prim_id, h.t, hex_float(h.t));
}

namespace {

const Hit kMiss{};

class Judge {
 public:
  Judge(GradeScene& scene, std::span<const Ray> rays, const Answers& plugin, const Answers& reference,
        const JudgeOptions& options)
      : scene_(scene), rays_(rays), plugin_(plugin), reference_(reference), o_(options) {
    // What the arbiter holds the plugin to (see answers.h): its watertightness claim, never the tie rule.
    claims_.watertight = options.watertight;
  }

  Judgement run() {
    Judgement j;
    j.rays = rays_.size();
    for (std::size_t i = 0; i < rays_.size(); ++i) {
      const bool check_closest = o_.queries != Queries::Any, check_any = o_.queries != Queries::Closest;
      const Hit& ph = check_closest ? plugin_.hits[i] : kMiss;
      const Hit& rh = check_closest ? reference_.hits[i] : kMiss;
      const bool po = check_any && plugin_.occluded[i] != 0, ro = check_any && reference_.occluded[i] != 0;
      const crosscheck::RayComparison c = crosscheck::compare_ray(scene_.index(), rays_[i], ph, rh, po, ro);

      if (check_closest && !c.identical) {
        pending_ruling_.clear();
        bool wrong = false;
        if (c.kind == crosscheck::MismatchClass::Tie && o_.tie_rule && same_primitive_geometry(ph, rh)) {
          // Copies of one primitive: every copy is hit at the same t, so the lowest id must win. brute
          // honours the rule and names the lowest copy.
          wrong = breaks_tie_rule(i, ph, o_.reference == "brute" ? &rh : nullptr);
          if (!wrong) ++j.tie;
        } else {
          wrong = !arbitrate(c.kind, j, [&](const arbiter::Arbiter& a) {
            const arbiter::Ruling plugin_ruling = a.rule_closest(rays_[i], ph, claims_);
            return std::pair{plugin_ruling, a.rule_closest(rays_[i], rh, claims_).right};
          });
        }
        if (wrong) record(j, i, false);
      }
      if (check_closest && ph.found() && (j.wrong.empty() || j.wrong.back().ray != i)) {
        // The right t on the right primitive still renders wrong with wrong u, v or ng (hit_attributes.h).
        const crosscheck::AttributeRuling attributes = crosscheck::rule_attributes(scene_.index(), rays_[i], ph);
        if (!attributes.right) {
          ++j.wrong_attributes;
          pending_ruling_ = "; wrong attributes: " + attributes.detail;
          record(j, i, false);
        }
      }
      if (check_any && po != ro) {
        pending_ruling_.clear();
        const crosscheck::MismatchClass kind = c.occlusion == crosscheck::OcclusionClass::Genuine
                                                   ? crosscheck::MismatchClass::Genuine
                                                   : crosscheck::MismatchClass::Edge;
        const bool wrong = !arbitrate(kind, j, [&](const arbiter::Arbiter& a) {
          const arbiter::Ruling plugin_ruling = a.rule_occluded(rays_[i], po, claims_);
          return std::pair{plugin_ruling, a.rule_occluded(rays_[i], ro, claims_).right};
        });
        if (wrong) record(j, i, true);
      }
    }
    return j;
  }

 private:
  // Whether the plugin's answer to a disagreement is right, by the arbiter. `rule` returns the plugin's
  // ruling and whether the reference's answer was right. Beyond the cap, the classification decides:
  // a genuine disagreement is wrong, an edge or tie is not.
  template <typename Rule>
  bool arbitrate(crosscheck::MismatchClass kind, Judgement& j, Rule&& rule) {
    if (arbitrations_ >= o_.max_arbitrations) {
      if (kind == crosscheck::MismatchClass::Genuine) {
        ++j.unarbitrated;
        return false;
      }
      ++(kind == crosscheck::MismatchClass::Tie ? j.tie : j.edge);
      return true;
    }
    ++arbitrations_;
    ++j.ruled;
    const auto [ruling, reference_right] = rule(scene_.arbiter());
    if (!ruling.right) {
      pending_ruling_ = ruling_text(ruling);
      return false;
    }
    if (!reference_right) ++j.overruled;
    else if (ruling.reason == arbiter::Reason::Tie) ++j.tie;
    else if (ruling.reason != arbiter::Reason::Agrees) ++j.edge;
    return true;
  }

  static std::string ruling_text(const arbiter::Ruling& r) {
    return fmt::format("; exact arithmetic: {} ({}{})", describe_hit(r.exact), arbiter::to_string(r.reason),
                       r.detail.empty() ? "" : ": " + r.detail);
  }

  // Whether the plugin's hit `ph` on a duplicated primitive is not the lowest-id copy, which brute names
  // (`brute_hit`, or brute asked now).
  bool breaks_tie_rule(std::size_t i, const Hit& ph, const Hit* brute_hit) {
    Hit bh;
    if (brute_hit != nullptr) bh = *brute_hit;
    else scene_.reference("brute").intersect(rays_[i], bh);
    if (!same_primitive_geometry(ph, bh)) return false;
    return bh.geom_id != ph.geom_id ? bh.geom_id < ph.geom_id : bh.prim_id < ph.prim_id;
  }

  // The same triangle (vertices equal in the same order) or the same sphere, under two ids.
  bool same_primitive_geometry(const Hit& a, const Hit& b) const {
    const crosscheck::GeometryIndex& index = scene_.index();
    const TriangleMesh* ma = index.mesh(a.geom_id);
    const TriangleMesh* mb = index.mesh(b.geom_id);
    if (ma && mb && a.prim_id < ma->indices.size() && b.prim_id < mb->indices.size()) {
      const glm::uvec3 ta = ma->indices[a.prim_id], tb = mb->indices[b.prim_id];
      for (int k = 0; k < 3; ++k)
        if (ma->positions[ta[k]] != mb->positions[tb[k]]) return false;
      return true;
    }
    const Sphere* sa = index.sphere(a.geom_id);
    const Sphere* sb = index.sphere(b.geom_id);
    return sa && sb && sa->center == sb->center && sa->radius == sb->radius;
  }

  void record(Judgement& j, std::size_t i, bool any) {
    (any ? j.wrong_any : j.wrong_closest) += 1;
    j.wrong.push_back({i, any});
    const std::string ruling = std::exchange(pending_ruling_, std::string());
    if (!j.first_wrong_description.empty()) return;
    if (any) {
      j.first_wrong_description = fmt::format("any-hit: {} says {}, {} says {}", o_.plugin_label,
                                              plugin_.occluded[i] ? "occluded" : "not occluded", o_.reference,
                                              reference_.occluded[i] ? "occluded" : "not occluded");
    } else {
      j.first_wrong_description = fmt::format("closest hit: {} reports {}, {} {}", o_.plugin_label,
                                              describe_hit(plugin_.hits[i]), o_.reference,
                                              describe_hit(reference_.hits[i]));
    }
    j.first_wrong_description += ruling;
  }

  GradeScene& scene_;
  std::span<const Ray> rays_;
  const Answers& plugin_;
  const Answers& reference_;
  const JudgeOptions& o_;
  BackendTraits claims_;
  std::size_t arbitrations_ = 0;
  std::string pending_ruling_;  // the arbiter's word on the answer being recorded as wrong (empty: not ruled)
};

}  // namespace

Judgement judge(GradeScene& scene, std::span<const Ray> rays, const Answers& plugin, const Answers& reference,
                const JudgeOptions& options) {
  return Judge(scene, rays, plugin, reference, options).run();
}

bool same_bits(const Hit& a, const Hit& b) {
  const auto bits = [](float f) { return std::bit_cast<std::uint32_t>(f); };
  if (!a.found() && !b.found()) return true;
  return a.geom_id == b.geom_id && a.prim_id == b.prim_id && bits(a.t) == bits(b.t) && bits(a.u) == bits(b.u) &&
         bits(a.v) == bits(b.v) && bits(a.ng.x) == bits(b.ng.x) && bits(a.ng.y) == bits(b.ng.y) &&
         bits(a.ng.z) == bits(b.ng.z);
}

std::string summary_of_allowed(const Judgement& j) {
  std::string s;
  if (j.edge) s += fmt::format(", {} edge", j.edge);
  if (j.tie) s += fmt::format(", {} tie", j.tie);
  if (j.overruled) s += fmt::format(", {} where {} arithmetic overruled the reference", j.overruled, j.second_opinion);
  return s.empty() ? "" : " (disagreements allowed:" + s.substr(1) + ")";
}

nlohmann::json judgement_figures(const Judgement& j, std::size_t rays, std::size_t answers, std::size_t wrong,
                                 const std::string& reference) {
  return {{"rays", rays},
          {"answers", answers},
          {"wrong", wrong},
          {"wrong_closest", j.wrong_closest},
          {"wrong_any", j.wrong_any},
          {"wrong_attributes", j.wrong_attributes},
          {"edge", j.edge},
          {"tie", j.tie},
          {"overruled", j.overruled},
          {"unarbitrated", j.unarbitrated},
          {"ruled", j.ruled},
          {"reference", reference},
          {"second_opinion", j.second_opinion}};
}

}  // namespace twinray::grade
