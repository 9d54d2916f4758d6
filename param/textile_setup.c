/*
 * param/textile_setup.c -- the set-up of the textile parameterization
 * (pz_textile_setup): the checks, the LSCM start, each face's 3D frames, the
 * seam and dart segments, the panels' outlines, and per panel the sparsity
 * pattern of its two systems with CHOLMOD's symbolic analysis. Also the
 * per-solve state (textile_state_begin / textile_state_end) and the
 * classification of seams that cannot be mirror images. The design and
 * the file map: param/textile_internal.h.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _DEFAULT_SOURCE /* getloadavg, sysconf */
#include "param/textile_internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* A solve of fewer iterations than this (the segmentation's evaluations: 5) factorizes each system a few times
 * only: the fill METIS saves does not pay for trying it (pz_param_analyze; docs/param.md, "Speed"). */
#define BRIEF_ITERATIONS 10
#include <unistd.h>

/* ------------------------------------------------------------------------ */
/* Freeing                                                                   */
/* ------------------------------------------------------------------------ */

/* The part of a coordinate's solver that belongs to one solve. */
static void solver_end(coordinate_solver *solver)
{
    if (!solver->started)
        return;
    cholmod_free_dense(&solver->work_e, &solver->common);
    cholmod_free_dense(&solver->work_y, &solver->common);
    cholmod_free_dense(&solver->solution, &solver->common);
    cholmod_free_dense(&solver->rhs, &solver->common);
    cholmod_free_dense(&solver->residual, &solver->common);
    free(solver->product);
    free(solver->current);
    free(solver->direction);
    free(solver->grain_gradient);
    free(solver->grain_response);
    solver->product = solver->current = solver->direction = solver->grain_gradient = solver->grain_response = NULL;
    cholmod_free_factor(&solver->factor, &solver->common);
}

static void solver_free(coordinate_solver *solver)
{
    if (!solver->started)
        return;
    solver_end(solver);
    cholmod_free_sparse(&solver->matrix, &solver->common);
    cholmod_finish(&solver->common);
    solver->started = 0;
}

void textile_state_end(textile_state *state)
{
    for (int32_t p = 0; state->panels && p < state->pattern->panel_count; ++p) {
        solver_end(&state->panels[p].solver[0]);
        solver_end(&state->panels[p].solver[1]);
    }
    free(state->terms);
    free(state->face_energy);
    free(state->face_flipped);
    free(state->panel_pull);
    free(state->grain_norm);
    free(state->pull_weight);
    free(state->pull_target);
    free(state->seam_length_only);
    free(state->dart_length_only);
    free(state->segment_target);
    free(state->segment_weight);
    free(state->stretch_boost);
    free(state->face_strain);
    free(state->curve_mismatch);
    state->terms = NULL;
    state->face_energy = state->panel_pull = state->grain_norm = state->pull_weight = state->pull_target = NULL;
    state->face_flipped = state->seam_length_only = state->dart_length_only = NULL;
    state->segment_target = state->segment_weight = NULL;
    state->stretch_boost = state->face_strain = state->curve_mismatch = NULL;
}

void textile_state_free(textile_state *state)
{
    textile_state_end(state);
    if (state->panels)
        for (int32_t p = 0; p < state->pattern->panel_count; ++p) {
            panel_system *system = &state->panels[p];
            /* The symbolic factor was made with u's common (any common frees it). */
            if (system->solver[0].started)
                cholmod_free_factor(&system->symbolic, &system->solver[0].common);
            solver_free(&system->solver[0]);
            solver_free(&system->solver[1]);
            free(system->vertices);
            free(system->slots);
            free(system->segment_ids);
            free(system->segment_slots);
        }
    free(state->panels);
    free(state->frames);
    free(state->areas);
    free(state->grain_local);
    free(state->vertex_panel);
    free(state->vertex_rank);
    free(state->vertex_local);
    free(state->offsets);
    free(state->order);
    free(state->outline_offsets);
    free(state->outline_edges);
    free(state->seam_segment_base);
    free(state->dart_segment_base);
    free(state->curve_length_3d);
    free(state->segment_ends);
    free(state->segment_weight_start);
    memset(state, 0, sizeof *state);
}

/* ------------------------------------------------------------------------ */
/* Each panel's systems                                                      */
/* ------------------------------------------------------------------------ */

