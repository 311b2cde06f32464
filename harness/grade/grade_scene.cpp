#include "harness/grade/grade_scene.h"

#include "backends/registry.h"
#include "harness/scenes/named_scene.h"

namespace twinray::grade {

GradeScene::GradeScene(const SuiteScene& spec, const Suite& suite)
    : scene_(std::make_unique<Scene>(load_named_scene(spec.name, suite.dir))),
      index_(std::make_unique<crosscheck::GeometryIndex>(scene_->geometry)),
      trace_name_(portable_scene_name(spec.name, suite.dir)) {}

const Backend& GradeScene::reference(const std::string& backend) {
  std::unique_ptr<Backend>& slot = references_[backend];
  if (!slot) {
    slot = make_backend(backend);
    slot->build(scene_->geometry);
  }
  return *slot;
}

const arbiter::Arbiter& GradeScene::arbiter() {
  if (!arbiter_) arbiter_ = std::make_unique<arbiter::Arbiter>(scene_->geometry);
  return *arbiter_;
}

}  // namespace twinray::grade
