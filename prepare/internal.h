/*
 * prepare/internal.h -- what the files of prepare/ share (not public): the
 * welded seams being carried through the steps, the step report, the plan
 * (options with their defaults filled in), half-edges sorted by edge, small
 * vector helpers, and each step's entry point. The steps and their files:
 *
 *   1. weld              prepare/weld.c     (also the sorted half-edges)
 *   2-3. repair, fragments prepare/repair.c
 *   4. decimate          prepare/decimate.c (thinning; CGAL edge collapse in prepare/cgal_shim.cpp)
 *   4-5. remesh          prepare/remesh.c   (edge choice, corners, CGAL isotropic remeshing)
 *   6-7. poses, labels, Hausdorff distance  prepare/carry.c
 *   automatic mode       prepare/auto.c
 *   the driver, seams as polylines, the public functions  prepare/prepare.c
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PREPARE_INTERNAL_H
#define PZ_PREPARE_INTERNAL_H

#include "prepare/prepare.h"

#include "core/util.h"
#include "prepare/cgal_shim.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* ------------------------------------------------------------------------ */
/* State shared by the steps                                                 */
/* ------------------------------------------------------------------------ */

/* Undirected edges as vertex pairs: the welded seams of the working mesh. */
typedef struct prep_edge_list {
    int32_t count;
    size_t capacity;
    int32_t *pairs;
} prep_edge_list;

/* Appends the edge a-b (stored low index first); 0 when out of memory. */
static inline int prep_edge_list_add(prep_edge_list *list, int32_t a, int32_t b)
{
    if (!pz_grow((void **)&list->pairs, &list->capacity, 2 * (size_t)list->count + 2, sizeof(int32_t)))
        return 0;
    list->pairs[2 * list->count] = a < b ? a : b;
    list->pairs[2 * list->count + 1] = a < b ? b : a;
    ++list->count;
    return 1;
}

typedef struct prep_step_state {
    pz_ctx *ctx;
    const char *name;
    pz_prepare_report *report;
} prep_step_state;

/* Records a step's outcome and notes it on stderr ("NAME: prepare: STEP: detail"). (prepare/prepare.c) */
void prep_step_done(prep_step_state *state, pz_prepare_step_id id, int ran, double started, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

/* The options with their defaults filled in (prepare/prepare.c: fill_plan). */
typedef struct prep_plan {
    double weld, fraction, target_edge;
    int32_t target_faces;
    int iterations;
} prep_plan;

/* ------------------------------------------------------------------------ */
/* Small helpers                                                             */
/* ------------------------------------------------------------------------ */

static inline int prep_is_finite3(const double *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

/* Twice-area vector of the triangle a b c: (b - a) x (c - a). */
static inline void prep_face_normal(const double *a, const double *b, const double *c, double n[3])
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

static inline double prep_squared_distance3(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
}

static inline double prep_distance3(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* A half-edge keyed by its undirected edge, for sorting. */
typedef struct prep_halfedge_key {
    int32_t lo, hi, halfedge, pad;
} prep_halfedge_key;

/*
 * Every half-edge of `faces` with its undirected key, sorted by (lo, hi,
 * half-edge): equal edges are adjacent. NULL when out of memory; the caller
 * frees the array. (prepare/weld.c)
 */
prep_halfedge_key *prep_sorted_halfedges(const int32_t *faces, int32_t face_count);

/* The end of the run of keys with the same edge as keys[begin]. */
static inline size_t prep_group_end(const prep_halfedge_key *keys, size_t count, size_t begin)
{
    size_t end = begin + 1;
    while (end < count && keys[end].lo == keys[begin].lo && keys[end].hi == keys[begin].hi)
        ++end;
    return end;
}

/* ------------------------------------------------------------------------ */
/* The steps                                                                 */
/* ------------------------------------------------------------------------ */

/* 1. Welds vertices closer than `distance` in place; the welded seams go to `seams`. (prepare/weld.c) */
pz_status prep_weld(pz_mesh *mesh, double distance, prep_edge_list *seams, int32_t *welded, pz_ctx *ctx);

/* 2. Repairs in place (only the passes a validation calls for), seams followed. (prepare/repair.c) */
pz_status prep_repair(pz_mesh *mesh, const char *name, prep_edge_list *seams, pz_prepare_report *report,
                      pz_ctx *ctx);

/* 3. Drops the components under `fraction` of the area unless `keep` says all. (prepare/repair.c) */
pz_status prep_drop_fragments(pz_mesh *mesh, const char *name, double fraction, pz_prepare_keep keep,
                              prep_edge_list *seams, pz_prepare_report *report, pz_ctx *ctx);

/*
 * 4. Thins `in` (manifold, oriented) towards target_faces, no new edge longer
 * than max_edge; *out gets the result (malloc'd, seams renumbered).
 * (prepare/decimate.c)
 */
pz_status prep_thin_out(const pz_cgal_surface *in, int32_t target_faces, double max_edge, pz_cgal_surface *out,
                        pz_ctx *ctx);

/*
 * 4-5. Decimates when needed and remeshes `work`: *out gets the new mesh,
 * *remeshed the CGAL surface with its seams; the report and the two steps'
 * details are filled (`why` is appended to the remesh detail).
 * (prepare/remesh.c)
 */
pz_status prep_decimate_and_remesh(const pz_mesh *work, const prep_edge_list *seams, const char *name,
                                   const prep_plan *plan, const char *why, pz_mesh **out,
                                   pz_cgal_surface *remeshed, prep_step_state *state, pz_ctx *ctx);

/* 6-7. Carries poses and labels from `work` to `output` and measures the Hausdorff distances. (prepare/carry.c) */
pz_status prep_carry_and_measure(const pz_mesh *work, pz_mesh *output, prep_step_state *state, pz_ctx *ctx);

/* Face fraction whose smallest angle exceeds 20 degrees (1 for no faces, 0 when out of memory). (prepare/prepare.c) */
double prep_well_shaped_fraction(const pz_mesh *mesh);

/* Steps 4-7 when remeshing: result->mesh and its seams. (prepare/prepare.c) */
pz_status prep_remesh_all(const pz_mesh *work, const prep_edge_list *seams, const char *name, const prep_plan *plan,
                          const char *why, pz_prepare_result *result, prep_step_state *state, pz_ctx *ctx);

/* ------------------------------------------------------------------------ */
/* Automatic mode (prepare/auto.c)                                           */
/* ------------------------------------------------------------------------ */

typedef enum prep_auto_need { PREP_NEED_NOTHING = 0, PREP_NEED_DENSITY, PREP_NEED_SHAPE } prep_auto_need;

/* What automatic mode does with `work`: the face count to remesh to in plan->target_faces, why in `why`. */
prep_auto_need prep_auto_decide(const pz_mesh *work, const pz_prepare_options *options, double well_shaped,
                                prep_plan *plan, char *why, size_t size);

/*
 * A remesh for density beyond the Hausdorff bound: tried again with more
 * faces; *undone set (and result emptied) when no remesh fits the bound.
 */
pz_status prep_retry_denser(const pz_mesh *work, const prep_edge_list *seams, const char *name, prep_plan *plan,
                            double work_shaped, char *why, size_t size, int *undone, pz_prepare_result *result,
                            prep_step_state *state, pz_ctx *ctx);

/* A remesh for shape that moved the shape too much is undone: `why` says what was tried. */
void prep_undo_remesh(pz_prepare_result *result, char *why, size_t size);

#endif /* PZ_PREPARE_INTERNAL_H */
