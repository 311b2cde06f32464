#pragma once
// A suite scene as the checks see it: loaded once, with the reference backends (embree, brute, bvh,
// embree-fast) and the arbiter built in the grader's own process on first use and shared by every check on the scene.
// Expected answers therefore never leave the parent process; the plugin sees only the geometry.

#include "core/backend/backend.h"
#include "core/scene/scene.h"
#include "harness/arbiter/arbiter.h"
#include "harness/crosscheck/hit_comparison.h"
#include "harness/grade/suite.h"

#include <map>
#include <memory>
#include <string>

namespace twinray::grade {

class GradeScene {
 public:
  // Throws InputError when the scene cannot be loaded.
  GradeScene(const SuiteScene& spec, const Suite& suite);

  const Scene& scene() const { return *scene_; }
  const SceneGeometry& geometry() const { return scene_->geometry; }
  const crosscheck::GeometryIndex& index() const { return *index_; }
  // How `twinray trace` loads the same scene from any folder (an absolute path or a procedural name).
  const std::string& trace_name() const { return trace_name_; }

  // A built-in backend built on this scene ("embree", "brute", "bvh", "embree-fast"), built on first use.
  const Backend& reference(const std::string& backend);
  // The arbiter over this scene (exact arithmetic), built on first use: only checks with disagreements pay.
  const arbiter::Arbiter& arbiter();

 private:
  std::unique_ptr<Scene> scene_;  // stable address: backends keep pointers into its geometry
  std::unique_ptr<crosscheck::GeometryIndex> index_;
  std::string trace_name_;
  std::map<std::string, std::unique_ptr<Backend>> references_;
  std::unique_ptr<arbiter::Arbiter> arbiter_;
};

}  // namespace twinray::grade
