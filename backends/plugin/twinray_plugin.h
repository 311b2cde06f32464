/*
 * twinray plugin ABI, version 1: load your own BVH into twinray and grade it against Embree.
 *
 *   twinray crosscheck SCENE --backends embree,plugin:/path/libmybvh.so
 *
 * A plugin is a shared library that exports one function,
 *
 *   const twinray_plugin_v1* twinray_plugin_entry(void);
 *
 * returning a table that lives as long as the library. This header is plain C89 (plus the C++ guards), so
 * a plugin may be written in C, C++ (declare the entry point extern "C"), Rust, Zig... Guide with a
 * worked example: docs/plugin-abi.md; a complete brute-force plugin: tests/plugins/brute_plugin.c.
 *
 * Contract, in short (the documentation has the details):
 *  - twinray calls create, then build exactly once, then any number of queries, then destroy.
 *  - Geometry passed to build stays valid and unchanged until destroy: the plugin may keep pointers into it.
 *  - Queries are called concurrently from many threads on the same instance: they must not modify it.
 *  - Every ray a plugin sees is valid: finite origin and direction, direction not zero,
 *    0 <= tmin <= tmax, tmax possibly +infinity. A hit counts when tmin <= t <= tmax (closed interval);
 *    t is in units of |dir| (the direction need not be normalised).
 *  - Hit conventions (identical to every twinray backend): for triangles the hit point is
 *    (1-u-v)*p0 + u*p1 + v*p2 and ng = normalize(cross(p1-p0, p2-p0)), never flipped toward the ray; for
 *    spheres prim_id is 0, ng is the outward unit normal, u = phi/(2 pi) in [0,1) with
 *    phi = atan2(n.z, n.x) and v = theta/pi with theta = acos(n.y).
 *  - Plugin code must not let a C++ exception or a longjmp escape through this interface.
 *  - Every call returns with the floating-point control bits it was called with (MXCSR's flush-to-zero,
 *    denormals-are-zero, rounding mode, exception masks), and a batch call writes its count answers only.
 *
 * Versioning: abi_version is the first member of every version of the table, so a loader can read it
 * before it trusts anything else. Any change to a struct or a signature increments
 * TWINRAY_PLUGIN_ABI_VERSION; a plugin built against another version is refused with a clear message.
 */
#ifndef TWINRAY_PLUGIN_H
#define TWINRAY_PLUGIN_H

#include <stddef.h> /* size_t */

