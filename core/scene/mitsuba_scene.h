#pragma once
// Mitsuba 3 XML scenes (.xml), for the subset twinray can represent exactly (docs/mitsuba.md):
//
//   scene     version 2.x or 3.x; <default name value> parameters and $name substitution in attributes
//   integrator path: max_depth, rr_depth (hide_emitters false only)
//   sensor    perspective: fov, fov_axis (x, y, smaller, larger, diagonal), to_world, near_clip <= 0.01 and a
//             far_clip beyond the scene (twinray clips nothing); sampler independent, stratified,
//             multijitter, orthogonal or ldsampler (sample_count -> spp, seed; twinray renders with its own
//             sampler, which has the same expectation); film hdrfilm: width, height, rfilter box
//   bsdf      diffuse (reflectance), conductor with material none (a mirror; specular_reflectance),
//             dielectric (int_ior / ext_ior as numbers or Mitsuba's names; twinray's ior is their ratio),
//             twosided around one diffuse or conductor; top-level with id, or nested in a shape
//   shape     obj, ply (face_normals true: twinray shades with geometric normals), sphere, rectangle,
//             cube; to_world, flip_normals (not on spheres); a bsdf (nested or <ref>) and an area emitter
//   emitter   area (in a shape; radiance), constant (radiance), envmap (filename, scale, to_world a
//             rotation about +Y)
//   transform translate, rotate, scale, matrix (affine), lookat
//   values    float, integer, boolean, string, rgb, spectrum (a single value), point, vector
//
// Anything else (another plugin, an unknown property, a texture, a Gaussian pixel filter, smooth vertex
// normals, ...) is an InputError naming the element and its line, never a silent substitute. An emitter
// shape's BSDF must be diffuse: twinray's emissive material reflects diffusely. Mitsuba's BSDFs are
// one-sided unless wrapped in twosided; they import as Material::two_sided = false.

#include "core/scene/scene.h"

#include <filesystem>
#include <string_view>

namespace twinray {

Scene load_mitsuba_scene(const std::filesystem::path& xml_file);

// From text in memory; `xml_file` names the scene in errors and its folder resolves relative file names.
Scene parse_mitsuba_scene(std::string_view text, const std::filesystem::path& xml_file);

}  // namespace twinray