/* Index of entry (row, col), row <= col, in the sorted upper CSC matrix. */
static int32_t find_slot(const cholmod_sparse *matrix, int32_t row, int32_t col)
{
    const int *colp = matrix->p, *rows = matrix->i;
    int lo = colp[col], hi = colp[col + 1] - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (rows[mid] < row)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The length-only seam segments of one panel (both ends are in it: a seam
 * side lies in one panel). 0 when out of memory. */
static int panel_segments(const textile_state *state, panel_system *system, int32_t panel)
{
    int32_t count = 0;
    for (int32_t g = 0; g < state->segment_count; ++g)
        count += state->vertex_panel[state->segment_ends[2 * g]] == panel;
    system->segment_count = count;
    system->segment_ids = malloc((size_t)count * sizeof(int32_t) + 1);
    system->segment_slots = malloc((size_t)count * sizeof(int32_t) + 1);
    if (!system->segment_ids || !system->segment_slots)
        return 0;
    count = 0;
    for (int32_t g = 0; g < state->segment_count; ++g)
        if (state->vertex_panel[state->segment_ends[2 * g]] == panel)
            system->segment_ids[count++] = g;
    return 1;
}

/* Builds one panel's vertex list, sparsity pattern, slots, and the symbolic
 * factorization shared by its u and v systems. 0 on success, else a status
 * (message in *message). */
static pz_status panel_setup(textile_state *state, int32_t panel, char *message, size_t message_size)
{
    const pz_mesh *mesh = state->pattern->mesh;
    panel_system *system = &state->panels[panel];
    const int32_t *faces = state->order + state->offsets[panel];
    int32_t count = state->offsets[panel + 1] - state->offsets[panel];
    system->vertices = malloc((size_t)3 * count * sizeof(int32_t) + 1);
    system->slots = malloc((size_t)6 * count * sizeof(int32_t) + 1);
    if (!system->vertices || !system->slots) {
        snprintf(message, message_size, "textile: out of memory");
        return PZ_ERR_NOMEM;
    }
    /* Vertices in order of first use: vertex_local doubles as the "seen" mark
     * (every vertex belongs to one panel, so the panels write disjoint entries). */
    int32_t n = 0;
    for (int32_t i = 0; i < 3 * count; ++i) {
        int32_t v = mesh->faces[3 * faces[i / 3] + i % 3];
        if (state->vertex_local[v] < 0) {
            state->vertex_local[v] = n;
            system->vertices[n++] = v;
        }
    }
    system->vertex_count = n;
    if (!panel_segments(state, system, panel)) {
        snprintf(message, message_size, "textile: out of memory");
        return PZ_ERR_NOMEM;
    }
    for (int k = 0; k < 2; ++k) {
        cholmod_start(&system->solver[k].common);
        system->solver[k].started = 1;
        /* Simplicial: its solves (CHOLMOD's own loops) beat the supernodal
         * ones on the reference BLAS (dgemv_ + dtrsv_), and the iteration
         * makes many solves per factorization (docs/param.md, "Speed
         * against libigl": 15-25 % less CPU per iteration from 2K to 34K
         * faces); from SIMPLICIAL_MAX_FACES on CHOLMOD chooses (supernodal at
         * the 200K hemisphere). */
        system->solver[k].common.supernodal = count < SIMPLICIAL_MAX_FACES ? CHOLMOD_SIMPLICIAL : CHOLMOD_AUTO;
    }
    coordinate_solver *su = &system->solver[0], *sv = &system->solver[1];
    cholmod_triplet *triplet = cholmod_allocate_triplet(n, n, (size_t)6 * count + system->segment_count, 1,
                                                        CHOLMOD_REAL, &su->common);
    if (!triplet) {
        snprintf(message, message_size, "textile: out of memory");
        return PZ_ERR_NOMEM;
    }
    static const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    int *ti = triplet->i, *tj = triplet->j;
    double *tx = triplet->x;
    for (int32_t f = 0; f < count; ++f) {
        const int32_t *face = mesh->faces + 3 * faces[f];
        for (int e = 0; e < 6; ++e) {
            int32_t a = state->vertex_local[face[pair[e][0]]], b = state->vertex_local[face[pair[e][1]]];
            ti[triplet->nnz] = a < b ? a : b;
            tj[triplet->nnz] = a < b ? b : a;
            tx[triplet->nnz++] = 1;
        }
    }
    for (int32_t i = 0; i < system->segment_count; ++i) {
        const int32_t *ends = state->segment_ends + 2 * system->segment_ids[i];
        int32_t a = state->vertex_local[ends[0]], b = state->vertex_local[ends[1]];
        ti[triplet->nnz] = a < b ? a : b;
        tj[triplet->nnz] = a < b ? b : a;
        tx[triplet->nnz++] = 1;
    }
    su->matrix = cholmod_triplet_to_sparse(triplet, 0, &su->common);
    cholmod_free_triplet(&triplet, &su->common);
    if (su->matrix) {
        for (int32_t f = 0; f < count; ++f) {
            const int32_t *face = mesh->faces + 3 * faces[f];
            for (int e = 0; e < 6; ++e) {
                int32_t a = state->vertex_local[face[pair[e][0]]], b = state->vertex_local[face[pair[e][1]]];
                system->slots[6 * f + e] = find_slot(su->matrix, a < b ? a : b, a < b ? b : a);
            }
        }
        for (int32_t i = 0; i < system->segment_count; ++i) {
            const int32_t *ends = state->segment_ends + 2 * system->segment_ids[i];
            int32_t a = state->vertex_local[ends[0]], b = state->vertex_local[ends[1]];
            system->segment_slots[i] = find_slot(su->matrix, a < b ? a : b, a < b ? b : a);
        }
        /* A large panel reuses its LSCM start's ordering when it has one: the same adjacency (the textile system
         * adds the pins and seam segments), and the search for it (nested dissection and AMD) costs 0.2 s at
         * 100K unknowns. */
        /* Ranked when the start's system was (the two pins have no rank: among any three vertices one is not a
         * pin). */
        int ranked = state->vertex_rank && n >= PZ_METIS_MAX_UNKNOWNS &&
                     (state->vertex_rank[system->vertices[0]] >= 0 || state->vertex_rank[system->vertices[1]] >= 0 ||
                      state->vertex_rank[system->vertices[2]] >= 0);
        system->symbolic = ranked ? pz_param_analyze_ranked(su->matrix, system->vertices, state->vertex_rank, &su->common)
                                  : pz_param_analyze(su->matrix, mesh->positions, system->vertices, !state->brief,
                                                     &su->common);
        /* The factorization costs `ratio` PCG steps: CHOLMOD's flop count for
         * the factor against two triangular solves and a product, times
         * FACTOR_FLOP_COST (the flops underestimate it below ~50K unknowns:
         * measured 16 steps against a count of 6 at 1K unknowns, 40 against
         * 16 at 10K, 32 against 42 at 100K). Deterministic, unlike timing. */
        double step = 4 * su->common.lnz + 4.0 * ((int *)su->matrix->p)[n];
        double ratio = step > 0 ? FACTOR_FLOP_COST * su->common.fl / step : 0;
        int max_steps = ratio < PCG_MIN_STEPS ? PCG_MIN_STEPS : ratio > PCG_MAX_STEPS ? PCG_MAX_STEPS : (int)ratio;
        su->max_steps = sv->max_steps = max_steps;
        sv->matrix = cholmod_copy_sparse(su->matrix, &sv->common);
    }
    if (!system->symbolic || !sv->matrix) {
        snprintf(message, message_size, "textile: panel %d: out of memory in the symbolic analysis", panel);
        return PZ_ERR_NOMEM;
    }
    return PZ_OK;
}

/* One solve's part of a panel's systems: factors copied from the symbolic
 * analysis (so every solve factorizes exactly as the first did) and the
 * vectors. 0 when out of memory. */
static int panel_begin(panel_system *system)
{
    size_t n = (size_t)system->vertex_count;
    int allocated = 1;
    for (int k = 0; k < 2 && allocated; ++k) {
        coordinate_solver *s = &system->solver[k];
        s->factored = s->fresh = s->failed = s->refactor = s->exact = s->direct_runs = s->response_ready = 0;
        s->factorizations = s->failed_steps = s->pcg_solves = 0;
        s->backoff = 1;
        s->borrowing = k == 1 && s->max_steps >= BORROW_MIN_STEPS;
        s->factor = cholmod_copy_factor(system->symbolic, &s->common);
        s->rhs = cholmod_zeros(n, 1, CHOLMOD_REAL, &s->common);
        s->residual = cholmod_zeros(n, 1, CHOLMOD_REAL, &s->common);
        s->product = malloc(n * sizeof(double) + 1);
        s->current = malloc(n * sizeof(double) + 1);
        s->direction = malloc(n * sizeof(double) + 1);
        s->grain_gradient = malloc(n * sizeof(double) + 1);
        s->grain_response = calloc(n + 1, sizeof(double));
        allocated = s->factor && s->rhs && s->residual &&  s->product && s->current && s->direction &&
                    s->grain_gradient &&
                    s->grain_response;
    }
    return allocated;
}

/* The 3D frame coordinates of every face in every pose used, and rest areas. */
static void compute_frames(textile_state *state)
{
    const pz_mesh *mesh = state->pattern->mesh;
    int32_t poses = state->pose_total;
#pragma omp parallel for schedule(static) num_threads(state->threads) if (state->parallel)
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double e1[3], e2[3];
        for (int32_t p = 0; p < poses; ++p) {
            const double *pos = p == 0 ? mesh->positions : mesh->poses + (size_t)(p - 1) * mesh->vertex_count * 3;
            double area = pz_param_face_frame(pos, mesh->faces + 3 * f, state->frames + ((size_t)f * poses + p) * 3,
                                              e1, e2);
            if (p == 0) {
                double a = dot3(state->grain, e1), b = dot3(state->grain, e2);
                if (state->panel_grain_turn) /* a grain hint turns the panel's warp about the face normal */
                    pz_param_turn_in_frame(state->panel_grain_turn[state->pattern->face_panel[f]], &a, &b);
                state->areas[f] = area;
                state->grain_local[2 * f] = a;
                state->grain_local[2 * f + 1] = b;
            }
        }
    }
}

