/*
 * An independent test BVH for `twinray grade`, written the way many students and engineers write one, and
 * deliberately unlike tests/plugins/scotty_bvh.cpp (a binned SAH tree with a watertight double test):
 *
 *  - a linear BVH after Karras, "Maximizing Parallelism in the Construction of BVHs, Octrees, and k-d
 *    Trees" (HPG 2012): 30-bit Morton codes (10 bits per axis) of the primitives' box centres, sorted with
 *    qsort; duplicate codes are ordered and split by the primitive's index, as the paper augments the key
 *    (delta(i, j) = 32 + clz(i ^ j) when the codes are equal);
 *  - one primitive per leaf, N - 1 interior nodes, boxes refit bottom-up (a leaf walks up to its parent;
 *    the second child to arrive computes the parent's box, the way the GPU version uses an atomic flag);
 *  - a float slab test the textbook way: reciprocal direction, no padding (Ize's 1 + 2 gamma(3) is not
 *    applied), near/far intersected with the ray's interval [tmin, best t];
 *  - Moller-Trumbore in float, no epsilon but the exact det == 0 check; spheres by the textbook quadratic
 *    b^2 - 4ac in double;
 *  - a small explicit stack (nearer child first). Along any path the common prefix of the 62-bit key
 *    (30 bits of code, 32 of index) grows by at least one bit per level, so the tree is at most 63 deep and
 *    64 entries never overflow.
 *  It claims neither watertightness nor the tie rule: it is correct but not robust.
 *
 * LBVH_BUG=n builds one classic mistake of this architecture (tests/test_grade_lbvh.cpp grades them):
 *   1 Morton codes from centroids scaled by 1024 instead of 1023 and not clamped: the largest centroid's
 *     10 bits overflow into the next axis (the tree is still valid, its order is wrong: quality only)
 *   2 duplicate codes without the index tiebreak: delta(i, j) of equal codes is 32 and the direction of a
 *     node's range is taken as +1 on a tie, so nodes over equal codes get wrong ranges (lost primitives)
 *   3 refit in one pass that computes a parent's box as soon as its first child arrives (from a child
 *     whose sibling's box is not yet known) and never again
 *   4 a traversal stack of 32 entries that drops what does not fit
 *   5 the slab test not intersected with the ray's interval (only the box's own [near, far] >= 0): right
 *     answers, more nodes visited
 *   6 the leaf's primitive taken at its sorted position, not through the sort's permutation
 */
#include "twinray_plugin.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef LBVH_BUG
#define LBVH_BUG 0
#endif

#if LBVH_BUG == 4
#define LBVH_STACK 32
#else
#define LBVH_STACK 64
#endif

#define LEAF_BIT 0x80000000u

typedef struct box {
  float lo[3], hi[3];
} box;

typedef struct prim {
  unsigned index;   /* mesh index (into geometry.meshes) or sphere index */
  unsigned prim_id; /* triangle index within its mesh; 0 for a sphere */
  int sphere;       /* 1 for a sphere */
} prim;

typedef struct node {
  box bounds;
  unsigned child[2]; /* an interior node's index, or LEAF_BIT | the leaf's sorted position */
} node;

typedef struct lbvh {
  twinray_geometry geometry;
  size_t count;   /* primitives = leaves */
  prim* prims;    /* in sorted (Morton) order */
  box* leaf_box;  /* per leaf */
  node* nodes;    /* count - 1 interior nodes, root 0 */
  prim* unsorted; /* LBVH_BUG 6 only */
  size_t depth;
  double sah;
} lbvh;

static void* lbvh_create(void) { return calloc(1, sizeof(lbvh)); }

static void lbvh_destroy(void* self) {
  lbvh* b = (lbvh*)self;
  if (b == NULL) return;
  free(b->prims);
  free(b->leaf_box);
  free(b->nodes);
  free(b->unsorted);
  free(b);
}

static const float* vertex(const twinray_mesh* mesh, unsigned prim_id, int k) {
  return mesh->positions + 3 * (size_t)mesh->indices[3 * (size_t)prim_id + (size_t)k];
}

static void box_empty(box* b) {
  int k;
  for (k = 0; k < 3; ++k) {
    b->lo[k] = ((float)HUGE_VAL);
    b->hi[k] = -((float)HUGE_VAL);
  }
}

