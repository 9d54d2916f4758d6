/*
 * prepare/auto.c -- automatic mode (pz_prepare_auto, `run --prepare auto`):
 * whether to remesh at all, and what to do when a remesh leaves the
 * Hausdorff bound. prepare/prepare.c runs it; docs/prepare.md has the
 * measurements behind the thresholds.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/internal.h"

#include <stdio.h>
#include <stdlib.h>

/*
 * Automatic mode (`panelize run --prepare auto`), measured in
 * docs/prepare.md: the field, tracing and segmentation did best on the
 * paper's densities (2-8K faces) and worse, and 2-4x slower, from ~12K
 * faces on; so a mesh over AUTO_MAX_FACES is remeshed to that (decimated
 * first when huge). Below it the density is kept: refining a coarse mesh
 * adds no shape (the new vertices lie on the old facets) and did not help
 * the pipeline (better in 3 of 7 runs, worse in 4). A mesh with fewer than
 * AUTO_WELL_SHAPED of its faces free of angles under 20 degrees (the
 * paper's "well shaped") is remeshed at its own face count; when that moves
 * the shape beyond the Hausdorff bound (a coarse mesh: remeshing at its own
 * density cuts across its curved facets, the wetsuit's 2274 faces moved
 * 47.8 mm against a bound of 25.1 mm), the input's triangles are kept.
 */
#define AUTO_MAX_FACES 10000
#define AUTO_WELL_SHAPED 0.95

prep_auto_need prep_auto_decide(const pz_mesh *work, const pz_prepare_options *options, double well_shaped,
                                prep_plan *plan, char *why, size_t size)
{
    int32_t most = options->target_faces > 0 ? options->target_faces : AUTO_MAX_FACES;
    if (work->face_count > most) {
        plan->target_faces = most;
        snprintf(why, size, "auto: %d faces, more than the %d the field and segmentation work best with",
                 (int)work->face_count, (int)most);
        return PREP_NEED_DENSITY;
    }
    if (well_shaped < AUTO_WELL_SHAPED) {
        plan->target_faces = work->face_count;
        snprintf(why, size, "auto: %.1f%% of the faces have every angle over 20 degrees (under %.0f%%): remeshed "
                 "at the input's %d faces", 100.0 * well_shaped, 100.0 * AUTO_WELL_SHAPED, (int)work->face_count);
        return PREP_NEED_SHAPE;
    }
    snprintf(why, size, "not needed: %d faces (at most %d), %.1f%% of them with every angle over 20 degrees",
             (int)work->face_count, (int)most, 100.0 * well_shaped);
    return PREP_NEED_NOTHING;
}

/* Drops the remeshed result (auto mode: a remesh that is undone or tried again). */
static void discard_remesh(pz_prepare_result *result)
{
    pz_prepare_report *report = &result->report;
    pz_mesh_free(&result->mesh);
    free(result->seam_offsets);
    free(result->seam_vertices);
    result->seam_offsets = result->seam_vertices = NULL;
    result->seam_count = 0;
    report->decimated_faces = 0;
    report->target_edge = 0.0;
    report->hausdorff = report->pose_hausdorff_max = 0.0;
    report->within_bound = 1;
}

void prep_undo_remesh(pz_prepare_result *result, char *why, size_t size)
{
    pz_prepare_report *report = &result->report;
    snprintf(why, size, "auto: undone: remeshed for shape (%d faces), it moved %.2f mm from the input (bound "
             "%.2f mm): the input's triangles are kept", (int)result->mesh->face_count, report->hausdorff,
             report->hausdorff_bound);
    discard_remesh(result);
}

/*
 * Auto mode, a fine mesh remeshed to fewer faces beyond the Hausdorff bound
 * (a scan with detail finer than the count can hold: the shared face scan,
 * 34K faces, was 1.48 mm from its input at 10000 faces, bound 1.04 mm): the
 * face count is doubled, up to AUTO_RETRY_MAX_FACES and below the input's
 * own count, until the result is within the bound. A badly shaped input
 * (under AUTO_WELL_SHAPED) is then remeshed at its own count, as in the
 * shape case. When no remesh is within the bound, the input is kept as it
 * is (*undone set; the remesh detail lists the counts tried).
 */
#define AUTO_RETRY_MAX_FACES 40000

pz_status prep_retry_denser(const pz_mesh *work, const prep_edge_list *seams, const char *name, prep_plan *plan,
                            double work_shaped, char *why, size_t size, int *undone, pz_prepare_result *result,
                            prep_step_state *state, pz_ctx *ctx)
{
    pz_prepare_report *report = &result->report;
    char tried[120] = "";
    size_t used = 0;
    pz_status status = PZ_OK;
    int own_count_tried = 0;
    while (!status && !report->within_bound) {
        used += (size_t)snprintf(tried + used, sizeof tried - used, "%s%d faces %.2f mm", used ? ", " : "",
                                 (int)result->mesh->face_count, report->hausdorff);
        used = used < sizeof tried ? used : sizeof tried - 1;
        int32_t next = 2 * plan->target_faces;
        if (next > AUTO_RETRY_MAX_FACES || next >= work->face_count) {
            if (own_count_tried || work_shaped >= AUTO_WELL_SHAPED)
                break;
            next = work->face_count; /* badly shaped: its own density is the last try */
            own_count_tried = 1;
        }
        discard_remesh(result);
        plan->target_faces = next;
        snprintf(why, size, "auto: %d faces; beyond the bound %.2f mm at %s: retried at %d faces",
                 (int)work->face_count, report->hausdorff_bound, tried, (int)next);
        status = prep_remesh_all(work, seams, name, plan, why, result, state, ctx);
    }
    if (status || report->within_bound)
        return status;
    snprintf(why, size, "auto: undone: beyond the bound %.2f mm at %s: the input's %d faces (%.1f%% well shaped) "
             "are kept", report->hausdorff_bound, tried, (int)work->face_count, 100.0 * work_shaped);
    discard_remesh(result);
    *undone = 1;
    return PZ_OK;
}
