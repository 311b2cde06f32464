/*
 * A complete twinray plugin in plain C89: no acceleration structure at all, every query tests every
 * primitive. It is the starting point for a plugin of your own (replace the loops with your BVH) and the
 * test of the plugin ABI (tests/test_plugin_backend.cpp crosschecks it against the built-in backends).
 *
 * Build:  cc -std=c89 -O2 -shared -fPIC -fvisibility=hidden -I backends/plugin brute_plugin.c -o libbrute.so -lm
 * Use:    twinray crosscheck SCENE --backends embree,plugin:./libbrute.so
 *
 * Arithmetic is in double, then t is rounded to float before the interval test, so the interval is
 * checked on exactly the t that is reported (twinray_plugin.h: tmin <= t <= tmax).
 */
#include "twinray_plugin.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct brute {
  twinray_geometry geometry; /* twinray keeps the arrays alive until destroy */
} brute;

static void* brute_create(void) { return calloc(1, sizeof(brute)); }

static void brute_destroy(void* self) { free(self); }

static int brute_build(void* self, const twinray_geometry* geometry, char* error, size_t error_capacity) {
  size_t i;
  for (i = 0; i < geometry->sphere_count; ++i) {
    if (!(geometry->spheres[i].radius > 0.0f)) {
      /* C89 has no snprintf; the message is short enough for any sane capacity, and is cut otherwise. */
      char message[96];
      sprintf(message, "sphere with geom_id %u has radius <= 0", geometry->spheres[i].geom_id);
      if (error_capacity > 0) {
        size_t k;
        for (k = 0; k + 1 < error_capacity && message[k] != '\0'; ++k) error[k] = message[k];
        error[k] = '\0';
      }
      return TWINRAY_ERROR;
    }
  }
  ((brute*)self)->geometry = *geometry;
  return TWINRAY_OK;
}

/* The order of twinray's Hit (hit.h): smaller t first, then lower (geom_id, prim_id). Honouring it makes
 * the result independent of the loop order, which is what TWINRAY_PLUGIN_HONOURS_TIES promises. */
static int precedes(float t, twinray_id geom_id, twinray_id prim_id, const twinray_hit* best) {
  if (t != best->t) return t < best->t;
  if (geom_id != best->geom_id) return geom_id < best->geom_id;
  return prim_id < best->prim_id;
}

