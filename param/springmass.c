/*
 * param/springmass.c -- spring-mass flattening with strain-energy relaxation
 * (wang2002 "Surface flattening based on energy model", mccartney2005
 * "orthotropic pattern flattening", IISERM "heap accelerated flattening").
 *
 * Every panel (a disk of the cut mesh) is flattened on its own:
 *
 * Seed. A multi-source Dijkstra from the boundary vertices over the edges
 * gives each vertex its distance to the boundary; a face's medial distance is
 * the mean over its corners (mccartney2005 Sec. 6). The face farthest from the
 * boundary is laid down undistorted, turned so that the 3D grain projected
 * onto it becomes +v (the warp; mccartney2005 Sec. 8).
 *
 * Phase one (wang2002 Sec. 6.1, mccartney2005 Sec. 6). Faces that share an
 * edge with a flattened face wait in a max-heap keyed by medial distance, so
 * the flattening grows from the middle outward. A face with one unplaced
 * corner is unconstrained: the corner goes to the intersection of the two
 * circles with the 3D edge lengths as radii, on the side that keeps the face
 * counter-clockwise. A face whose three corners are placed is constrained:
 * its springs join the system, the corner with the highest energy is moved
 * to its energy minimum (repeated node relaxations), then energy is released:
 *   full  (wang2002 InitFlatten): sweeps over every placed node until the
 *         energy varies less than energy_variation or 50 sweeps;
 *   heap  (IISERM Sec. 3): node energies live in an indexed max-heap and only
 *         the nodes on one path from the root down the larger children
 *         (single path, Sec. 3.1), or on up to heap_paths paths whose number
 *         grows as 2^(level-2) (multi-path, Sec. 3.2, Eq. 5), are relaxed.
 *
 * Phase two (wang2002 Sec. 5-6.2): for the isotropic springs, first a global
 * release (local-global iterations with one CHOLMOD factorization of the
 * spring Laplacian; see global_release: node sweeps alone stop far from the
 * minimum on large panels), then sweeps over all nodes until E_S (Eq. 4)
 * and E_C (Eq. 6) are both below the accuracy, or the energy (Eq. 3) varies
 * less than energy_variation, or max_iterations sweeps; a diverging sweep
 * is undone (see DIVERGENCE_RISE). A panel that ends folded or with its
 * outline crossing itself is flattened again, with 8 heap paths, then from
 * its LSCM (see RETRY_PATHS).
 *
 * Seam matching (not in the papers, see sm_link): the facing segments of
 * every seam and dart get the mean of their two 2D lengths; each panel's
 * outline is refitted to those lengths exactly in angle space (wang2008
 * Eqs. 2-8 for one loop, fit_loop) and its interior released again with the
 * outline pinned. Faces still flipped at the end are untangled
 * geometrically (pz_param_untangle, wirewarp_layout.c), a matched outline kept.
 *
 * Node relaxation, isotropic. The force of Eq. 2 (C = 0.5) moves the node as
 * Eqs. 11-13 with the node starting at rest: dq = dt^2 / (2 m_i) f_i. The
 * paper drops damping, so a persistent velocity would oscillate forever; and
 * it calls rho and C scale factors: we fix the scale so that dt^2 / (2 m_i) =
 * 1 / sum_j C, the largest step for which the move cannot raise the node's
 * energy (the springs' Hessian is bounded by sum_j C); phase two
 * over-relaxes it by PHASE_TWO_OMEGA (SOR, see there). Then the overlap
 * penalty of Eqs. 14-15: for every opposite edge whose distance h_j to the
 * node has fallen below PENALTY_FRACTION of the 3D distance h_j*, the node is
 * pushed away from the edge by the shortfall. (The paper's threshold h_j* on
 * its own would fight the springs wherever a triangle is slightly
 * compressed; the fraction keeps it to triangles heading for a flip.)
 *
 * Node relaxation, orthotropic: the energy is mccartney2005 Eqs. 5-9 over
 * the node's triangles, 0.5 A (K_su (S_u - 1)^2 + K_sv (S_v - 1)^2 + K_r
 * phi^2) with u the weft, v the warp of the pattern plane, and the move is
 * ISERM's (IISERM Sec. 2, Fig. 3): four trial moves of +-delta along u and v,
 * the best one kept when it lowers the energy; each node's delta grows by 1.5
 * after a success and halves after a failure. A flipped triangle adds a
 * barrier so that moves which unflip it are taken.
 *
 * Energy map (wang2002 Sec. 6.3): the energy of each vertex (Eq. 1, or a
 * third of its triangles' orthotropic energy); Eq. 16 interpolates it
 * linearly inside triangles (energy.svg draws the value at the centroid).
 * The suggested cutting line is the crest line through the maximum: from the
 * maximum down to the boundary and from it inward, each step to the
 * neighbour (closer to / farther from the boundary) with the highest energy,
 * i.e. the slowest descent; inward it stops at a local maximum of boundary
 * distance or when the energy falls below a tenth of the maximum.
 *
 * Trial cut (mccartney2005 Sec. 4, 7): the panel is cut along that line
 * (pz_mesh_cut) and flattened again; the two sides of the cut, walked along
 * the boundary from one mouth through the tip to the other, enclose a
 * polygon whose signed area is negative when the sides splay apart (a gap:
 * dart) and positive when they overlap (a gusset), since the boundary walks
 * with the material on its left.
 *
 * CHOLMOD: the spring Laplacian's sparsity pattern is the piece's edges
 * whatever the pins, so its symbolic analysis is made once per piece
 * (sm_spring) and every global release of that piece -- phase two, the
 * second tries, the release against a matched outline -- factorizes a copy
 * of it. Cancellation (ctx->cancel) is checked between panels, between
 * sweeps and every 256 faces of phase one. Files:
 * param/springmass_internal.h.
 *
 * Cost: phase one heap O(F log F) plus the paths; full O(F * n * sweeps);
 * phase two one sparse factorization plus O(n) per global iteration (two
 * triangular solves) and per sweep; seam matching O(outline) per Newton step
 * and one more release per linked panel. Memory O(n + F) plus the factor,
 * for all panels at once (matching needs them all). Failure: PZ_ERR_NOMEM;
 * PZ_ERR_DATA when a panel cannot be reached from its seed through edges.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/springmass_internal.h"

#include <stdlib.h>
#include <string.h>

static void settings_from(const pz_springmass_options *options, sm_settings *s)
{
    pz_springmass_options zero = {0};
    if (!options)
        options = &zero;
    memset(s, 0, sizeof *s);
    s->heap = options->relax == 0;
    s->paths = options->heap_paths > 1 ? options->heap_paths : 1;
    s->orthotropic = options->orthotropic;
    pz_fabric fabric = pz_fabric_default(); /* a constant left 0 takes the paper's */
    s->fabric.k_su = options->fabric.k_su > 0 ? options->fabric.k_su : fabric.k_su;
    s->fabric.k_sv = options->fabric.k_sv > 0 ? options->fabric.k_sv : fabric.k_sv;
    s->fabric.k_r = options->fabric.k_r > 0 ? options->fabric.k_r : fabric.k_r;
    double z[3] = {0, 0, 1};
    memcpy(s->grain, options->grain_given ? options->grain : z, sizeof s->grain);
    s->max_iterations = options->max_iterations > 0 ? options->max_iterations : 1000;
    s->phase_one_iterations = options->phase_one_iterations > 0 ? options->phase_one_iterations : 50;
    s->accuracy = options->accuracy > 0 ? options->accuracy : 0.01;
    s->energy_variation = options->energy_variation > 0 ? options->energy_variation : 0.0005;
    s->local_only = options->local_release_only;
    s->independent = options->independent_panels;
}