static void box_grow(box* b, const box* o) {
  int k;
  for (k = 0; k < 3; ++k) {
    if (o->lo[k] < b->lo[k]) b->lo[k] = o->lo[k];
    if (o->hi[k] > b->hi[k]) b->hi[k] = o->hi[k];
  }
}

static double box_area(const box* b) {
  double dx = (double)b->hi[0] - b->lo[0], dy = (double)b->hi[1] - b->lo[1], dz = (double)b->hi[2] - b->lo[2];
  return 2.0 * (dx * dy + dy * dz + dz * dx);
}

static void prim_box(const twinray_geometry* g, const prim* p, box* out) {
  int k, j;
  if (p->sphere) {
    const twinray_sphere* s = &g->spheres[p->index];
    /* The float sum rounds to nearest, possibly a hair inside the true extent: only a ray touching the
       silhouette within that rounding could be lost, and a grazing answer is either way right. */
    for (k = 0; k < 3; ++k) {
      out->lo[k] = s->center[k] - s->radius;
      out->hi[k] = s->center[k] + s->radius;
    }
    return;
  }
  box_empty(out);
  for (j = 0; j < 3; ++j) {
    const float* v = vertex(&g->meshes[p->index], p->prim_id, j);
    for (k = 0; k < 3; ++k) {
      if (v[k] < out->lo[k]) out->lo[k] = v[k];
      if (v[k] > out->hi[k]) out->hi[k] = v[k];
    }
  }
}

/* Spreads the 10 low bits of v so that two zeros separate them (Karras's expandBits). */
static unsigned expand_bits(unsigned v) {
  v = (v * 0x00010001u) & 0xFF0000FFu;
  v = (v * 0x00000101u) & 0x0F00F00Fu;
  v = (v * 0x00000011u) & 0xC30C30C3u;
  v = (v * 0x00000005u) & 0x49249249u;
  return v;
}

static unsigned quantise(float x) {
#if LBVH_BUG == 1
  return (unsigned)(x * 1024.0f); /* x == 1 gives 1024: bit 10 */
#else
  float q = x * 1024.0f;
  if (q < 0.0f) q = 0.0f;
  if (q > 1023.0f) q = 1023.0f;
  return (unsigned)q;
#endif
}

typedef struct keyed {
  unsigned code;
  unsigned index;
} keyed;

static int keyed_less(const void* a, const void* b) {
  const keyed* x = (const keyed*)a;
  const keyed* y = (const keyed*)b;
  if (x->code != y->code) return x->code < y->code ? -1 : 1;
  if (x->index != y->index) return x->index < y->index ? -1 : 1;
  return 0;
}

static int clz32(unsigned x) { return x == 0 ? 32 : __builtin_clz(x); }

/* The length of the common prefix of keys i and j, -1 outside [0, n). */
static int delta(const keyed* keys, long n, long i, long j) {
  if (j < 0 || j >= n) return -1;
  if (keys[i].code == keys[j].code) {
#if LBVH_BUG == 2
    return 32;
#else
    return 32 + clz32((unsigned)i ^ (unsigned)j);
#endif
  }
  return clz32(keys[i].code ^ keys[j].code);
}

/* Karras 2012, figure 4: interior node i's children. */
static void karras_node(const keyed* keys, long n, long i, node* out) {
  long d, lmax, l, t, j, s, split, lo, hi;
  int dmin, dnode;
#if LBVH_BUG == 2
  d = delta(keys, n, i, i + 1) - delta(keys, n, i, i - 1) >= 0 ? 1 : -1;
#else
  d = delta(keys, n, i, i + 1) - delta(keys, n, i, i - 1) > 0 ? 1 : -1;
#endif
  dmin = delta(keys, n, i, i - d);
  lmax = 2;
  while (delta(keys, n, i, i + lmax * d) > dmin) lmax *= 2;
  l = 0;
  for (t = lmax / 2; t >= 1; t /= 2)
    if (delta(keys, n, i, i + (l + t) * d) > dmin) l += t;
  j = i + l * d;
  dnode = delta(keys, n, i, j);
  s = 0;
  t = l;
  do {
    t = (t + 1) / 2;
    if (delta(keys, n, i, i + (s + t) * d) > dnode) s += t;
  } while (t > 1);
  split = i + s * d + (d < 0 ? d : 0);
  lo = i < j ? i : j;
  hi = i < j ? j : i;
  out->child[0] = lo == split ? (LEAF_BIT | (unsigned)split) : (unsigned)split;
  out->child[1] = hi == split + 1 ? (LEAF_BIT | (unsigned)(split + 1)) : (unsigned)(split + 1);
}

