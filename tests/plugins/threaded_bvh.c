/*
 * A fourth independent test BVH for `twinray grade`: a stackless "threaded" BVH, the layout of many GPU and
 * student renderers (Smits, "Efficiency Issues for Ray Tracing", JGT 1998: skip pointers; Hachisuka's
 * multiple-threaded BVH, MTBVH, for a front-to-back order without a stack), written in plain C89 and unlike
 * scotty_bvh.cpp, lbvh_plugin.c and bvh4_plugin.cpp in every part that touches the verdict:
 *
 *  - build: object-median split on the longest axis of the primitives' box centres (a quickselect, no SAH),
 *    one primitive per leaf; a range whose box centres all coincide cannot be split by position and becomes
 *    one leaf of all of them;
 *  - layout: the binary build tree is flattened six times, once per direction (+x, -x, +y, -y, +z, -z), each a
 *    depth-first pre-order in which a node's child whose box centre comes first along that direction is
 *    visited first. Every entry of a table holds its node, a hit link (where to go when the ray enters the
 *    node's box: the next entry for an interior node, the escape for a leaf) and a miss link, the escape (the
 *    entry after the node's subtree). No stack: a ray walks one table from entry 0 until it reaches the end;
 *  - the table is picked by the ray direction's largest component and its sign, so the walk is roughly front
 *    to back, and a closest-hit query prunes every box that starts beyond its closest hit so far;
 *  - the textbook float slab test (reciprocal direction, near and far planes picked by the direction's sign,
 *    no padding, a NaN plane (0 * inf) ignored by the comparisons: that axis stays open);
 *  - triangles by the plane-then-inside test of many textbooks (Shirley; Scratchapixel): the crossing of the
 *    triangle's plane t = n.(p0 - o) / n.d, the hit point p = o + t d, then three edge functions
 *    n.((pj - pi) x (p - pi)) >= 0, all in float, from a per-triangle record (unit normal and twice the area
 *    precomputed in double and stored as float, so that the products stay in float's range on the nest's
 *    2^-36 to 2^36 triangles); u and v are two edge functions over twice the area;
 *  - spheres by the half-b quadratic in double, the smaller root computed stably (q = -(b + sign(b) sqrt));
 *  - it claims neither watertightness nor the tie rule, and counts its traversal (one node per box tested).
 *
 * THREADED_BUG=n builds one mistake natural to this design (tests/test_grade_threaded.cpp grades them; the
 * table of what the grader catches is in docs/grading.md, "The thirteenth round: a threaded BVH"):
 *   1 swapped-escape     a node's escape links set by left and right, not by the order of the table: the left
 *                        child escapes to the right one and the right child to its parent's escape. Right in
 *                        the tables that visit the left child first; in the others the right child, visited
 *                        first, escapes past its sibling, and the left subtree is never reached
 *   2 fixed-order        every ray walks the +x table ("the order is just an optimisation"): right answers,
 *                        the walk is back to front for half the rays and prunes less (performance only)
 *   3 sphere-no-shrink   the closest-hit walk keeps a sphere hit but does not shrink its bound to it (the
 *                        triangle test writes the bound through a pointer, the sphere test into a copy): a
 *                        farther primitive tested later replaces it
 *   4 type-split         after the links are made, the primitives are split into triangles first and spheres
 *                        after ("one kernel per type"), but the leaves keep their old ranges: in a scene of
 *                        triangles and spheres together leaves name other primitives
 *   5 root-miss-zero     the root's miss link left 0 (calloc) instead of the end: a ray that misses the whole
 *                        scene's box walks back to the root, forever
 *   6 escape-by-count    the escape computed as the entry plus 2 m - 1 for a subtree over m primitives ("a
 *                        binary tree over m leaves has 2 m - 1 nodes"): right where every leaf holds one
 *                        primitive, too far past a leaf of several (box centres that coincide)
 *   7 anyhit-break       any-hit ends the walk at the first box that starts beyond tmax ("the table is sorted
 *                        front to back"): the table's order is by box centres, not by where the ray enters
 *   8 anyhit-no-exit     any-hit remembers a hit and walks on to the end of the table (right answers, more
 *                        work: performance only)
 *   9 last-entry-skipped the walk stops one entry before the end of its table ("the last entry is the end
 *                        marker", as in the GPU code it was ported from, which appends one): every table's
 *                        last entry, a leaf, is never tested, so each direction loses one primitive
 *  10 unsorted-roots     the stable quadratic's roots q / a and c / q taken in that order, without the swap:
 *                        for a sphere ahead of the origin q / a is the far root, reported while the near one
 *                        is in the interval too
 *  11 origin-edges       the edge functions in the ray's space (Kensler and Shirley's form): triple products
 *                        d . ((pa - o) x (pb - o)) of the vertices relative to the origin, in float. Right at
 *                        unit scale; a triangle of edge e seen from a distance S rounds them by about u S^2,
 *                        an error of u S (S / e) across its edges: small triangles far from the origin gain
 *                        and lose crossings far inside them
 */