/* ------------------------------------------------------------------------ */
/* Checks                                                                    */
/* ------------------------------------------------------------------------ */

/* Every vertex in one panel only (the panels' systems index their own
 * vertices and are built in parallel) and no panel empty. */
static pz_status check_panels(const pz_pattern *pattern, pz_ctx *ctx)
{
    const pz_mesh *mesh = pattern->mesh;
    int32_t *vertex_panel = malloc((size_t)mesh->vertex_count * sizeof(int32_t) + 1);
    int32_t *panel_faces = calloc((size_t)pattern->panel_count + 1, sizeof(int32_t));
    pz_status status = PZ_OK;
    if (!vertex_panel || !panel_faces)
        status = pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    for (int32_t v = 0; !status && v < mesh->vertex_count; ++v)
        vertex_panel[v] = -1;
    for (int32_t i = 0; !status && i < 3 * mesh->face_count; ++i) {
        int32_t v = mesh->faces[i], panel = pattern->face_panel[i / 3];
        if (panel < 0 || panel >= pattern->panel_count || v < 0 || v >= mesh->vertex_count) {
            status = pz_error(ctx, PZ_ERR_DATA, "textile: face %d: panel or vertex out of range", i / 3);
        } else if (vertex_panel[v] >= 0 && vertex_panel[v] != panel) {
            status = pz_error(ctx, PZ_ERR_DATA, "textile: vertex %d is in panels %d and %d (the mesh is not cut)", v,
                              vertex_panel[v], panel);
        } else {
            vertex_panel[v] = panel;
            panel_faces[panel] += i % 3 == 0;
        }
    }
    for (int32_t p = 0; !status && p < pattern->panel_count; ++p)
        if (panel_faces[p] == 0)
            status = pz_error(ctx, PZ_ERR_DATA, "textile: panel %d has no faces", p);
    free(vertex_panel);
    free(panel_faces);
    return status;
}