static void set_error(char* error, size_t capacity, const char* message) {
  size_t k;
  if (capacity == 0) return;
  for (k = 0; k + 1 < capacity && message[k] != '\0'; ++k) error[k] = message[k];
  error[k] = '\0';
}

static const box* ref_box(const lbvh* b, unsigned ref) {
  return (ref & LEAF_BIT) ? &b->leaf_box[ref & ~LEAF_BIT] : &b->nodes[ref].bounds;
}

static size_t depth_of(const lbvh* b, unsigned ref, size_t level) {
  size_t l, r;
  if (ref & LEAF_BIT) return level;
  l = depth_of(b, b->nodes[ref].child[0], level + 1);
  r = depth_of(b, b->nodes[ref].child[1], level + 1);
  return l > r ? l : r;
}

static int lbvh_build(void* self, const twinray_geometry* g, char* error, size_t error_capacity) {
  lbvh* b = (lbvh*)self;
  size_t n = 0, m, i;
  keyed* keys;
  prim* all;
  box* boxes;
  box centres;
  unsigned* parent = NULL;
  unsigned char* arrived = NULL;
  b->geometry = *g;
  for (m = 0; m < g->mesh_count; ++m) n += g->meshes[m].triangle_count;
  n += g->sphere_count;
  if (n >= (size_t)LEAF_BIT) {
    set_error(error, error_capacity, "lbvh: more than 2^31 primitives");
    return TWINRAY_ERROR;
  }
  b->count = n;
  if (n == 0) return TWINRAY_OK;
  all = (prim*)malloc(n * sizeof(prim));
  boxes = (box*)malloc(n * sizeof(box));
  keys = (keyed*)malloc(n * sizeof(keyed));
  b->prims = (prim*)malloc(n * sizeof(prim));
  b->leaf_box = (box*)malloc(n * sizeof(box));
  b->nodes = (node*)malloc((n > 1 ? n - 1 : 1) * sizeof(node));
  parent = (unsigned*)calloc(2 * n, sizeof(unsigned)); /* zero: defined even where a broken build leaves gaps */
  arrived = (unsigned char*)calloc(n, 1);
  if (!all || !boxes || !keys || !b->prims || !b->leaf_box || !b->nodes || !parent || !arrived) {
    free(all);
    free(boxes);
    free(keys);
    free(parent);
    free(arrived);
    set_error(error, error_capacity, "lbvh: out of memory");
    return TWINRAY_ERROR;
  }
  n = 0;
  for (m = 0; m < g->mesh_count; ++m)
    for (i = 0; i < g->meshes[m].triangle_count; ++i) {
      all[n].index = (unsigned)m;
      all[n].prim_id = (unsigned)i;
      all[n].sphere = 0;
      ++n;
    }
  for (m = 0; m < g->sphere_count; ++m) {
    all[n].index = (unsigned)m;
    all[n].prim_id = 0;
    all[n].sphere = 1;
    ++n;
  }
  /* Morton codes of the box centres, normalised to the centres' bounds. */
  box_empty(&centres);
  for (i = 0; i < n; ++i) {
    box c;
    int k;
    prim_box(g, &all[i], &boxes[i]);
    for (k = 0; k < 3; ++k) c.lo[k] = c.hi[k] = 0.5f * (boxes[i].lo[k] + boxes[i].hi[k]);
    box_grow(&centres, &c);
  }
  for (i = 0; i < n; ++i) {
    unsigned q[3];
    int k;
    for (k = 0; k < 3; ++k) {
      float extent = centres.hi[k] - centres.lo[k];
      float c = 0.5f * (boxes[i].lo[k] + boxes[i].hi[k]);
      q[k] = quantise(extent > 0.0f ? (c - centres.lo[k]) / extent : 0.0f);
    }
    keys[i].code = expand_bits(q[0]) * 4u + expand_bits(q[1]) * 2u + expand_bits(q[2]);
    keys[i].index = (unsigned)i;
  }
  qsort(keys, n, sizeof(keyed), keyed_less);
  for (i = 0; i < n; ++i) {
    b->prims[i] = all[keys[i].index];
    b->leaf_box[i] = boxes[keys[i].index];
  }
#if LBVH_BUG == 6
  b->unsorted = all;
  all = NULL;
#endif
  free(all);
  free(boxes);
  /* The tree: interior node i's children; parents of interior nodes at [0, n-1), of leaves at n + i. */
  parent[0] = 0;
  parent[n] = 0;
  for (i = 0; i + 1 < n; ++i) {
    int c;
    karras_node(keys, (long)n, (long)i, &b->nodes[i]);
    box_empty(&b->nodes[i].bounds);
    for (c = 0; c < 2; ++c) {
      unsigned ref = b->nodes[i].child[c];
      parent[(ref & LEAF_BIT) ? n + (ref & ~LEAF_BIT) : ref] = (unsigned)i;
    }
  }
  free(keys);
  /* Refit: every leaf walks up; a node's box is computed by the second child to arrive, when both
     children's boxes are final. */
  for (i = 0; n > 1 && i < n; ++i) {
    unsigned at = parent[n + i];
    for (;;) {
#if LBVH_BUG == 3
      if (arrived[at]) break;
      arrived[at] = 1;
#else
      if (!arrived[at]) {
        arrived[at] = 1;
        break;
      }
#endif
      b->nodes[at].bounds = *ref_box(b, b->nodes[at].child[0]);
      box_grow(&b->nodes[at].bounds, ref_box(b, b->nodes[at].child[1]));
      if (at == 0) break;
      at = parent[at];
    }
  }
  free(parent);
  free(arrived);
  /* Statistics in the ABI's cost model (plugin-abi.md, "The SAH cost model"). */
  {
    const box* root = ref_box(b, n > 1 ? 0u : LEAF_BIT);
    double a = box_area(root), sum = 0.0;
    b->depth = depth_of(b, n > 1 ? 0u : LEAF_BIT, 0);
    if (a > 0.0) {
      for (i = 0; i + 1 < n; ++i) sum += box_area(&b->nodes[i].bounds) / a;
      for (i = 0; i < n; ++i) sum += box_area(&b->leaf_box[i]) / a;
      b->sah = sum;
    }
  }
  return TWINRAY_OK;
}

