/*
 * param/springmass_internal.h -- the parts of the spring-mass back-end
 * (pz_param_springmass; the method: param/springmass.c) and what they share.
 *
 * Files:
 *   springmass_panel.c    set-up of one panel: its edges, rest lengths,
 *                         heights, areas, adjacency and boundary distances;
 *                         the indexed heap; the energies (Eqs. 1-6, 9)
 *   springmass_release.c  solve: node relaxation, energy release, the
 *                         global release (CHOLMOD, the spring Laplacian's
 *                         symbolic analysis kept per piece: sm_spring),
 *                         phase one, phase two
 *   springmass_match.c    solve: seam matching (outlines refitted to equal
 *                         segment lengths, interiors released again)
 *   springmass_report.c   report: energy map, cutting line, trial cut,
 *                         energy.svg, pz_springmass_result_clear
 *   springmass.c          the driver: pieces, second tries, the result
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PARAM_SPRINGMASS_INTERNAL_H
#define PZ_PARAM_SPRINGMASS_INTERNAL_H

#include "param/internal.h"

#include <math.h>

#define SM_PI 3.14159265358979323846
#define SM_SPRING_C 0.5          /* wang2002 Sec. 5: C = 0.5 */
#define PENALTY_FRACTION 0.2     /* Eq. 14 applies when h_j < this * h_j* */
#define CONSTRAINED_STEPS 20     /* node minimization of a constrained corner */
#define CREST_STOP_FRACTION 0.1  /* the cutting line ends below this fraction of the maximum energy */

/* Indexed max-heap over ids with external keys (springmass_panel.c). */
typedef struct sm_heap {
    int32_t count;
    int32_t *items;     /* heap order */
    int32_t *where;     /* id -> index in items, -1 when absent */
    const double *key;  /* id -> key */
} sm_heap;

int sm_heap_init(sm_heap *h, int32_t capacity, const double *key);
void sm_heap_free(sm_heap *h);
/* Inserts id, or moves it after its key changed. */
void sm_heap_update(sm_heap *h, int32_t id);
int32_t sm_heap_pop(sm_heap *h);

typedef struct sm_settings {
    int heap;               /* 1 heap release, 0 full */
    int paths;              /* 1 single path, >= 2 multi-path cap */
    int orthotropic;
    pz_fabric fabric;
    double grain[3];
    int max_iterations, phase_one_iterations;
    double accuracy, energy_variation;
    int local_only;         /* phase two without the global release */
    int independent;        /* no seam matching */
} sm_settings;

/*
 * The spring Laplacian's symbolic analysis, kept for every global release of
 * one piece (phase two, the matched release, the second tries): its sparsity
 * pattern is the piece's edges whatever the pins, so it is analyzed once and
 * each release factorizes a copy (springmass_release.c). Zero it to start;
 * sm_spring_free releases it.
 */
typedef struct sm_spring {
    int started;
    cholmod_common common;     /* simplicial, quiet */
    cholmod_factor *symbolic;  /* NULL: none yet */
} sm_spring;

void sm_spring_free(sm_spring *spring);

/* Over-relaxation of the isotropic move in the whole-system sweeps of phase
 * two: plain Gauss-Seidel moves (omega = 1) spread a long-wavelength error by
 * one ring per sweep and the energy-variation rule then stops early, far
 * from the minimum; SOR with omega < 2 converges to the same minimum. */
#define PHASE_TWO_OMEGA 1.7

typedef struct sm_panel {
    const pz_mesh *mesh;
    pz_topology *topology;
    const sm_settings *settings;
    int32_t nv, nf, ne;
    int32_t *edge_vertices;    /* ne x 2 */
    double *rest;              /* ne: 3D edge lengths d_j */
    int32_t *vertex_edge_offsets, *vertex_edges;  /* CSR vertex -> edges */
    int32_t *vertex_face_offsets, *vertex_faces;  /* CSR vertex -> faces */
    double *height;            /* nf x 3: 3D distance of corner k to its opposite edge (h_j*) */
    double *area3d;            /* nf */
    double *boundary_distance; /* nv */
    double *medial;            /* nf */
    uint8_t *edge_active, *face_placed, *vertex_placed;
    int32_t *placed_order, placed_count;
    double *uv;                /* nv x 2 */
    double *energy;            /* nv: node energy (relaxation key) */
    double *delta;             /* nv: orthotropic trial step */
    double mean_edge;
    uint8_t *pinned;           /* nv or NULL: vertices the releases keep in place (a matched outline) */
    int32_t *loop, loop_count; /* the boundary loop (seam matching), local vertices in order */
    int32_t *loop_position;    /* nv: index in loop, -1 inside */
    sm_heap node_heap;         /* heap release only */
    double omega;              /* isotropic move scale: 1, or PHASE_TWO_OMEGA in phase two */
    sm_spring *spring;         /* the spring Laplacian's kept analysis (its piece's), or NULL: the release's own */
    pz_ctx *ctx;               /* cancellation (panel_init's) */
    long long relaxations, evaluations;
} sm_panel;