static void sub(const double* a, const double* b, double* out) {
  out[0] = a[0] - b[0];
  out[1] = a[1] - b[1];
  out[2] = a[2] - b[2];
}
static void cross(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void load(const float* f, double* out) {
  out[0] = f[0];
  out[1] = f[1];
  out[2] = f[2];
}

/* Moller-Trumbore in double. Returns 1 with t (float), u, v when the ray crosses the triangle in range. */
static int hit_triangle(const twinray_ray* ray, const twinray_mesh* mesh, size_t prim, float* t_out, float* u_out,
                        float* v_out) {
  double p0[3], p1[3], p2[3], o[3], d[3], e1[3], e2[3], pv[3], tv[3], qv[3];
  double det, inv, u, v;
  float t;
#ifdef TWINRAY_PLUGIN_INJECT_BUG
  /* A deliberately broken build (twinray_buggy_plugin): every mesh loses its last triangle, the way a BVH
     with an off-by-one leaf range would. The tests use it to prove that crosscheck catches such bugs. */
  if (prim + 1 == mesh->triangle_count) return 0;
#endif
  load(mesh->positions + 3 * (size_t)mesh->indices[3 * prim + 0], p0);
  load(mesh->positions + 3 * (size_t)mesh->indices[3 * prim + 1], p1);
  load(mesh->positions + 3 * (size_t)mesh->indices[3 * prim + 2], p2);
  load(ray->org, o);
  load(ray->dir, d);
  sub(p1, p0, e1);
  sub(p2, p0, e2);
  cross(d, e2, pv);
  det = dot(e1, pv);
  if (det == 0.0) return 0; /* parallel to the plane */
  inv = 1.0 / det;
  sub(o, p0, tv);
  u = dot(tv, pv) * inv;
  if (u < 0.0 || u > 1.0) return 0;
  cross(tv, e1, qv);
  v = dot(d, qv) * inv;
  if (v < 0.0 || u + v > 1.0) return 0;
  t = (float)(dot(e2, qv) * inv);
  if (!(t >= ray->tmin && t <= ray->tmax)) return 0;
  *t_out = t;
  *u_out = (float)u;
  *v_out = (float)v;
  return 1;
}

/* Both roots of |o + t d - c| = r, with the discriminant taken from the closest-approach vector so that
 * nothing large cancels (tiny far spheres), and the near root via Vieta (huge near spheres). */
static int sphere_roots(const twinray_ray* ray, const twinray_sphere* s, double* t0, double* t1) {
  double o[3], d[3], c[3], f[3], l[3];
  double a, b, r, disc, q, cq, flen, ra, rb;
  load(ray->org, o);
  load(ray->dir, d);
  load(s->center, c);
  sub(o, c, f);
  r = s->radius;
  a = dot(d, d);
  b = dot(f, d);
  l[0] = f[0] - (b / a) * d[0];
  l[1] = f[1] - (b / a) * d[1];
  l[2] = f[2] - (b / a) * d[2];
  disc = a * (r * r - dot(l, l));
  if (!(disc >= 0.0)) return 0;
  flen = sqrt(dot(f, f));
  cq = (flen - r) * (flen + r);
  q = -(b + (b >= 0.0 ? sqrt(disc) : -sqrt(disc)));
  if (q == 0.0) {
    *t0 = *t1 = 0.0;
    return 1;
  }
  ra = cq / q;
  rb = q / a;
  *t0 = ra < rb ? ra : rb;
  *t1 = ra < rb ? rb : ra;
  return 1;
}

static int hit_sphere(const twinray_ray* ray, const twinray_sphere* s, float* t_out) {
  double t0, t1;
  float t;
  if (!sphere_roots(ray, s, &t0, &t1)) return 0;
  t = (float)t0;
  if (t >= ray->tmin && t <= ray->tmax) {
    *t_out = t;
    return 1;
  }
  t = (float)t1;
  if (t >= ray->tmin && t <= ray->tmax) {
    *t_out = t;
    return 1;
  }
  return 0;
}

static void triangle_normal(const twinray_mesh* mesh, size_t prim, float* ng) {
  double p0[3], p1[3], p2[3], e1[3], e2[3], n[3], len;
  load(mesh->positions + 3 * (size_t)mesh->indices[3 * prim + 0], p0);
  load(mesh->positions + 3 * (size_t)mesh->indices[3 * prim + 1], p1);
  load(mesh->positions + 3 * (size_t)mesh->indices[3 * prim + 2], p2);
  sub(p1, p0, e1);
  sub(p2, p0, e2);
  cross(e1, e2, n);
  len = sqrt(dot(n, n));
  ng[0] = (float)(n[0] / len);
  ng[1] = (float)(n[1] / len);
  ng[2] = (float)(n[2] / len);
}

/* Outward normal and (u, v) = (phi / 2pi, theta / pi), theta measured from +Y, at the double root nearest
 * to the reported t. */
static void sphere_attributes(const twinray_ray* ray, const twinray_sphere* s, twinray_hit* hit) {
  const double two_pi = 6.283185307179586476925;
  double t0, t1, td = hit->t, p[3], len, phi;
  float u;
  if (sphere_roots(ray, s, &t0, &t1)) td = fabs(t0 - td) <= fabs(t1 - td) ? t0 : t1;
  p[0] = (double)ray->org[0] + td * ray->dir[0] - s->center[0];
  p[1] = (double)ray->org[1] + td * ray->dir[1] - s->center[1];
  p[2] = (double)ray->org[2] + td * ray->dir[2] - s->center[2];
  len = sqrt(dot(p, p));
  p[0] /= len;
  p[1] /= len;
  p[2] /= len;
  hit->ng[0] = (float)p[0];
  hit->ng[1] = (float)p[1];
  hit->ng[2] = (float)p[2];
  phi = atan2(p[2], p[0]);
  if (phi < 0.0) phi += two_pi;
  u = (float)(phi / two_pi);
  hit->u = u < 1.0f ? u : 0.99999994f; /* keep u in [0, 1) */
  hit->v = (float)(acos(p[1] < -1.0 ? -1.0 : (p[1] > 1.0 ? 1.0 : p[1])) / (two_pi / 2.0));
}

static int brute_intersect1(const void* self, const twinray_ray* ray, twinray_hit* hit, twinray_query_stats* stats) {
  const twinray_geometry* g = &((const brute*)self)->geometry;
  const twinray_mesh* best_mesh = NULL;
  const twinray_sphere* best_sphere = NULL;
  size_t best_prim = 0, m, i;
  float t, u, v;
  hit->t = ray->tmax;
  hit->geom_id = TWINRAY_INVALID_ID;
  hit->prim_id = TWINRAY_INVALID_ID;
  for (m = 0; m < g->mesh_count; ++m) {
    const twinray_mesh* mesh = &g->meshes[m];
    for (i = 0; i < mesh->triangle_count; ++i) {
      if (!hit_triangle(ray, mesh, i, &t, &u, &v)) continue;
      if (hit->geom_id != TWINRAY_INVALID_ID && !precedes(t, mesh->geom_id, (twinray_id)i, hit)) continue;
      hit->t = t;
      hit->u = u;
      hit->v = v;
      hit->geom_id = mesh->geom_id;
      hit->prim_id = (twinray_id)i;
      best_mesh = mesh;
      best_sphere = NULL;
      best_prim = i;
    }
    stats->primitives_tested += mesh->triangle_count;
  }
  for (i = 0; i < g->sphere_count; ++i) {
    const twinray_sphere* s = &g->spheres[i];
    if (!hit_sphere(ray, s, &t)) continue;
    if (hit->geom_id != TWINRAY_INVALID_ID && !precedes(t, s->geom_id, 0, hit)) continue;
    hit->t = t;
    hit->geom_id = s->geom_id;
    hit->prim_id = 0;
    best_mesh = NULL;
    best_sphere = s;
  }
  stats->primitives_tested += g->sphere_count;
  /* Attributes once, for the final hit only. */
  if (best_mesh != NULL) triangle_normal(best_mesh, best_prim, hit->ng);
  if (best_sphere != NULL) sphere_attributes(ray, best_sphere, hit);
  return hit->geom_id != TWINRAY_INVALID_ID;
}

static int brute_occluded1(const void* self, const twinray_ray* ray, twinray_query_stats* stats) {
  const twinray_geometry* g = &((const brute*)self)->geometry;
  size_t m, i;
  float t, u, v;
  for (m = 0; m < g->mesh_count; ++m) {
    for (i = 0; i < g->meshes[m].triangle_count; ++i) {
      ++stats->primitives_tested;
      if (hit_triangle(ray, &g->meshes[m], i, &t, &u, &v)) return 1;
    }
  }
  for (i = 0; i < g->sphere_count; ++i) {
    ++stats->primitives_tested;
    if (hit_sphere(ray, &g->spheres[i], &t)) return 1;
  }
  return 0;
}

/* Optional entry points may be left NULL; this one exists to exercise twinray's batch path. */
static void brute_intersect_batch(const void* self, const twinray_ray* rays, twinray_hit* hits, size_t count,
                                  twinray_query_stats* stats) {
  size_t i;
  for (i = 0; i < count; ++i) brute_intersect1(self, &rays[i], &hits[i], stats);
}

static void brute_build_stats(const void* self, twinray_build_stats* stats) {
  (void)self;
  stats->memory_bytes = sizeof(brute); /* no private copy of the geometry, no tree */
}

static const twinray_plugin_v1 brute_table = {
    TWINRAY_PLUGIN_ABI_VERSION,
    "brute-c",
    TWINRAY_PLUGIN_COUNTS_TRAVERSAL | TWINRAY_PLUGIN_HONOURS_TIES,
    brute_create,
    brute_destroy,
    brute_build,
    brute_intersect1,
    brute_occluded1,
    brute_intersect_batch,
    NULL, /* occluded_batch: twinray loops over occluded1 */
    brute_build_stats,
};

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &brute_table; }