#include "twinray_plugin.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef THREADED_BUG
#define THREADED_BUG 0
#endif

#define TABLES 6

typedef struct box {
  float lo[3], hi[3];
} box;

typedef struct item {
  unsigned index;   /* mesh index (into geometry.meshes) or sphere index */
  unsigned prim_id; /* triangle index within its mesh; 0 for a sphere */
  unsigned sphere;  /* 1 for a sphere */
} item;

/* A triangle as the inside test wants it (float, precomputed in double). */
typedef struct tri_record {
  float p[3][3];
  float n[3];  /* unit normal, normalize(cross(p1 - p0, p2 - p0)) */
  float area2; /* |cross(p1 - p0, p2 - p0)| */
} tri_record;

typedef struct bnode {
  box bounds;
  unsigned child[2]; /* interior: the two children */
  unsigned first, count; /* leaf: count > 0 items from first */
  unsigned prims;        /* primitives in the subtree */
  unsigned size;         /* nodes in the subtree */
} bnode;

typedef struct thread_link {
  unsigned node;
  unsigned hit;  /* entry to go to when the node's box is entered */
  unsigned miss; /* entry to go to when it is not: the entry after the node's subtree */
} thread_link;

typedef struct threaded {
  twinray_geometry geometry;
  size_t count;       /* primitives */
  item* items;        /* in leaf order */
  tri_record* tris;   /* per item (triangles only) */
  bnode* nodes;       /* build tree, root 0 */
  unsigned node_count;
  thread_link* table[TABLES];
  size_t depth, leaves;
  double sah;
} threaded;

static void* threaded_create(void) { return calloc(1, sizeof(threaded)); }

static void threaded_destroy(void* self) {
  threaded* b = (threaded*)self;
  int k;
  if (b == NULL) return;
  free(b->items);
  free(b->tris);
  free(b->nodes);
  for (k = 0; k < TABLES; ++k) free(b->table[k]);
  free(b);
}

static const float* vertex(const twinray_mesh* mesh, unsigned prim_id, int k) {
  return mesh->positions + 3 * (size_t)mesh->indices[3 * (size_t)prim_id + (size_t)k];
}