typedef struct ray_ctx {
  float org[3], dir[3], inv[3];
} ray_ctx;

/* The textbook slab test in float. NaN (0 * inf, the origin on a slab plane of an axis the ray runs
   parallel to) is ignored by the comparisons, which keeps that axis open: conservative. */
static int slab(const ray_ctx* r, const box* b, float tmin, float tmax, float* near_out) {
  float tn = -((float)HUGE_VAL), tf = ((float)HUGE_VAL);
  int k;
  for (k = 0; k < 3; ++k) {
    float t0 = (b->lo[k] - r->org[k]) * r->inv[k];
    float t1 = (b->hi[k] - r->org[k]) * r->inv[k];
    if (t0 > t1) {
      float s = t0;
      t0 = t1;
      t1 = s;
    }
    if (t0 > tn) tn = t0;
    if (t1 < tf) tf = t1;
  }
#if LBVH_BUG == 5
  (void)tmin;
  (void)tmax;
  *near_out = tn;
  return tn <= tf && tf >= 0.0f;
#else
  if (tmin > tn) tn = tmin;
  if (tmax < tf) tf = tmax;
  *near_out = tn;
  return tn <= tf;
#endif
}

/* Moller-Trumbore in float: no epsilon but det == 0. */
static int hit_triangle(const ray_ctx* r, const twinray_mesh* mesh, unsigned prim_id, float tmin, float tmax,
                        float* t_out, float* u_out, float* v_out) {
  const float* p0 = vertex(mesh, prim_id, 0);
  const float* p1 = vertex(mesh, prim_id, 1);
  const float* p2 = vertex(mesh, prim_id, 2);
  float e1[3], e2[3], pv[3], tv[3], qv[3], det, inv, u, v, t;
  int k;
  for (k = 0; k < 3; ++k) {
    e1[k] = p1[k] - p0[k];
    e2[k] = p2[k] - p0[k];
    tv[k] = r->org[k] - p0[k];
  }
  pv[0] = r->dir[1] * e2[2] - r->dir[2] * e2[1];
  pv[1] = r->dir[2] * e2[0] - r->dir[0] * e2[2];
  pv[2] = r->dir[0] * e2[1] - r->dir[1] * e2[0];
  det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
  if (det == 0.0f) return 0;
  inv = 1.0f / det;
  u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) * inv;
  if (u < 0.0f || u > 1.0f) return 0;
  qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
  qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
  qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
  v = (r->dir[0] * qv[0] + r->dir[1] * qv[1] + r->dir[2] * qv[2]) * inv;
  if (v < 0.0f || u + v > 1.0f) return 0;
  t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
  if (!(t >= tmin && t <= tmax)) return 0;
  *t_out = t;
  *u_out = u;
  *v_out = v;
  return 1;
}