/* One panel of the pattern: its own mesh and buffers, kept until every panel is flattened (seam matching). */
typedef struct sm_piece {
    pz_mesh *mesh;
    int32_t *vertex_map;       /* local -> pattern vertex */
    double *uv, *map;
    int32_t *line, line_count;
    sm_settings retry;         /* the settings of a retry (its panel points to them) */
    sm_spring spring;          /* the global release's symbolic analysis, shared by every try and release */
} sm_piece;

static void pieces_free(sm_piece *pieces, sm_panel *panels, int32_t count)
{
    for (int32_t k = 0; pieces && k < count; ++k) {
        if (panels)
            sm_panel_free(&panels[k]);
        pz_mesh_free(&pieces[k].mesh);
        free(pieces[k].vertex_map);
        free(pieces[k].uv);
        free(pieces[k].map);
        free(pieces[k].line);
        sm_spring_free(&pieces[k].spring);
    }
    free(pieces);
    free(panels);
}

/* Flipped faces plus crossings of the outline; -1 when out of memory. */
static int32_t panel_defects(const sm_panel *p)
{
    int32_t *edges = malloc((size_t)p->loop_count * 2 * sizeof(int32_t) + 1);
    if (!edges)
        return -1;
    for (int32_t i = 0; i < p->loop_count; ++i) {
        edges[2 * i] = p->loop[i];
        edges[2 * i + 1] = p->loop[(i + 1) % p->loop_count];
    }
    int32_t crossings = pz_metrics_outline_crossings(edges, p->loop_count, p->uv);
    free(edges);
    return crossings < 0 ? -1 : crossings + sm_flipped_faces(p);
}