static void box_empty(box* b) {
  int k;
  for (k = 0; k < 3; ++k) {
    b->lo[k] = (float)HUGE_VAL;
    b->hi[k] = -(float)HUGE_VAL;
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

static void item_box(const twinray_geometry* g, const item* p, box* out) {
  int k, j;
  if (p->sphere) {
    const twinray_sphere* s = &g->spheres[p->index];
    /* Rounded to nearest, possibly a hair inside the true extent: only a ray touching the silhouette within
       that rounding could be lost, and a grazing answer is either way right. */
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

static void set_error(char* error, size_t capacity, const char* message) {
  size_t k;
  if (capacity == 0) return;
  for (k = 0; k + 1 < capacity && message[k] != '\0'; ++k) error[k] = message[k];
  error[k] = '\0';
}

/* ---- build ---------------------------------------------------------------------------------------------- */

typedef struct builder {
  const twinray_geometry* g;
  item* items;
  box* boxes;     /* per item, permuted with it */
  float* centres; /* 3 per item, permuted with it */
  bnode* nodes;
  unsigned used;
} builder;

static void swap_items(builder* s, size_t i, size_t j) {
  item ti = s->items[i];
  box tb = s->boxes[i];
  float tc[3];
  memcpy(tc, &s->centres[3 * i], sizeof tc);
  s->items[i] = s->items[j];
  s->boxes[i] = s->boxes[j];
  memcpy(&s->centres[3 * i], &s->centres[3 * j], sizeof tc);
  s->items[j] = ti;
  s->boxes[j] = tb;
  memcpy(&s->centres[3 * j], tc, sizeof tc);
}

/* Hoare's quickselect: afterwards the item at kth has every item before it <= and after it >= on `axis`.
   Equal keys are swapped across (Hoare), so ranges of equal keys still split in the middle. */
static void select_kth(builder* s, size_t lo, size_t hi, size_t kth, int axis) {
  while (hi > lo) {
    float pivot;
    size_t i = lo, j = hi;
    {
      float a = s->centres[3 * lo + (size_t)axis], b = s->centres[3 * ((lo + hi) / 2) + (size_t)axis],
            c = s->centres[3 * hi + (size_t)axis];
      pivot = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b)); /* median of three */
    }
    for (;;) {
      while (s->centres[3 * i + (size_t)axis] < pivot) ++i;
      while (s->centres[3 * j + (size_t)axis] > pivot) --j;
      if (i >= j) break;
      swap_items(s, i, j);
      ++i;
      --j;
    }
    /* [lo, j] <= pivot <= [j + 1, hi] */
    if (kth <= j)
      hi = j;
    else
      lo = j + 1;
  }
}

static unsigned build_node(builder* s, size_t first, size_t count, size_t depth, size_t* max_depth) {
  unsigned id = s->used++;
  bnode* n = &s->nodes[id];
  box centres;
  size_t i;
  int axis = 0, k;
  float extent = 0.0f;
  if (depth > *max_depth) *max_depth = depth;
  box_empty(&n->bounds);
  box_empty(&centres);
  for (i = first; i < first + count; ++i) {
    box c;
    box_grow(&n->bounds, &s->boxes[i]);
    for (k = 0; k < 3; ++k) c.lo[k] = c.hi[k] = s->centres[3 * i + (size_t)k];
    box_grow(&centres, &c);
  }
  for (k = 0; k < 3; ++k)
    if (centres.hi[k] - centres.lo[k] > extent) {
      extent = centres.hi[k] - centres.lo[k];
      axis = k;
    }
  n->prims = (unsigned)count;
  if (count == 1 || extent == 0.0f) { /* one primitive, or nothing to split them by */
    n->first = (unsigned)first;
    n->count = (unsigned)count;
    n->child[0] = n->child[1] = 0;
    n->size = 1;
    return id;
  }
  {
    size_t half = count / 2;
    unsigned left, right;
    select_kth(s, first, first + count - 1, first + half, axis);
    left = build_node(s, first, half, depth + 1, max_depth);
    right = build_node(s, first + half, count - half, depth + 1, max_depth);
    n = &s->nodes[id];
    n->child[0] = left;
    n->child[1] = right;
    n->first = 0;
    n->count = 0;
    n->size = 1 + s->nodes[left].size + s->nodes[right].size;
  }
  return id;
}

/* Which child the table for direction `dir` (0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z) visits first: the one whose
   box centre comes first along that direction. */
static int first_child(const bnode* nodes, const bnode* n, int dir) {
  int axis = dir / 2;
  float c0 = nodes[n->child[0]].bounds.lo[axis] + nodes[n->child[0]].bounds.hi[axis];
  float c1 = nodes[n->child[1]].bounds.lo[axis] + nodes[n->child[1]].bounds.hi[axis];
  if (dir % 2 == 0) return c1 < c0 ? 1 : 0;
  return c0 < c1 ? 1 : 0;
}

/* The number of entries a subtree takes in a table. */
static unsigned subtree_entries(const bnode* n) {
#if THREADED_BUG == 6
  return 2 * n->prims - 1;
#else
  return n->size;
#endif
}

/* Writes node `id`'s subtree into `table` from entry *next on, in pre-order with the first child of direction
   `dir` first; `escape` is the entry after the subtree. Recursion depth: the tree's (object-median splits
   halve the range, so about log2 of the primitives). */
static void thread_subtree(const bnode* nodes, thread_link* table, unsigned id, unsigned* next, unsigned escape,
                           int dir) {
  const bnode* n = &nodes[id];
  unsigned at = (*next)++;
  table[at].node = id;
  table[at].miss = escape;
  if (n->count > 0) {
    table[at].hit = escape;
    return;
  }
  table[at].hit = at + 1;
  {
    int f = first_child(nodes, n, dir);
    unsigned near_child = n->child[f], far_child = n->child[1 - f];
    unsigned near_escape = at + 1 + subtree_entries(&nodes[near_child]);
#if THREADED_BUG == 1
    /* the left child escapes to the right one's entry, the right child to its parent's escape, as if the
       left child were always first */
    if (f == 0) {
      thread_subtree(nodes, table, near_child, next, near_escape, dir);
      thread_subtree(nodes, table, far_child, next, escape, dir);
    } else {
      thread_subtree(nodes, table, near_child, next, escape, dir);
      thread_subtree(nodes, table, far_child, next, at + 1, dir);
    }
#else
    thread_subtree(nodes, table, near_child, next, near_escape, dir);
    thread_subtree(nodes, table, far_child, next, escape, dir);
#endif
  }
}

static void make_tri_record(const twinray_mesh* mesh, unsigned prim_id, tri_record* r) {
  double e1[3], e2[3], n[3], len;
  int k, j;
  for (j = 0; j < 3; ++j) {
    const float* v = vertex(mesh, prim_id, j);
    for (k = 0; k < 3; ++k) r->p[j][k] = v[k];
  }
  for (k = 0; k < 3; ++k) {
    e1[k] = (double)r->p[1][k] - r->p[0][k];
    e2[k] = (double)r->p[2][k] - r->p[0][k];
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (k = 0; k < 3; ++k) r->n[k] = (float)(n[k] / len);
  r->area2 = (float)len;
}

static double subtree_sah(const bnode* nodes, unsigned id, double root_area) {
  const bnode* n = &nodes[id];
  if (n->count > 0) return box_area(&n->bounds) / root_area * n->count;
  return box_area(&n->bounds) / root_area + subtree_sah(nodes, n->child[0], root_area) +
         subtree_sah(nodes, n->child[1], root_area);
}

static int threaded_build(void* self, const twinray_geometry* g, char* error, size_t error_capacity) {
  threaded* b = (threaded*)self;
  builder s;
  size_t n = 0, m, i;
  int dir;
  b->geometry = *g;
  for (m = 0; m < g->mesh_count; ++m) n += g->meshes[m].triangle_count;
  n += g->sphere_count;
  if (n >= 0x7FFFFFFFu) {
    set_error(error, error_capacity, "threaded: more than 2^31 primitives");
    return TWINRAY_ERROR;
  }
  b->count = n;
  if (n == 0) return TWINRAY_OK;
  s.g = g;
  s.items = (item*)malloc(n * sizeof(item));
  s.boxes = (box*)malloc(n * sizeof(box));
  s.centres = (float*)malloc(3 * n * sizeof(float));
  s.nodes = (bnode*)malloc((2 * n - 1) * sizeof(bnode));
  s.used = 0;
  b->tris = (tri_record*)malloc(n * sizeof(tri_record));
  if (!s.items || !s.boxes || !s.centres || !s.nodes || !b->tris) {
    free(s.items);
    free(s.boxes);
    free(s.centres);
    free(s.nodes);
    set_error(error, error_capacity, "threaded: out of memory");
    return TWINRAY_ERROR;
  }
  n = 0;
  for (m = 0; m < g->mesh_count; ++m)
    for (i = 0; i < g->meshes[m].triangle_count; ++i) {
      s.items[n].index = (unsigned)m;
      s.items[n].prim_id = (unsigned)i;
      s.items[n].sphere = 0;
      ++n;
    }
  for (m = 0; m < g->sphere_count; ++m) {
    s.items[n].index = (unsigned)m;
    s.items[n].prim_id = 0;
    s.items[n].sphere = 1;
    ++n;
  }
  for (i = 0; i < n; ++i) {
    int k;
    item_box(g, &s.items[i], &s.boxes[i]);
    for (k = 0; k < 3; ++k) s.centres[3 * i + (size_t)k] = 0.5f * (s.boxes[i].lo[k] + s.boxes[i].hi[k]);
  }
  build_node(&s, 0, n, 0, &b->depth);
  free(s.boxes);
  free(s.centres);
  b->items = s.items;
  b->nodes = s.nodes;
  b->node_count = s.used;
  for (dir = 0; dir < TABLES; ++dir) {
    b->table[dir] = (thread_link*)malloc((size_t)b->node_count * sizeof(thread_link));
    if (!b->table[dir]) {
      set_error(error, error_capacity, "threaded: out of memory");
      return TWINRAY_ERROR; /* destroy frees what was made */
    }
    {
      unsigned next = 0;
      thread_subtree(b->nodes, b->table[dir], 0, &next, b->node_count, dir);
    }
#if THREADED_BUG == 5
    b->table[dir][0].miss = 0; /* "the root has no escape" (calloc'd tables in the original) */
#endif
  }
#if THREADED_BUG == 4
  { /* one kernel per type: triangles first, then spheres (a stable split), after the leaves were set */
    item* split = (item*)malloc(n * sizeof(item));
    size_t at = 0;
    if (split) {
      for (i = 0; i < n; ++i)
        if (!b->items[i].sphere) split[at++] = b->items[i];
      for (i = 0; i < n; ++i)
        if (b->items[i].sphere) split[at++] = b->items[i];
      memcpy(b->items, split, n * sizeof(item));
      free(split);
    }
  }
#endif
  for (i = 0; i < n; ++i)
    if (!b->items[i].sphere) make_tri_record(&g->meshes[b->items[i].index], b->items[i].prim_id, &b->tris[i]);
  {
    double a = box_area(&b->nodes[0].bounds);
    unsigned k;
    for (k = 0; k < b->node_count; ++k)
      if (b->nodes[k].count > 0) ++b->leaves;
    b->sah = a > 0.0 ? subtree_sah(b->nodes, 0, a) : 0.0;
  }
  return TWINRAY_OK;
}

/* ---- queries -------------------------------------------------------------------------------------------- */

typedef struct ray_ctx {
  float org[3], dir[3], inv[3];
  int neg[3];
} ray_ctx;

static void make_ray(const twinray_ray* ray, ray_ctx* r) {
  int k;
  for (k = 0; k < 3; ++k) {
    r->org[k] = ray->org[k];
    r->dir[k] = ray->dir[k];
    r->inv[k] = 1.0f / ray->dir[k]; /* +-inf for a zero component, with its sign */
    r->neg[k] = r->inv[k] < 0.0f;
  }
}

#if THREADED_BUG != 2
static float abs_float(float x) { return x < 0.0f ? -x : x; } /* C89 has no fabsf */
#endif

/* The table of the direction's largest component and its sign. */
static int pick_table(const ray_ctx* r) {
#if THREADED_BUG == 2
  (void)r;
  return 0;
#else
  float ax = abs_float(r->dir[0]), ay = abs_float(r->dir[1]), az = abs_float(r->dir[2]);
  int axis = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
  return 2 * axis + r->neg[axis];
#endif
}

/* The textbook slab test in float, cut to [tmin, tmax]; *near_out is where the ray enters. A NaN plane
   (0 * inf: the origin exactly on a plane the ray runs in) fails the comparisons and leaves that axis open. */
static int slab(const ray_ctx* r, const box* b, float tmin, float tmax, float* near_out) {
  float tn = tmin, tf = tmax;
  int k;
  for (k = 0; k < 3; ++k) {
    float t0 = ((r->neg[k] ? b->hi[k] : b->lo[k]) - r->org[k]) * r->inv[k];
    float t1 = ((r->neg[k] ? b->lo[k] : b->hi[k]) - r->org[k]) * r->inv[k];
    if (t0 > tn) tn = t0;
    if (t1 < tf) tf = t1;
  }
  *near_out = tn;
  return tn <= tf;
}

/* The plane, then the inside test by edge functions, all in float. */
static int hit_triangle(const ray_ctx* r, const tri_record* tr, float tmin, float tmax, float* t_out,
                        float* u_out, float* v_out) {
  float ndotd = tr->n[0] * r->dir[0] + tr->n[1] * r->dir[1] + tr->n[2] * r->dir[2];
  float t, p[3], w[3];
  int k, e;
  if (ndotd == 0.0f) return 0; /* parallel to the plane */
  t = (tr->n[0] * (tr->p[0][0] - r->org[0]) + tr->n[1] * (tr->p[0][1] - r->org[1]) +
       tr->n[2] * (tr->p[0][2] - r->org[2])) /
      ndotd;
  if (!(t >= tmin && t <= tmax)) return 0;
#if THREADED_BUG == 11
  (void)p;
  {
    float rel[3][3], det;
    for (e = 0; e < 3; ++e)
      for (k = 0; k < 3; ++k) rel[e][k] = tr->p[e][k] - r->org[k];
    for (e = 0; e < 3; ++e) {
      const float* pa = rel[(e + 1) % 3];
      const float* pb = rel[(e + 2) % 3];
      w[e] = r->dir[0] * (pa[1] * pb[2] - pa[2] * pb[1]) + r->dir[1] * (pa[2] * pb[0] - pa[0] * pb[2]) +
             r->dir[2] * (pa[0] * pb[1] - pa[1] * pb[0]);
    }
    if (!((w[0] >= 0.0f && w[1] >= 0.0f && w[2] >= 0.0f) || (w[0] <= 0.0f && w[1] <= 0.0f && w[2] <= 0.0f)))
      return 0;
    det = w[0] + w[1] + w[2];
    if (det == 0.0f) return 0;
    *t_out = t;
    *u_out = w[1] / det;
    *v_out = w[2] / det;
    return 1;
  }
#endif
  for (k = 0; k < 3; ++k) p[k] = r->org[k] + t * r->dir[k];
  /* w[e]: the edge function of the edge opposite vertex e, n . ((p_b - p_a) x (p - p_a)) */
  for (e = 0; e < 3; ++e) {
    const float* pa = tr->p[(e + 1) % 3];
    const float* pb = tr->p[(e + 2) % 3];
    float ed[3], vp[3], c[3];
    for (k = 0; k < 3; ++k) {
      ed[k] = pb[k] - pa[k];
      vp[k] = p[k] - pa[k];
    }
    c[0] = ed[1] * vp[2] - ed[2] * vp[1];
    c[1] = ed[2] * vp[0] - ed[0] * vp[2];
    c[2] = ed[0] * vp[1] - ed[1] * vp[0];
    w[e] = tr->n[0] * c[0] + tr->n[1] * c[1] + tr->n[2] * c[2];
    if (w[e] < 0.0f) return 0;
  }
  *t_out = t;
  *u_out = w[1] / tr->area2;
  *v_out = w[2] / tr->area2;
  return 1;
}

/* |o + t d - c|^2 = r^2 with half b, in double; the smaller root without cancellation. Returns the first
   root in [tmin, tmax]. */
static int hit_sphere(const ray_ctx* r, const twinray_sphere* s, float tmin, float tmax, float* t_out,
                      double* td_out) {
  double oc[3], a, hb, c, disc, q, roots[2];
  int k;
  for (k = 0; k < 3; ++k) oc[k] = (double)r->org[k] - s->center[k];
  a = (double)r->dir[0] * r->dir[0] + (double)r->dir[1] * r->dir[1] + (double)r->dir[2] * r->dir[2];
  hb = oc[0] * r->dir[0] + oc[1] * r->dir[1] + oc[2] * r->dir[2];
  c = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - (double)s->radius * s->radius;
  disc = hb * hb - a * c;
  if (disc < 0.0) return 0;
  q = -(hb + (hb >= 0.0 ? sqrt(disc) : -sqrt(disc)));
  if (q == 0.0) { /* hb == 0 and c == 0: the origin on the sphere, the ray tangent */
    roots[0] = roots[1] = 0.0;
  } else {
    roots[0] = q / a;
    roots[1] = c / q;
#if THREADED_BUG == 10
    if (0) {
#else
    if (roots[1] < roots[0]) {
#endif
      double tmp = roots[0];
      roots[0] = roots[1];
      roots[1] = tmp;
    }
  }
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

/* One walk for both queries: any != 0 answers whether anything lies in the interval. */
static int walk(const threaded* b, const twinray_ray* ray, int any, twinray_hit* hit, twinray_query_stats* stats) {
  ray_ctx r;
  const thread_link* table;
  unsigned at, end;
  float best = ray->tmax;
  const item* best_item = NULL;
  double best_td = 0.0;
  float best_u = 0.0f, best_v = 0.0f;
#if THREADED_BUG == 8
  int occluded = 0;
#endif
  if (b->count == 0) return 0;
  make_ray(ray, &r);
  table = b->table[pick_table(&r)];
#if THREADED_BUG == 9
  end = b->node_count - 1;
#else
  end = b->node_count;
#endif
  at = 0;
  while (at < end) {
    const thread_link* e = &table[at];
    const bnode* n = &b->nodes[e->node];
    float near_t;
    ++stats->nodes_visited;
    if (!slab(&r, &n->bounds, ray->tmin, best, &near_t)) {
#if THREADED_BUG == 7
      if (any && near_t > ray->tmax) break; /* "everything after this starts farther still" */
#endif
      at = e->miss;
      continue;
    }
    if (n->count > 0) {
      unsigned k;
      for (k = n->first; k < n->first + n->count; ++k) {
        const item* p = &b->items[k];
        float t, u = 0.0f, v = 0.0f;
        double td = 0.0;
        int found;
        ++stats->primitives_tested;
        if (p->sphere) {
#if THREADED_BUG == 3
          float bound = best; /* the sphere's test gets a copy of the bound, and the copy shrinks */
          found = hit_sphere(&r, &b->geometry.spheres[p->index], ray->tmin, bound, &t, &td);
          if (found) {
            bound = t;
            (void)bound;
            best_item = p;
            best_td = td;
            if (any) return 1;
          }
          continue;
#else
          found = hit_sphere(&r, &b->geometry.spheres[p->index], ray->tmin, best, &t, &td);
#endif
        } else {
          found = hit_triangle(&r, &b->tris[k], ray->tmin, best, &t, &u, &v);
        }
        if (found) {
#if THREADED_BUG == 8
          if (any) {
            occluded = 1;
            continue;
          }
#else
          if (any) return 1;
#endif
          best = t;
          best_item = p;
          best_td = td;
          best_u = u;
          best_v = v;
        }
      }
    }
    at = e->hit;
  }
#if THREADED_BUG == 8
  if (any) return occluded;
#endif
  if (best_item == NULL) return 0;
#if THREADED_BUG == 3
  if (best_item->sphere) { /* the sphere's own t, as its test found it */
    float t;
    double td;
    hit_sphere(&r, &b->geometry.spheres[best_item->index], ray->tmin, ray->tmax, &t, &td);
    best = t;
    best_td = td;
  }
#endif
  hit->t = best;
  hit->geom_id = best_item->sphere ? b->geometry.spheres[best_item->index].geom_id
                                   : b->geometry.meshes[best_item->index].geom_id;
  hit->prim_id = best_item->prim_id;
  if (best_item->sphere) {
    sphere_attributes(&r, &b->geometry.spheres[best_item->index], best_td, hit);
  } else {
    const tri_record* tr = &b->tris[best_item - b->items];
    int k;
    hit->u = best_u;
    hit->v = best_v;
    for (k = 0; k < 3; ++k) hit->ng[k] = tr->n[k];
  }
  return 1;
}

static int threaded_intersect1(const void* self, const twinray_ray* ray, twinray_hit* hit,
                               twinray_query_stats* stats) {
  return walk((const threaded*)self, ray, 0, hit, stats);
}

static int threaded_occluded1(const void* self, const twinray_ray* ray, twinray_query_stats* stats) {
  twinray_hit unused;
  return walk((const threaded*)self, ray, 1, &unused, stats);
}

static void threaded_build_stats(const void* self, twinray_build_stats* stats) {
  const threaded* b = (const threaded*)self;
  stats->memory_bytes = sizeof(threaded) + b->count * (sizeof(item) + sizeof(tri_record)) +
                        (size_t)b->node_count * (sizeof(bnode) + TABLES * sizeof(thread_link));
  stats->nodes = b->node_count;
  stats->leaves = b->leaves;
  stats->max_depth = b->depth;
  stats->sah_cost = b->sah;
}

static const twinray_plugin_v1 threaded_table = {
    TWINRAY_PLUGIN_ABI_VERSION,
    "threaded-c",
    TWINRAY_PLUGIN_COUNTS_TRAVERSAL, /* neither watertight nor the tie rule */
    threaded_create,
    threaded_destroy,
    threaded_build,
    threaded_intersect1,
    threaded_occluded1,
    NULL,
    NULL,
    threaded_build_stats,
};

TWINRAY_PLUGIN_EXPORT const twinray_plugin_v1* twinray_plugin_entry(void) { return &threaded_table; }