/* The textbook quadratic |o + t d - c|^2 = r^2 in double: the near root if it is in the interval, else the
   far one. */
static int hit_sphere(const ray_ctx* r, const twinray_sphere* s, float tmin, float tmax, float* t_out,
                      double* td_out) {
  double oc[3], a, bq, c, disc, sq, roots[2];
  int k;
  for (k = 0; k < 3; ++k) oc[k] = (double)r->org[k] - s->center[k];
  a = (double)r->dir[0] * r->dir[0] + (double)r->dir[1] * r->dir[1] + (double)r->dir[2] * r->dir[2];
  bq = 2.0 * (oc[0] * r->dir[0] + oc[1] * r->dir[1] + oc[2] * r->dir[2]);
  c = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - (double)s->radius * s->radius;
  disc = bq * bq - 4.0 * a * c;
  if (disc < 0.0) return 0;
  sq = sqrt(disc);
  roots[0] = (-bq - sq) / (2.0 * a);
  roots[1] = (-bq + sq) / (2.0 * a);
  for (k = 0; k < 2; ++k) {
    float t = (float)roots[k];
    if (t >= tmin && t <= tmax) {
      *t_out = t;
      *td_out = roots[k];
      return 1;
    }
  }
  return 0;
}

static void triangle_normal(const twinray_mesh* mesh, unsigned prim_id, float* ng) {
  const float* p0 = vertex(mesh, prim_id, 0);
  const float* p1 = vertex(mesh, prim_id, 1);
  const float* p2 = vertex(mesh, prim_id, 2);
  double e1[3], e2[3], n[3], len;
  int k;
  for (k = 0; k < 3; ++k) {
    e1[k] = (double)p1[k] - p0[k];
    e2[k] = (double)p2[k] - p0[k];
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (k = 0; k < 3; ++k) ng[k] = (float)(n[k] / len);
}

static void sphere_attributes(const ray_ctx* r, const twinray_sphere* s, double td, twinray_hit* hit) {
  const double two_pi = 6.283185307179586476925;
  double p[3], len, phi;
  float u;
  int k;
  for (k = 0; k < 3; ++k) p[k] = (double)r->org[k] + td * r->dir[k] - s->center[k];
  len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  for (k = 0; k < 3; ++k) {
    p[k] /= len;
    hit->ng[k] = (float)p[k];
  }
  phi = atan2(p[2], p[0]);
  if (phi < 0.0) phi += two_pi;
  u = (float)(phi / two_pi);
  hit->u = u < 1.0f ? u : 0.99999994f;
  hit->v = (float)(acos(p[1] < -1.0 ? -1.0 : (p[1] > 1.0 ? 1.0 : p[1])) / (two_pi / 2.0));
}

static void make_ray(const twinray_ray* ray, ray_ctx* r) {
  int k;
  for (k = 0; k < 3; ++k) {
    r->org[k] = ray->org[k];
    r->dir[k] = ray->dir[k];
    r->inv[k] = 1.0f / ray->dir[k]; /* +-inf for a zero component */
  }
}

static const prim* leaf_prim(const lbvh* b, unsigned leaf) {
#if LBVH_BUG == 6
  return &b->unsorted[leaf];
#else
  return &b->prims[leaf];
#endif
}

/* One traversal for both queries: any != 0 stops at the first hit. */
static int traverse(const lbvh* b, const twinray_ray* ray, int any, twinray_hit* hit, twinray_query_stats* stats) {
  unsigned stack_ref[LBVH_STACK];
  float stack_near[LBVH_STACK];
  int sp = 0;
  ray_ctx r;
  unsigned ref;
  float best = ray->tmax, near_t;
  const prim* best_prim = NULL;
  double best_td = 0.0;
  if (b->count == 0) return 0;
  make_ray(ray, &r);
  ref = b->count > 1 ? 0u : LEAF_BIT;
  ++stats->nodes_visited;
  if (!slab(&r, ref_box(b, ref), ray->tmin, best, &near_t)) return 0;
  for (;;) {
    if (ref & LEAF_BIT) {
      const prim* p = leaf_prim(b, ref & ~LEAF_BIT);
      float t, u = 0.0f, v = 0.0f;
      double td = 0.0;
      int found;
      ++stats->primitives_tested;
      if (p->sphere)
        found = hit_sphere(&r, &b->geometry.spheres[p->index], ray->tmin, best, &t, &td);
      else
        found = hit_triangle(&r, &b->geometry.meshes[p->index], p->prim_id, ray->tmin, best, &t, &u, &v);
      if (found) {
        if (any) return 1;
        best = t;
        best_prim = p;
        best_td = td;
        hit->u = u;
        hit->v = v;
      }
    } else {
      const node* nd = &b->nodes[ref];
      float tl, tr;
      int hl = slab(&r, ref_box(b, nd->child[0]), ray->tmin, best, &tl);
      int hr = slab(&r, ref_box(b, nd->child[1]), ray->tmin, best, &tr);
      stats->nodes_visited += 2;
      if (hl && hr) {
        unsigned near_ref = tl <= tr ? nd->child[0] : nd->child[1];
        unsigned far_ref = tl <= tr ? nd->child[1] : nd->child[0];
#if LBVH_BUG == 4
        if (sp < LBVH_STACK) /* full: the far child is dropped */
#endif
        {
          stack_ref[sp] = far_ref;
          stack_near[sp] = tl <= tr ? tr : tl;
          ++sp;
        }
        ref = near_ref;
        continue;
      }
      if (hl || hr) {
        ref = hl ? nd->child[0] : nd->child[1];
        continue;
      }
    }
    /* Next pending entry whose box still starts before the closest hit so far. */
    for (;;) {
      if (sp == 0) goto done;
      --sp;
      if (stack_near[sp] <= best) break;
    }
    ref = stack_ref[sp];
  }
done:
  if (best_prim == NULL) return 0;
  hit->t = best;
  hit->geom_id = best_prim->sphere ? b->geometry.spheres[best_prim->index].geom_id
                                   : b->geometry.meshes[best_prim->index].geom_id;
  hit->prim_id = best_prim->prim_id;
  if (best_prim->sphere)
    sphere_attributes(&r, &b->geometry.spheres[best_prim->index], best_td, hit);
  else
    triangle_normal(&b->geometry.meshes[best_prim->index], best_prim->prim_id, hit->ng);
  return 1;
}

static int lbvh_intersect1(const void* self, const twinray_ray* ray, twinray_hit* hit, twinray_query_stats* stats) {
  return traverse((const lbvh*)self, ray, 0, hit, stats);
}

static int lbvh_occluded1(const void* self, const twinray_ray* ray, twinray_query_stats* stats) {
  twinray_hit unused;
  return traverse((const lbvh*)self, ray, 1, &unused, stats);
}

static void lbvh_build_stats(const void* self, twinray_build_stats* stats) {
  const lbvh* b = (const lbvh*)self;
  stats->memory_bytes = sizeof(lbvh) + b->count * (sizeof(prim) + sizeof(box)) +
                        (b->count > 1 ? b->count - 1 : 0) * sizeof(node);
  stats->nodes = b->count > 1 ? 2 * b->count - 1 : b->count;
  stats->leaves = b->count;
  stats->max_depth = b->depth;
  stats->sah_cost = b->sah;
}

static const twinray_plugin_v1 lbvh_table = {
    TWINRAY_PLUGIN_ABI_VERSION,
    "lbvh-c",
    TWINRAY_PLUGIN_COUNTS_TRAVERSAL, /* neither watertight nor the tie rule */
    lbvh_create,
    lbvh_destroy,
    lbvh_build,
    lbvh_intersect1,
    lbvh_occluded1,
    NULL,
    NULL,
    lbvh_build_stats,
};

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &lbvh_table; }