/* sqrt of the squares, not hypot: pattern coordinates are far from overflow, and glibc's hypot was a
 * quarter of the 20K-face run's time (perf) */
static inline double norm2d(double x, double y) { return sqrt(x * x + y * y); }

static inline double dist2d(const double *a, const double *b) { return norm2d(a[0] - b[0], a[1] - b[1]); }

static inline double dist3d(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* What one panel's flattening reports (into pz_springmass_panel and the sums). */
typedef struct sm_outcome {
    int stop, iterations;
    double phase_one_energy, final_energy, e_area, e_shape;
    double phase_one_ms, phase_two_ms;
    long long relaxations, phase_one_relaxations, evaluations;
    int global_iterations;
} sm_outcome;

/*
 * Sewing needs the two sides of a seam (the two legs of a dart) to have the
 * same length. Flattened alone, each panel's springs give its outline their
 * own compromise, and the sides of a seam came out up to 13 % apart on the
 * shared garments (docs/springmass.md). So every pair of facing segments
 * (a_i a_i+1 on one side, b_i b_i+1 on the other, as the pattern pairs
 * them; a dart's legs out to the tip) is a link, and after phase two both
 * segments get the mean of their 2D lengths. Each panel's outline is then
 * refitted with those edge lengths exactly (fit_loop: wang2008's
 * length-preserving boundary, Eqs. 2-8 for one loop, the target angles
 * being the outline's own turning angles, so it moves as little as the new
 * lengths allow), and its interior is released again with the outline
 * pinned. Matching segment by segment keeps facing notches together; only
 * lengths are shared, each panel keeps its own shape. A penalty coupling in
 * the releases was tried first: with stiff links the local-global release
 * converged slowly and panels held by the flip guard kept their partners
 * from matching (0.1-1.1 % left on the shared garments, energy up 30-150 %).
 */
typedef struct sm_link {
    int32_t curve;            /* seam s, or seam_count + dart d */
    int32_t panel[2];         /* side a's and side b's panel */
    int32_t end[2][2];        /* each side's segment: two local vertices of its panel */
    double rest;              /* mean 3D length of the two segments */
} sm_link;

/* springmass_panel.c */
pz_status sm_panel_init(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv, pz_ctx *ctx);
void sm_panel_free(sm_panel *p);
int32_t sm_edge_other(const sm_panel *p, int32_t e, int32_t v);
double sm_node_energy(sm_panel *p, int32_t v);
double sm_total_energy(sm_panel *p);
void sm_accuracy(const sm_panel *p, double *e_area, double *e_shape);

/* springmass_release.c */
int32_t sm_flipped_faces(const sm_panel *p);
void sm_place_vertex(sm_panel *p, int32_t v);
void sm_activate_face(sm_panel *p, int32_t f);
pz_status sm_panel_release(sm_panel *p, sm_outcome *outcome, pz_ctx *ctx);
/* Phase one and two of one disk mesh into uv; spring (may be NULL) keeps the global release's analysis. */
pz_status sm_panel_flatten(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv,
                           sm_spring *spring, sm_outcome *outcome, pz_ctx *ctx);
pz_status sm_panel_finish(sm_panel *p, sm_outcome *outcome, double *map, int32_t *line, int32_t *line_count,
                          pz_ctx *ctx);
pz_status sm_flatten_disk(const pz_mesh *mesh, const sm_settings *settings, double *uv, sm_outcome *outcome,
                          pz_ctx *ctx);

/* springmass_match.c */
int32_t sm_build_links(const pz_pattern *pattern, int32_t *const *vertex_maps, const sm_panel *panels, sm_link **out);
int sm_panel_loop(sm_panel *p, pz_ctx *ctx);
pz_status sm_match_seams(sm_panel *panels, int32_t panel_count, const sm_link *links, int32_t link_count,
                         sm_outcome *outcomes, int32_t *unmatched, pz_ctx *ctx);
double sm_worst_mismatch(const sm_panel *panels, const sm_link *links, int32_t link_count, int32_t curve_count);

/* springmass_report.c */
void sm_energy_map(sm_panel *p, double *out);
int32_t sm_crest_line(const sm_panel *p, const double *map, int32_t *line);
pz_status sm_trial_cut(const pz_mesh *panel_mesh, const sm_settings *settings, const int32_t *line, int32_t line_count,
                       pz_springmass_panel *out, pz_ctx *ctx);

#endif /* PZ_PARAM_SPRINGMASS_INTERNAL_H */
