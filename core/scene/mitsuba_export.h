#pragma once
// A twinray scene as a Mitsuba 3 scene: `OUT/scene.xml`, its meshes as binary PLY files in `OUT/meshes/`
// and the environment map copied to `OUT/textures/`. Every convention is mapped so that Mitsuba 3 renders
// the same image in expectation (docs/mitsuba.md has the table):
//  - camera: perspective sensor, `fov_axis` y (twinray's field of view is vertical), `lookat` to_world;
//    near and far clip planes outside the scene's bounds (twinray clips nothing);
//  - film: hdrfilm, box reconstruction filter (twinray's pixel is the mean of its samples), RGB;
//  - integrator: `path` with twinray's max_depth (same segment-counting convention) and rr_depth;
//  - diffuse -> `diffuse`, mirror -> `conductor` with material `none` (a perfect mirror) and the
//    reflectance as specular_reflectance, glass -> `dielectric` with int_ior = ior and ext_ior = 1;
//    two-sided materials are wrapped in `twosided` (Mitsuba's BSDFs are one-sided by default);
//  - emissive -> an `area` emitter on each shape (one-sided, front = counter-clockwise side, as in twinray)
//    with a diffuse BSDF of the material's albedo;
//  - meshes -> `ply` with face_normals (twinray shades with geometric normals only), spheres -> `sphere`;
//  - environment: constant -> `constant`; image -> `envmap` with `scale` and a to_world rotation about +Y
//    of 180 + rotation degrees (Mitsuba's map centre column faces +Z, twinray's faces -Z).
// Sample count, seed, max_depth and rr_depth come from the scene's render settings; the sample count is the XML default
// parameter `spp`, so `mitsuba.load_file(path, spp=N)` overrides it.

#include "core/scene/scene.h"

#include <filesystem>
#include <optional>
#include <string>

namespace twinray {

struct MitsubaExportOptions {
  std::optional<int> rr_depth;  // overrides the scene's render.rr_depth (twinray's --rr-depth)
  // Mitsuba interpolates environment maps bilinearly. A map twinray looks up bilinearly too
  // (Environment::filter) is written as it is and both renderers see the same radiance. For a map twinray
  // looks up by nearest texel, writing it with every texel repeated k x k times confines the difference to
  // bands 1/k of a texel wide around the texel edges, where Mitsuba blends neighbours symmetrically: what
  // `twinray compare` uses (k = 4). 1 copies the file as it is.
  int env_upsample = 1;
};

// Writes the files; returns the path of scene.xml. Throws InputError naming the file it could not write
// or the environment map it could not copy.
std::filesystem::path export_mitsuba_scene(const Scene& scene, const std::filesystem::path& out_dir,
                                           const MitsubaExportOptions& options = {});

// The XML text alone (mesh paths as `meshes/...`, the environment map as `textures/...`), for tests.
std::string mitsuba_scene_xml(const Scene& scene, const MitsubaExportOptions& options = {});

// Binary little-endian PLY of the mesh's vertices and triangles (float x y z, uint8 count + uint32 indices).
std::string ply_bytes(const TriangleMesh& mesh);

}  // namespace twinray