#ifdef __cplusplus
extern "C" {
#endif

#define TWINRAY_PLUGIN_ABI_VERSION 1u

/* Name of the exported entry point, for dlsym. */
#define TWINRAY_PLUGIN_ENTRY_SYMBOL "twinray_plugin_entry"

/* "No geometry": the geom_id and prim_id of a miss. */
#define TWINRAY_INVALID_ID 0xFFFFFFFFu

/* Capability flags (twinray_plugin_v1.flags). They only change how results are compared, never what
 * twinray sends. */
#define TWINRAY_PLUGIN_COUNTS_TRAVERSAL 1u /* fills twinray_query_stats on every query */
#define TWINRAY_PLUGIN_HONOURS_TIES 2u     /* equal t: reports the lower (geom_id, prim_id) */
#define TWINRAY_PLUGIN_WATERTIGHT 4u       /* no ray lost through shared edges or vertices */

/* Ids are 32-bit unsigned integers on every platform twinray supports (checked by the loader). */
typedef unsigned int twinray_id;

typedef struct twinray_ray {
  float org[3];
  float tmin;
  float dir[3];
  float tmax; /* may be +infinity */
} twinray_ray;

typedef struct twinray_hit {
  float t;
  float u, v;
  twinray_id geom_id; /* TWINRAY_INVALID_ID for a miss */
  twinray_id prim_id;
  float ng[3];
} twinray_hit;

/* A triangle mesh. Vertices are packed xyz floats; triangles are packed index triples, counter-clockwise
 * seen from the front. Every index is < vertex_count, every referenced vertex is finite and no triangle is
 * degenerate. The 4 bytes after the last vertex are readable (room for 16-byte SIMD loads). */
typedef struct twinray_mesh {
  twinray_id geom_id;
  const float* positions;    /* 3 * vertex_count floats */
  size_t vertex_count;
  const twinray_id* indices; /* 3 * triangle_count ids; prim_id i is the triangle at indices[3i] */
  size_t triangle_count;
} twinray_mesh;

typedef struct twinray_sphere {
  twinray_id geom_id;
  float center[3];
  float radius;
} twinray_sphere;

/* Geometry ids number all shapes of the scene, meshes and spheres interleaved: every geom_id below appears
 * exactly once, and all of them are < geom_id_end. */
typedef struct twinray_geometry {
  const twinray_mesh* meshes;
  size_t mesh_count;
  const twinray_sphere* spheres;
  size_t sphere_count;
  twinray_id geom_id_end;
} twinray_geometry;

/* Per-thread traversal counters. A query receives a pointer (never NULL) to the calling thread's
 * counters, and a plugin with TWINRAY_PLUGIN_COUNTS_TRAVERSAL adds its work to them. */
typedef struct twinray_query_stats {
  size_t nodes_visited;     /* interior and leaf nodes whose box was tested */
  size_t primitives_tested; /* ray-primitive tests */
} twinray_query_stats;

/* What the build produced; every field is optional (leave 0 when unknown). */
typedef struct twinray_build_stats {
  size_t memory_bytes; /* acceleration structure and private copies of geometry */
  size_t nodes;
  size_t leaves;
  size_t max_depth;
  double sah_cost;
} twinray_build_stats;

/* Status codes. */
#define TWINRAY_OK 0
#define TWINRAY_ERROR 1

typedef struct twinray_plugin_v1 {
  /* Must be TWINRAY_PLUGIN_ABI_VERSION. Always the first member. */
  unsigned int abi_version;
  /* Short identifier, e.g. "mybvh"; twinray reports the backend as "plugin:mybvh". */
  const char* name;
  /* TWINRAY_PLUGIN_* capability bits. */
  unsigned int flags;

  /* Required. A new instance, or NULL when out of memory. */
  void* (*create)(void);
  /* Required. Frees everything create and build allocated. Accepts NULL. */
  void (*destroy)(void* self);
  /* Required. Builds the acceleration structure. On failure returns TWINRAY_ERROR and writes a
   * NUL-terminated message of at most error_capacity bytes (including the NUL) into error. */
  int (*build)(void* self, const twinray_geometry* geometry, char* error, size_t error_capacity);

  /* Required. Closest hit in [tmin, tmax]: returns 1 and fills *hit, or returns 0 (the content of *hit
   * is then ignored). */
  int (*intersect1)(const void* self, const twinray_ray* ray, twinray_hit* hit, twinray_query_stats* stats);
  /* Required. 1 when any hit lies in [tmin, tmax], else 0. */
  int (*occluded1)(const void* self, const twinray_ray* ray, twinray_query_stats* stats);

  /* Optional (NULL: twinray loops over intersect1). count rays in, count hits out; a miss has
   * geom_id == TWINRAY_INVALID_ID. */
  void (*intersect_batch)(const void* self, const twinray_ray* rays, twinray_hit* hits, size_t count,
                          twinray_query_stats* stats);
  /* Optional (NULL: twinray loops over occluded1). occluded[i] is set to 1 or 0. */
  void (*occluded_batch)(const void* self, const twinray_ray* rays, unsigned char* occluded, size_t count,
                         twinray_query_stats* stats);
  /* Optional (NULL: no statistics). Called after a successful build. */
  void (*build_stats)(const void* self, twinray_build_stats* stats);
} twinray_plugin_v1;

/* The one exported symbol. Define it in your plugin as
 *   TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &my_table; }
 * Because it is declared here inside extern "C", a C++ definition gets C linkage (an unmangled name)
 * even without repeating extern "C". The export attribute matters when building with
 * -fvisibility=hidden. */
#if defined(_WIN32)
#define TWINRAY_PLUGIN_EXPORT __declspec(dllexport)
#else
#define TWINRAY_PLUGIN_EXPORT __attribute__((visibility("default")))
#endif
TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void);
typedef const twinray_plugin_v1* (*twinray_plugin_entry_fn)(void);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* TWINRAY_PLUGIN_H */