static pz_status check_correspondences(const pz_pattern *pattern, pz_ctx *ctx)
{
    int32_t nv = pattern->mesh->vertex_count;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        for (int32_t i = 0; i < seam->pair_count; ++i)
            if (seam->side_a[i] < 0 || seam->side_a[i] >= nv || seam->side_b[i] < 0 || seam->side_b[i] >= nv)
                return pz_error(ctx, PZ_ERR_DATA, "textile: seam %d: vertex out of range", s);
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        if (dart->tip < 0 || dart->tip >= nv)
            return pz_error(ctx, PZ_ERR_DATA, "textile: dart %d: tip out of range", d);
        for (int32_t i = 0; i < dart->pair_count; ++i)
            if (dart->leg_a[i] < 0 || dart->leg_a[i] >= nv || dart->leg_b[i] < 0 || dart->leg_b[i] >= nv)
                return pz_error(ctx, PZ_ERR_DATA, "textile: dart %d: vertex out of range", d);
    }
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Seams, darts and outlines                                                 */
/* ------------------------------------------------------------------------ */

/* The best-fit reflection x -> R x + t, R = [[c, s], [s, -c]] (symmetric,
 * det -1), of side a onto side b (Eqs. 7-8): centroids, then the R
 * maximizing c (S00 - S11) + s (S01 + S10), S = sum (q - cb)(p - ca)^T. */
void textile_fit_reflection(const pz_seam *seam, const double *uv, double *c_out, double *s_out, double t[2])
{
    int32_t n = seam->pair_count;
    double ca[2] = {0, 0}, cb[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            ca[k] += uv[2 * seam->side_a[i] + k] / n;
            cb[k] += uv[2 * seam->side_b[i] + k] / n;
        }
    double s00 = 0, s01 = 0, s10 = 0, s11 = 0;
    for (int32_t i = 0; i < n; ++i) {
        double px = uv[2 * seam->side_a[i]] - ca[0], py = uv[2 * seam->side_a[i] + 1] - ca[1];
        double qx = uv[2 * seam->side_b[i]] - cb[0], qy = uv[2 * seam->side_b[i] + 1] - cb[1];
        s00 += qx * px;
        s01 += qx * py;
        s10 += qy * px;
        s11 += qy * py;
    }
    double c = s00 - s11, s = s01 + s10, norm = sqrt(c * c + s * s);
    if (norm > 0) {
        c /= norm;
        s /= norm;
    } else {
        c = 1;
        s = 0;
    }
    *c_out = c;
    *s_out = s;
    t[0] = cb[0] - (c * ca[0] + s * ca[1]);
    t[1] = cb[1] - (s * ca[0] - c * ca[1]);
}

