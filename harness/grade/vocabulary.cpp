#include "harness/grade/vocabulary.h"

namespace twinray::grade {

std::string_view to_string(Outcome o) {
  switch (o) {
    case Outcome::Pass: return "pass";
    case Outcome::Fail: return "fail";
    case Outcome::Crash: return "crash";
    case Outcome::Timeout: return "timeout";
    case Outcome::Skipped: return "skipped";
  }
  return "?";
}

std::string_view to_string(Category c) {
  switch (c) {
    case Category::Build: return "build";
    case Category::ClosestHit: return "closest-hit";
    case Category::AnyHit: return "any-hit";
    case Category::RayInterval: return "ray-interval";
    case Category::AxisAligned: return "axis-aligned";
    case Category::Watertight: return "watertight";
    case Category::Spheres: return "spheres";
    case Category::Ties: return "ties";
    case Category::ThreadSafety: return "thread-safety";
    case Category::Determinism: return "determinism";
    case Category::Performance: return "performance";
    case Category::TreeQuality: return "tree-quality";
    case Category::DeepTree: return "deep-tree";
    case Category::BatchCalls: return "batch-calls";
    case Category::Complexity: return "complexity";
  }
  return "?";
}

std::string_view to_string(Visibility v) {
  switch (v) {
    case Visibility::Visible: return "visible";
    case Visibility::Hidden: return "hidden";
    case Visibility::AfterDueDate: return "after_due_date";
    case Visibility::AfterPublished: return "after_published";
  }
  return "?";
}

std::optional<Category> parse_category(std::string_view name) {
  for (Category c : kAllCategories)
    if (to_string(c) == name) return c;
  return std::nullopt;
}

std::optional<Visibility> parse_visibility(std::string_view name) {
  for (Visibility v : {Visibility::Visible, Visibility::Hidden, Visibility::AfterDueDate, Visibility::AfterPublished})
    if (to_string(v) == name) return v;
  return std::nullopt;
}

bool is_correctness_category(Category c) {
  switch (c) {
    case Category::ClosestHit:
    case Category::AnyHit:
    case Category::RayInterval:
    case Category::AxisAligned:
    case Category::Watertight:
    case Category::Spheres:
    case Category::Ties:
    case Category::DeepTree:
    case Category::BatchCalls:
      return true;
    default:
      return false;
  }
}

}  // namespace twinray::grade
