#pragma once
// The words of a scorecard. Their spellings are a public contract (JSON, Gradescope and JUnit files, suite
// manifests, docs/grading.md): add new ones, never rename.
//
//   outcome     pass, fail, crash, timeout, skipped
//   category    build, closest-hit, any-hit, ray-interval, axis-aligned, watertight, spheres, ties,
//               thread-safety, determinism, performance, tree-quality, deep-tree, batch-calls
//   visibility  visible, hidden, after_due_date, after_published (Gradescope's own four values)
//   required    true, false, "if-claimed" (required only when the plugin claims the property: watertight,
//               honours ties)

#include <optional>
#include <string_view>

namespace twinray::grade {

enum class Outcome { Pass, Fail, Crash, Timeout, Skipped };

enum class Category {
  Build,
  ClosestHit,
  AnyHit,
  RayInterval,
  AxisAligned,
  Watertight,
  Spheres,
  Ties,
  ThreadSafety,
  Determinism,
  Performance,
  TreeQuality,
  DeepTree,
  BatchCalls,  // the plugin's optional intersect_batch / occluded_batch; not applicable to a plugin without them
  Complexity,  // how time per ray grows from a scene to one with several times the primitives (check_complexity.cpp)
};

enum class Visibility { Visible, Hidden, AfterDueDate, AfterPublished };

enum class Requirement { Required, Optional, IfClaimed };

inline constexpr Category kAllCategories[] = {
    Category::Build,       Category::ClosestHit,   Category::AnyHit,      Category::RayInterval,
    Category::AxisAligned, Category::Watertight,   Category::Spheres,     Category::Ties,
    Category::ThreadSafety, Category::Determinism, Category::Performance, Category::TreeQuality,
    Category::DeepTree,    Category::BatchCalls,   Category::Complexity};

std::string_view to_string(Outcome o);
std::string_view to_string(Category c);
std::string_view to_string(Visibility v);

std::optional<Category> parse_category(std::string_view name);
std::optional<Visibility> parse_visibility(std::string_view name);

// Categories whose checks judge answers (what "full marks on correctness" covers).
bool is_correctness_category(Category c);

}  // namespace twinray::grade