/* RMS distance of side b to side a after the best-fit reflection, over the
 * 3D length of side a; 0 for a seam of fewer than 2 pairs. */
static double relative_reflection_residual(const pz_mesh *mesh, const pz_seam *seam, const double *uv)
{
    int32_t n = seam->pair_count;
    if (n < 2)
        return 0;
    double c, s, t[2], sum = 0, length = 0;
    textile_fit_reflection(seam, uv, &c, &s, t);
    for (int32_t i = 0; i < n; ++i) {
        const double *p = uv + 2 * seam->side_a[i], *q = uv + 2 * seam->side_b[i];
        double dx = c * p[0] + s * p[1] + t[0] - q[0], dy = s * p[0] - c * p[1] + t[1] - q[1];
        sum += dx * dx + dy * dy;
        if (i > 0) {
            const double *x = mesh->positions + 3 * seam->side_a[i - 1], *y = mesh->positions + 3 * seam->side_a[i];
            double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
            length += sqrt(dot3(d, d));
        }
    }
    return length > 0 ? sqrt(sum / n) / length : 0;
}

/* Appends the facing segments (a[i], a[i+1]) / (b[i], b[i+1]), i < n - 1,
 * and, when tip >= 0, (a[n-1], tip) / (b[n-1], tip); returns the first index. */
static int32_t add_segments(textile_state *state, const int32_t *a, const int32_t *b, int32_t n, int32_t tip,
                            double weight)
{
    int32_t base = state->segment_count;
    for (int32_t i = 0; i < n; ++i) {
        if (i + 1 >= n && tip < 0)
            break;
        int32_t next_a = i + 1 < n ? a[i + 1] : tip, next_b = i + 1 < n ? b[i + 1] : tip;
        int32_t *ends = state->segment_ends + 2 * (size_t)state->segment_count;
        ends[0] = a[i];
        ends[1] = next_a;
        ends[2] = b[i];
        ends[3] = next_b;
        state->segment_weight_start[state->segment_count] = weight;
        state->segment_weight_start[state->segment_count + 1] = weight;
        state->segment_count += 2;
    }
    return base;
}

/*
 * The facing segments of every seam (2 sides) and dart (2 legs, out to the
 * tip): each pair is held to equal lengths (segment_length_targets), which is
 * what sewing needs whatever the 2D shapes. 0 when out of memory.
 */
static int build_segments(textile_state *state)
{
    const pz_pattern *pattern = state->pattern;
    int32_t ns = pattern->seam_count, nd = pattern->dart_count;
    size_t pairs = 0;
    for (int32_t s = 0; s < ns; ++s)
        pairs += pattern->seams[s].pair_count > 1 ? (size_t)pattern->seams[s].pair_count - 1 : 0;
    for (int32_t d = 0; d < nd; ++d)
        pairs += (size_t)pattern->darts[d].pair_count;
    state->seam_segment_base = malloc(((size_t)ns + 1) * sizeof(int32_t));
    state->dart_segment_base = malloc(((size_t)nd + 1) * sizeof(int32_t));
    state->segment_ends = malloc(pairs * 4 * sizeof(int32_t) + 1);
    state->segment_weight_start = malloc(pairs * 2 * sizeof(double) + 1);
    if (!state->seam_segment_base || !state->dart_segment_base || !state->segment_ends ||
        !state->segment_weight_start)
        return 0;
    state->segment_count = 0;
    for (int32_t s = 0; s < ns; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        int usable = seam->pair_count >= 2 && state->w_seam > 0;
        state->seam_segment_base[s] =
            usable ? add_segments(state, seam->side_a, seam->side_b, seam->pair_count, -1,
                                  state->w_seam * SEGMENT_LENGTH_STIFFNESS)
                   : -1;
    }
    state->seam_segment_end = state->segment_count;
    for (int32_t d = 0; d < nd; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        int usable = dart->pair_count >= 1 && state->w_dart > 0;
        state->dart_segment_base[d] =
            usable ? add_segments(state, dart->leg_a, dart->leg_b, dart->pair_count, dart->tip,
                                  state->w_dart * SEGMENT_LENGTH_STIFFNESS)
                   : -1;
    }
    return 1;
}

/*
 * Which seams can be mirror images (docs/param.md, "Seams that cannot be
 * mirror images"). At the LSCM start every panel has its own natural flat
 * shape; a seam whose sides are then further from mirror images than
 * mirror_tolerance (relative_reflection_residual) keeps only its equal
 * lengths: mirror seams (skirt side seams, a sleeve's underarm) measure
 * 0.2-3.6 % on the test garments, a collar band on a neckline 25 %, sleeve
 * caps in armholes 8-10 %, and forcing the latter into reflections takes
 * strains of that order. Writes state->seam_length_only (allocated by
 * textile_state_begin) and returns the number of length-only seams.
 */