/*
 * Second tries for a panel that ends phase two folded (flipped faces) or with
 * its outline crossing itself. Heap relaxation relaxes a few nodes per
 * triangle, and once in a while its phase one leaves a basin the releases
 * cannot leave: the generated bodice's back came out with a crossing
 * outline, energy 823 where full relaxation and 8 heap paths give 341. Such
 * a panel is flattened again with RETRY_PATHS heap paths (IISERM's
 * multi-path); if that is still folded (phase one itself tangles on the
 * shared head scans, one panel each), phase two starts from the panel's LSCM
 * instead of phase one (our addition, not the papers'). The best of the tries
 * is kept: fewer defects, else less energy. The cost is paid only there.
 */
#define RETRY_PATHS 8

/* Phase two from the panel's LSCM (area-scaled, grain along +v) instead of phase one. */
static pz_status panel_from_lscm(sm_panel *p, const pz_mesh *mesh, const sm_settings *settings, double *uv,
                                 sm_spring *spring, sm_outcome *outcome, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_status status = sm_panel_init(p, mesh, settings, uv, ctx);
    p->spring = spring;
    if (!status)
        status = pz_param_lscm(mesh, settings->grain, uv, ctx);
    if (status)
        return status;
    for (int32_t f = 0; f < p->nf; ++f)
        sm_activate_face(p, f);
    for (int32_t v = 0; v < p->nv; ++v)
        sm_place_vertex(p, v);
    outcome->phase_one_ms = 1e3 * (pz_seconds() - start);
    outcome->phase_one_energy = sm_total_energy(p);
    start = pz_seconds();
    status = sm_panel_release(p, outcome, ctx);
    outcome->phase_two_ms = 1e3 * (pz_seconds() - start);
    return status;
}

/* Panel k flattened again (with_lscm 0: RETRY_PATHS heap paths, 1: from LSCM); kept when better, updating
 * *defects. */
static pz_status retry_piece(sm_piece *piece, sm_panel *panel, sm_outcome *outcome, int with_lscm, int32_t *defects,
                             pz_ctx *ctx)
{
    sm_panel second;
    sm_outcome second_outcome = {0};
    size_t bytes = (size_t)panel->nv * 2 * sizeof(double);
    double *uv = malloc(bytes + 1);
    piece->retry = *panel->settings;
    piece->retry.paths = with_lscm ? piece->retry.paths : RETRY_PATHS;
    memset(&second, 0, sizeof second);
    pz_status status = !uv ? pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory")
                       : with_lscm ? panel_from_lscm(&second, piece->mesh, &piece->retry, uv, &piece->spring,
                                                     &second_outcome, ctx)
                                   : sm_panel_flatten(&second, piece->mesh, &piece->retry, uv, &piece->spring,
                                                      &second_outcome, ctx);
    if (!status && !sm_panel_loop(&second, ctx))
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    int32_t second_defects = status ? -1 : panel_defects(&second);
    if (!status && second_defects < 0)
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    if (!status && (second_defects < *defects ||
                    (second_defects == *defects && sm_total_energy(&second) < sm_total_energy(panel)))) {
        long long work = panel->relaxations;
        double ms = outcome->phase_one_ms + outcome->phase_two_ms;
        sm_panel_free(panel);
        *panel = second;
        memcpy(piece->uv, uv, bytes);
        panel->uv = piece->uv;
        panel->relaxations += work; /* every try counts */
        *outcome = second_outcome;
        outcome->phase_one_ms += ms;
        *defects = second_defects;
    } else {
        sm_panel_free(&second);
    }
    free(uv);
    return status;
}

