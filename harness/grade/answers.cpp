#include "harness/grade/answers.h"

#include "core/geometry/ray_text.h"

#include <fmt/core.h>

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
      : scene_(scene), rays_(rays), plugin_(plugin), reference_(reference), o_(options),
        second_name_(options.reference == "brute" ? "embree" : "brute") {}

  Judgement run() {
    Judgement j;
    j.rays = rays_.size();
    j.second_opinion = second_name_;
    for (std::size_t i = 0; i < rays_.size(); ++i) {
      const bool check_closest = o_.queries != Queries::Any, check_any = o_.queries != Queries::Closest;
      const Hit& ph = check_closest ? plugin_.hits[i] : kMiss;
      const Hit& rh = check_closest ? reference_.hits[i] : kMiss;
      const bool po = check_any && plugin_.occluded[i] != 0, ro = check_any && reference_.occluded[i] != 0;
      const crosscheck::RayComparison c = crosscheck::compare_ray(scene_.index(), rays_[i], ph, rh, po, ro);

      if (check_closest && !c.identical) {
        bool wrong = false;
        switch (c.kind) {
          case crosscheck::MismatchClass::Edge: ++j.edge; break;
          case crosscheck::MismatchClass::Tie:
            if (o_.tie_rule && same_primitive_geometry(ph, rh)) {
              // Copies of one primitive: every copy is hit at the same t, so the lowest id must win. brute
              // honours the rule and names the lowest copy.
              wrong = breaks_tie_rule(i, ph, o_.reference == "brute" ? &rh : nullptr);
            } else {
              ++j.tie;
            }
            break;
          case crosscheck::MismatchClass::Genuine: wrong = !arbitrate(i, ph, po, /*any=*/false, j); break;
        }
        if (wrong) record(j, i, false);
      }
      if (check_any) {
        if (c.occlusion == crosscheck::OcclusionClass::Edge) ++j.edge;
        if (c.occlusion == crosscheck::OcclusionClass::Genuine && !arbitrate(i, ph, po, /*any=*/true, j)) record(j, i, true);
      }
    }
    return j;
  }

 private:
  // True when the second opinion sides with the plugin (the reference erred).
  bool arbitrate(std::size_t i, const Hit& ph, bool po, bool any, Judgement& j) {
    if (arbitrations_ >= o_.max_arbitrations) {
      ++j.unarbitrated;
      return false;
    }
    ++arbitrations_;
    const bool right = agrees_with(second_name_, i, ph, po, any);
    if (right) ++j.overruled;
    return right;
  }

  bool agrees_with(const std::string& backend, std::size_t i, const Hit& ph, bool po, bool any) {
    const Backend& second = scene_.reference(backend);
    Hit sh;
    if (!any) second.intersect(rays_[i], sh);
    const bool so = any && second.occluded(rays_[i]);
    const crosscheck::RayComparison c = crosscheck::compare_ray(scene_.index(), rays_[i], ph, any ? kMiss : sh, po, so);
    if (any) return c.occlusion != crosscheck::OcclusionClass::Genuine;
    if (c.identical || c.kind == crosscheck::MismatchClass::Edge) return true;
    if (c.kind != crosscheck::MismatchClass::Tie) return false;
    return !(o_.tie_rule && same_primitive_geometry(ph, sh) && breaks_tie_rule(i, ph, backend == "brute" ? &sh : nullptr));
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
  }

  GradeScene& scene_;
  std::span<const Ray> rays_;
  const Answers& plugin_;
  const Answers& reference_;
  const JudgeOptions& o_;
  std::string second_name_;
  std::size_t arbitrations_ = 0;
};

}  // namespace

Judgement judge(GradeScene& scene, std::span<const Ray> rays, const Answers& plugin, const Answers& reference,
                const JudgeOptions& options) {
  return Judge(scene, rays, plugin, reference, options).run();
}

}  // namespace twinray::grade