int32_t textile_classify_seams(textile_state *state, const double *uv)
{
    const pz_pattern *pattern = state->pattern;
    int32_t ns = pattern->seam_count, length_only = 0;
    for (int32_t s = 0; s < ns; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        state->seam_length_only[s] = 0;
        if (seam->pair_count < 2 || state->w_seam <= 0 ||
            !(relative_reflection_residual(pattern->mesh, seam, uv) > state->mirror_tolerance))
            continue;
        state->seam_length_only[s] = 1;
        ++length_only;
    }
    return length_only;
}

/* The outline edges of every panel (boundary half-edges of the cut mesh), for the crossing test. */
static pz_status build_outlines(textile_state *state, pz_ctx *ctx)
{
    const pz_pattern *pattern = state->pattern;
    pz_topology *topology = NULL;
    pz_status status = pz_topology_build(pattern->mesh, &topology, ctx);
    if (status)
        return status;
    int32_t np = pattern->panel_count;
    state->outline_offsets = calloc((size_t)np + 2, sizeof(int32_t));
    int32_t boundary = 0;
    for (int32_t h = 0; h < topology->halfedge_count; ++h)
        boundary += topology->twin[h] < 0;
    state->outline_edges = malloc((size_t)boundary * 2 * sizeof(int32_t) + 1);
    if (!state->outline_offsets || !state->outline_edges) {
        pz_topology_free(&topology);
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    }
    for (int32_t h = 0; h < topology->halfedge_count; ++h)
        if (topology->twin[h] < 0)
            ++state->outline_offsets[pattern->face_panel[pz_he_face(h)] + 2];
    for (int32_t p = 0; p < np; ++p)
        state->outline_offsets[p + 2] += state->outline_offsets[p + 1];
    for (int32_t h = 0; h < topology->halfedge_count; ++h) {
        if (topology->twin[h] >= 0)
            continue;
        int32_t slot = state->outline_offsets[pattern->face_panel[pz_he_face(h)] + 1]++;
        state->outline_edges[2 * slot] = pz_he_from(topology, h);
        state->outline_edges[2 * slot + 1] = pz_he_to(topology, h);
    }
    pz_topology_free(&topology);
    return PZ_OK;
}

/* 3D length of side a of every seam and leg a of every dart (to the tip). */
static int curve_lengths(textile_state *state)
{
    const pz_pattern *pattern = state->pattern;
    int32_t curves = pattern->seam_count + pattern->dart_count;
    state->curve_length_3d = calloc((size_t)curves + 1, sizeof(double));
    if (!state->curve_length_3d)
        return 0;
    const double *pos = pattern->mesh->positions;
    for (int32_t c = 0; c < curves; ++c) {
        int32_t base = c < pattern->seam_count ? state->seam_segment_base[c]
                                               : state->dart_segment_base[c - pattern->seam_count];
        int32_t pairs = c < pattern->seam_count ? pattern->seams[c].pair_count - 1
                                                : pattern->darts[c - pattern->seam_count].pair_count;
        for (int32_t g = base; base >= 0 && g < base + 2 * pairs; g += 2) {
            const double *x = pos + 3 * state->segment_ends[2 * g], *y = pos + 3 * state->segment_ends[2 * g + 1];
            double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
            state->curve_length_3d[c] += sqrt(dot3(d, d));
        }
    }
    return 1;
}

/* ------------------------------------------------------------------------ */
/* The state                                                                 */
/* ------------------------------------------------------------------------ */

/* Everything of the state that depends on the pattern and the options only. */
static pz_status state_setup(textile_state *state, pz_ctx *ctx)
{
    const pz_pattern *pattern = state->pattern;
    const pz_mesh *mesh = pattern->mesh;
    size_t nv = (size_t)mesh->vertex_count, nf = (size_t)mesh->face_count;
    state->frames = malloc(nf * state->pose_total * 3 * sizeof(double) + 1);
    state->areas = malloc(nf * sizeof(double) + 1);
    state->grain_local = malloc(nf * 2 * sizeof(double) + 1);
    state->vertex_local = malloc(nv * sizeof(int32_t) + 1);
    state->panels = calloc((size_t)pattern->panel_count + 1, sizeof(panel_system));
    state->vertex_panel = malloc(nv * sizeof(int32_t) + 1);
    if (!state->frames || !state->areas || !state->grain_local || !state->vertex_local || !state->panels ||
        !state->vertex_panel)
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    for (size_t v = 0; v < nv; ++v)
        state->vertex_local[v] = -1;
    for (size_t i = 0; i < 3 * nf; ++i) /* check_panels: every vertex is in one panel */
        state->vertex_panel[mesh->faces[i]] = pattern->face_panel[i / 3];
    if (!build_segments(state))
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    pz_status outlined = build_outlines(state, ctx);
    if (outlined)
        return outlined;
    if (state->strain_limit > 0 && !curve_lengths(state))
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    compute_frames(state);
    pz_status failed = PZ_OK;
    int32_t failed_panel = -1;
    char message[sizeof ctx->error] = "";
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (state->parallel)
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        char local_message[sizeof ctx->error];
        pz_status st = panel_setup(state, p, local_message, sizeof local_message);
        if (st) {
#pragma omp critical(pz_textile_failure)
            if (!failed || p < failed_panel) { /* the lowest panel, whatever the timing */
                failed = st;
                failed_panel = p;
                memcpy(message, local_message, sizeof message);
            }
        }
    }
    if (failed)
        return pz_error(ctx, failed, "%s", message);
    return PZ_OK;
}