/* Extracts panel k and runs its phase one and two (and second tries when it ends folded). */
static pz_status start_piece(const pz_pattern *pattern, const int32_t *faces, int32_t face_count, int32_t k,
                             const sm_settings *settings, sm_piece *piece, sm_panel *panel, sm_outcome *outcome,
                             int32_t *retried, pz_ctx *ctx)
{
    if (face_count == 0)
        return pz_error(ctx, PZ_ERR_DATA, "springmass: panel %d has no faces", (int)k);
    pz_status status = pz_mesh_extract(pattern->mesh, faces, face_count, &piece->mesh, &piece->vertex_map, NULL, ctx);
    if (status)
        return status;
    size_t nv = (size_t)piece->mesh->vertex_count;
    piece->uv = malloc(nv * 2 * sizeof(double) + 1);
    piece->map = malloc(nv * sizeof(double) + 1);
    piece->line = malloc(nv * sizeof(int32_t) + 1);
    if (!piece->uv || !piece->map || !piece->line)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    if ((status = sm_panel_flatten(panel, piece->mesh, settings, piece->uv, &piece->spring, outcome, ctx)))
        return status;
    if (!sm_panel_loop(panel, ctx))
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    int32_t defects = panel_defects(panel);
    if (defects < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    *retried += defects > 0;
    if (defects > 0 && settings->heap && settings->paths < RETRY_PATHS)
        status = retry_piece(piece, panel, outcome, 0, &defects, ctx);
    if (!status && defects > 0)
        status = retry_piece(piece, panel, outcome, 1, &defects, ctx);
    return status;
}

/* Writes panel k's coordinates back and fills its record (trial cut when asked). */
static pz_status record_piece(const sm_piece *piece, const sm_outcome *outcome, int32_t panel,
                              const sm_settings *settings, int do_trial_cut, double *uv, pz_springmass_result *result,
                              pz_ctx *ctx)
{
    int32_t nv = piece->mesh->vertex_count;
    for (int32_t v = 0; v < nv; ++v) {
        uv[2 * piece->vertex_map[v]] = piece->uv[2 * v];
        uv[2 * piece->vertex_map[v] + 1] = piece->uv[2 * v + 1];
    }
    if (!result)
        return PZ_OK;
    pz_springmass_panel *record = &result->panels[panel];
    record->panel = panel;
    record->stop = outcome->stop;
    record->iterations = outcome->iterations;
    record->global_iterations = outcome->global_iterations;
    record->phase_one_energy = outcome->phase_one_energy;
    record->final_energy = outcome->final_energy;
    record->e_area = outcome->e_area;
    record->e_shape = outcome->e_shape;
    int32_t top = 0;
    for (int32_t v = 0; v < nv; ++v) {
        result->vertex_energy[piece->vertex_map[v]] = piece->map[v];
        if (piece->map[v] > piece->map[top])
            top = v;
    }
    record->max_energy_vertex = piece->vertex_map[top];
    pz_status status = PZ_OK;
    if (do_trial_cut && piece->line_count >= 2)
        status = sm_trial_cut(piece->mesh, settings, piece->line, piece->line_count, record, ctx);
    record->cut_vertices = malloc((size_t)piece->line_count * sizeof(int32_t) + 1);
    if (!record->cut_vertices)
        return status ? status : pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    for (int32_t i = 0; i < piece->line_count; ++i)
        record->cut_vertices[i] = piece->vertex_map[piece->line[i]];
    record->cut_vertex_count = piece->line_count;
    result->phase_one_energy += outcome->phase_one_energy;
    result->final_energy += outcome->final_energy;
    result->node_relaxations += outcome->relaxations;
    result->phase_one_relaxations += outcome->phase_one_relaxations;
    result->energy_evaluations += outcome->evaluations;
    result->phase_one_ms += outcome->phase_one_ms;
    result->phase_two_ms += outcome->phase_two_ms;
    result->global_iterations += outcome->global_iterations;
    return status;
}

/* Seam matching (unless settings->independent), then the seams' mismatch into result (may be NULL). */
static pz_status match_pieces(const pz_pattern *pattern, const sm_settings *settings, const sm_piece *pieces,
                              sm_panel *panels, sm_outcome *outcomes, pz_springmass_result *result, pz_ctx *ctx)
{
    int32_t np = pattern->panel_count, unmatched = 0;
    int32_t **maps = malloc((size_t)np * sizeof(int32_t *) + 1);
    sm_link *links = NULL;
    int32_t count = maps ? 0 : -1;
    for (int32_t k = 0; count == 0 && k < np; ++k)
        maps[k] = pieces[k].vertex_map;
    if (count == 0)
        count = sm_build_links(pattern, maps, panels, &links);
    free(maps);
    pz_status status = count < 0 ? pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory") : PZ_OK;
    if (!status && count > 0 && !settings->independent)
        status = sm_match_seams(panels, np, links, count, outcomes, &unmatched, ctx);
    if (!status && result) {
        result->matched_pairs = settings->independent ? 0 : count;
        result->unmatched_panels = unmatched;
        result->max_seam_mismatch =
            count > 0 ? sm_worst_mismatch(panels, links, count, pattern->seam_count + pattern->dart_count) : 0;
    }
    free(links);
    return status;
}

pz_status pz_param_springmass(const pz_pattern *pattern, const pz_springmass_options *options, double *uv,
                              pz_springmass_result *result, pz_ctx *ctx)
{
    sm_settings settings;
    settings_from(options, &settings);
    if (result)
        memset(result, 0, sizeof *result);
    int32_t np = pattern->panel_count, *offsets = NULL, *order = NULL, retried = 0;
    pz_status status = pz_param_panel_faces(pattern, &offsets, &order, ctx);
    sm_piece *pieces = status ? NULL : calloc((size_t)np + 1, sizeof *pieces);
    sm_panel *panels = status ? NULL : calloc((size_t)np + 1, sizeof *panels);
    sm_outcome *outcomes = status ? NULL : calloc((size_t)np + 1, sizeof *outcomes);
    if (!status && (!pieces || !panels || !outcomes))
        status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    if (!status && result) {
        result->vertex_count = pattern->mesh->vertex_count;
        result->panel_count = np;
        result->vertex_energy = calloc((size_t)pattern->mesh->vertex_count + 1, sizeof(double));
        result->panels = calloc((size_t)np + 1, sizeof(pz_springmass_panel));
        if (!result->vertex_energy || !result->panels)
            status = pz_error(ctx, PZ_ERR_NOMEM, "springmass: out of memory");
    }
    for (int32_t k = 0; k < np && !status; ++k)
        if (!(status = pz_check_cancel(ctx, "springmass")))
            status = start_piece(pattern, order + offsets[k], offsets[k + 1] - offsets[k], k, &settings, &pieces[k],
                                 &panels[k], &outcomes[k], &retried, ctx);
    if (!status)
        status = match_pieces(pattern, &settings, pieces, panels, outcomes, result, ctx);
    for (int32_t k = 0; k < np && !status; ++k)
        status = sm_panel_finish(&panels[k], &outcomes[k], pieces[k].map, pieces[k].line, &pieces[k].line_count, ctx);
    int do_trial_cut = options && options->trial_cut;
    for (int32_t k = 0; k < np && !status; ++k)
        status = record_piece(&pieces[k], &outcomes[k], k, &settings, do_trial_cut, uv, result, ctx);
    if (result)
        result->retried_panels = retried;
    pieces_free(pieces, panels, np);
    free(outcomes);
    free(order);
    free(offsets);
    if (status && result)
        pz_springmass_result_clear(result);
    return status;
}