/* The state one solve writes, as it is at the start of every solve. */
pz_status textile_state_begin(textile_state *state, pz_ctx *ctx)
{
    const pz_pattern *pattern = state->pattern;
    size_t nv = (size_t)pattern->mesh->vertex_count, nf = (size_t)pattern->mesh->face_count;
    size_t np = (size_t)pattern->panel_count, segments = (size_t)state->segment_count;
    size_t curves = (size_t)pattern->seam_count + (size_t)pattern->dart_count;
    state->terms = malloc(nf * sizeof(face_terms) + 1);
    state->face_energy = malloc(nf * sizeof(double) + 1);
    state->face_flipped = malloc(nf + 1);
    state->panel_pull = malloc(np * sizeof(double) + 1);
    state->grain_norm = calloc(np + 1, sizeof(double));
    state->pull_weight = malloc(nv * sizeof(double) + 1);
    state->pull_target = malloc(nv * 2 * sizeof(double) + 1);
    state->seam_length_only = calloc((size_t)pattern->seam_count + 1, 1);
    state->dart_length_only = calloc((size_t)pattern->dart_count + 1, 1);
    state->segment_target = calloc(segments * 2 + 1, sizeof(double));
    state->segment_weight = malloc(segments * sizeof(double) + 1);
    int allocated = state->terms && state->face_energy && state->face_flipped && state->panel_pull &&
                    state->grain_norm && state->pull_weight && state->pull_target && state->seam_length_only &&
                    state->dart_length_only && state->segment_target && state->segment_weight;
    if (allocated && state->strain_limit > 0) {
        state->stretch_boost = malloc(nf * sizeof(double) + 1);
        state->face_strain = calloc(nf + 1, sizeof(double));
        state->curve_mismatch = calloc(curves + 1, sizeof(double));
        allocated = state->stretch_boost && state->face_strain && state->curve_mismatch;
        for (size_t f = 0; allocated && f < nf; ++f)
            state->stretch_boost[f] = 1;
    }
    for (size_t p = 0; allocated && p < np; ++p)
        allocated = panel_begin(&state->panels[p]);
    if (!allocated) {
        textile_state_end(state);
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    }
    memcpy(state->segment_weight, state->segment_weight_start, segments * sizeof(double));
    state->project_grain = 0;
    state->seams_open = 0;
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Options and pz_textile_setup                                              */
/* ------------------------------------------------------------------------ */

/*
 * The team size when the caller leaves it to us (options->threads == 0):
 * OpenMP's maximum, but one thread when the machine has no core to spare.
 * libgomp's default wait is active, so a thread descheduled by other work
 * leaves its partner spinning at every barrier: at 200K faces and load 3.4
 * on 2 cores, 66-184 ms per iteration with two threads against 79-109 ms
 * with one (docs/param.md, "Threads"). "No core to spare": the 1-minute load
 * average, less the one thread this process runs itself, leaves less than
 * one more core. The result does not depend on the team size (SUM_BLOCKS),
 * so this only changes the time.
 */
static int default_threads(void)
{
    int threads = omp_get_max_threads();
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    double load[1];
    if (threads > 1 && cores > 0 && getloadavg(load, 1) == 1) {
        double spare = (double)cores - fmax(load[0] - 1.0, 0.0);
        if (spare < (double)threads)
            threads = spare >= 2.0 ? (int)spare : 1;
    }
    return threads;
}

static void read_options(pz_textile_solver *solver, const pz_textile_options *options)
{
    textile_state *state = &solver->state;
    pz_textile_options defaults;
    memset(&defaults, 0, sizeof defaults);
    if (!options)
        options = &defaults;
    solver->iterations = options->iterations > 0 ? options->iterations : 20;
    state->brief = solver->iterations < BRIEF_ITERATIONS;
    solver->tolerance = options->tolerance > 0 ? options->tolerance : 1e-6;
    solver->on_iteration = options->on_iteration;
    solver->user = options->user;
    if (options->weights_given) {
        state->w_stretch = options->weight_stretch;
        state->w_rigid = options->weight_rigid;
        state->w_dart = options->weight_dart;
        state->w_seam = options->weight_seam;
    } else {
        state->w_stretch = 5;
        state->w_rigid = 1;
        state->w_dart = 5;
        state->w_seam = 5;
    }
    double up[3] = {0, 0, 1};
    memcpy(state->grain, options->grain_given ? options->grain : up, sizeof state->grain);
    state->panel_grain_turn = options->panel_grain_turn;
    /* An explicit count is a ceiling: a second thread that finds no free
     * core, or too little work between barriers, makes the iteration slower
     * (docs/param.md, "Threads"); the result is the same for any count. */
    int spare = default_threads();
    state->threads = options->threads > 0 && options->threads < spare ? options->threads : spare;
    state->parallel = state->threads > 1 && state->pattern->mesh->face_count >= PARALLEL_MIN_FACES;
    /* A parallel loop over one panel leaves every thread but one spinning at
     * the barrier (on a busy machine, descheduled: 5x slower iterations were
     * measured), so one-panel patterns split the work inside the panel. */
    state->across_panels = state->parallel && state->pattern->panel_count > 1;
    state->within_panel = state->parallel && state->pattern->panel_count == 1;
    state->pose_total = 1 + (options->use_poses ? state->pattern->mesh->pose_count : 0);
    state->regularization = 1e-8 * fmax(1.0, state->w_stretch + state->w_rigid);
    state->mirror_tolerance = options->seam_mirror_tolerance > 0 ? options->seam_mirror_tolerance : 0.05;
    state->strain_limit = options->strain_limit > 0 ? options->strain_limit : 0;
}

void pz_textile_solver_free(pz_textile_solver **solver)
{
    if (!solver || !*solver)
        return;
    if ((*solver)->state.pattern)
        textile_state_free(&(*solver)->state);
    free((*solver)->start_uv);
    free(*solver);
    *solver = NULL;
}

/*
 * The LSCM start (solver->start_uv), then the state (its systems' symbolic analyses). A panel of
 * PZ_METIS_MAX_UNKNOWNS unknowns or more orders its systems as its start's factorization was ordered
 * (state->vertex_rank: the same adjacency, the textile system adding the pins and seam segments) instead of
 * searching orderings again: at the 200K-face hemisphere the search (nested dissection and AMD) cost 0.2 s.
 * (Running the two side by side on two threads, as a first version did, saved about as much on two free cores
 * only; the systems cannot reuse an ordering the start is still making.)
 */
static pz_status start_and_state(pz_textile_solver *solver, pz_ctx *ctx)
{
    textile_state *state = &solver->state;
    const pz_pattern *pattern = state->pattern;
    if (!state->brief && !(state->vertex_rank = malloc((size_t)pattern->mesh->vertex_count * sizeof(int32_t) + 1)))
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    pz_status status = pz_param_lscm_pattern_ranked(pattern, state->grain, solver->start_uv, state->vertex_rank, ctx);
    if (!status)
        status = pz_check_cancel(ctx, "textile");
    if (!status)
        status = pz_param_panel_faces(pattern, &state->offsets, &state->order, ctx);
    if (!status)
        status = state_setup(state, ctx);
    free(state->vertex_rank); /* the analyses are made */
    state->vertex_rank = NULL;
    return status;
}

pz_status pz_textile_setup(const pz_pattern *pattern, const pz_textile_options *options, pz_textile_solver **out,
                           pz_ctx *ctx)
{
    if (!out)
        return pz_error(ctx, PZ_ERR_USAGE, "textile: no solver to set up");
    *out = NULL;
    if (!pattern || !pattern->mesh)
        return pz_error(ctx, PZ_ERR_USAGE, "textile: no pattern or no output");
    pz_textile_solver *solver = calloc(1, sizeof *solver);
    if (!solver)
        return pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    textile_state *state = &solver->state;
    state->pattern = pattern;
    read_options(solver, options);
    if (state->w_stretch < 0 || state->w_rigid < 0 || state->w_dart < 0 || state->w_seam < 0) {
        pz_textile_solver_free(&solver);
        return pz_error(ctx, PZ_ERR_USAGE, "textile: weights must not be negative");
    }
    double start = pz_seconds();
    pz_status status = check_panels(pattern, ctx);
    if (!status)
        status = check_correspondences(pattern, ctx);
    if (!status && !(solver->start_uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double) + 1)))
        status = pz_error(ctx, PZ_ERR_NOMEM, "textile: out of memory");
    if (!status)
        status = start_and_state(solver, ctx);
    if (status) {
        pz_textile_solver_free(&solver);
        return status;
    }
    solver->setup_ms = 1e3 * (pz_seconds() - start);
    *out = solver;
    return PZ_OK;
}
