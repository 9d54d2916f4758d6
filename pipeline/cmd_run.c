/*
 * pipeline/cmd_run.c -- `panelize run GARMENT -o DIR`: the whole pipeline,
 * garment in, sewable pattern out, no hand work (docs/run.md).
 *
 *   read -> prepare (--prepare auto: weld, repair, decimate, remesh only when
 *   the mesh needs it; the welded seams become sketch curves)
 *   -> field (cross-field with sketches and poses) -> segment (the automatic
 *   layout: panels that meet the goals, darts, symmetry) -> the flatten
 *   pipeline (pattern, textile flattening of all panels jointly with seam and
 *   dart symmetry, metrics, pieces, marker, every file all or nothing).
 *
 * With --panels the user's own panels are flattened and segmentation is
 * skipped (so is preparation, which would renumber the faces the panels
 * refer to). run reuses `flatten` through pz_flatten_execute and adds:
 * layout.obj (the seams and darts as polylines on the garment), per panel
 * `corners`, `darts`, `goals` and `mirror_panel`, and in `summary`
 * `goals_met` with the reasons when false, plus a `segmentation` and a
 * `prepare` object in report.json.
 *
 * The goals of the final pattern are judged on the final joint flattening:
 * every panel a disk with at most C corners (pz_segment_goals), every
 * triangle's warp and weft strain within +-S in every pose and no flip or
 * boundary self-intersection (pz_metrics_compute on every pose). Goals
 * stricter than the defaults first lay out the looser settings of a fixed
 * grid and never give fewer panels than they do (solve_setting; docs/segment.md,
 * "Monotone panel counts").
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "pipeline/pattern_output.h"
#include "prepare/prepare.h"
#include "segment/segment.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char pz_cli_run_usage[] =
    "usage: panelize run GARMENT -o DIR [--max-corners C] [--max-strain S]\n"
    "           [--pose FILE]... [--sketch FILE] [--panels FILE|uv]\n"
    "           [--symmetry auto|off|x|y|z] [--darts on|off] [--truing on|off] [--grain X,Y,Z]\n"
    "           [--prepare auto|off] [--backend textile|lscm|wirewarp|springmass]\n"
    "           [--iterations N] [--weights S,R,D,M] [--fabric KSU,KSV,KR]\n"
    "           [--seam-allowance MM] [--hem-allowance MM] [--allowances FILE]\n"
    "           [--notch-spacing MM] [--paper a4|letter] [--dxf-strict]\n"
    "           [--fabric-width MM] [--gap MM] [--size NAME] [--units U] [--repair]\n"
    "           [--json] [--quiet]\n"
    "\n"
    "Cuts a 3D garment into panels along field-aligned seams, adds darts and\n"
    "flattens every panel into a sewable pattern. Writes into DIR everything\n"
    "`panelize flatten` writes (garment.obj, the pattern files, report.json)\n"
    "plus layout.obj, the seams and darts as polylines on the 3D garment.\n"
    "\n"
    "options:\n"
    "  -o DIR               the output directory (required)\n"
    "  --max-corners C      at most C corners per panel (default 8)\n"
    "  --max-strain S       every triangle's warp and weft strain within +-S\n"
    "                       (default 0.05: 5% in tension or compression)\n"
    "  --symmetry M         auto (default: detect a mirror plane), off, x, y or z\n"
    "  --darts on|off       insert darts where a seam can be partly closed (default on)\n"
    "  --truing on|off      smooth the seams traced along mesh edges into clean lines\n"
    "                       by moving their vertices along the surface (default on;\n"
    "                       off keeps garment.obj's positions exactly the input's)\n"
    "  --sketch FILE        JSON {\"curves\": [[[x,y,z], ...], ...]} in the garment's\n"
    "                       units: curves that become seams, never removed\n"
    "  --panels FILE|uv     the user's own panels (see panelize flatten): no\n"
    "                       segmentation, no preparation\n"
    "  --prepare auto|off   auto (default): weld, repair and remesh the garment\n"
    "                       only when it needs it (see panelize prepare)\n"
    "  --grain X,Y,Z        the 3D warp direction (default: the garment's vertical)\n"
    "  --pose FILE          an extra pose with the same connectivity (repeatable)\n"
    "  other options        as in panelize flatten --help\n"
    "\n"
    "See docs/run.md.\n";

#define DEFAULT_MAX_CORNERS 8
#define DEFAULT_MAX_STRAIN 0.05
/* The final verdict (accept_pattern): layouts made again at most this many times, each round after the
 * first asking the segmentation's evaluations for VERDICT_MARGIN_STEP more strain margin (at most
 * VERDICT_MARGIN_MAX). */
#define MAX_VERDICT_ROUNDS 6
#define VERDICT_MARGIN_STEP 0.1
#define VERDICT_MARGIN_MAX 0.5

/* One goal setting's layouts and verdict rounds: the run's own goals, and each looser setting of the
 * ladder that keeps panel counts monotone (ladder_cuts). */
typedef struct goal_setting {
    int32_t max_corners;
    double max_strain;
    uint64_t *vetoed;                /* face-set keys of panels the joint flattening rejected */
    int32_t vetoed_count;
    int32_t verdict_rounds;          /* segmentations redone because of them */
    pz_segment_cache *cache;         /* evaluations shared by the rounds */
    char verdict_reasons[512];       /* the last rejection's panels, for the progress note */
} goal_setting;

static void goal_setting_clear(goal_setting *goals)
{
    free(goals->vetoed);
    pz_segment_cache_free(&goals->cache);
    goals->vetoed = NULL;
    goals->vetoed_count = 0;
}

/* A looser goal setting's final cut edges (flags over the garment's topology edges), computed once. */
typedef struct ladder_rung {
    int32_t max_corners;
    double max_strain;
    uint8_t *cuts;
    int32_t panels;
} ladder_rung;

typedef struct run_state {
    const pz_cli_args *args;
    /* settings */
    int32_t max_corners;
    double max_strain;
    pz_symmetry_mode symmetry;
    int darts;
    int prepare_auto;
    const char *sketch_path;
    int grain_given;
    double grain[3];
    /* results */
    pz_prepare_result *prepared;     /* --prepare auto, when it ran */
    pz_segment_result *segment;      /* NULL with --panels */
    int32_t field_singularities;
    double prepare_ms, field_ms, segment_ms;
    int32_t *panel_mirror;           /* pattern panel -> mirror panel (segmentation only) */
    int32_t *layout_vertices;        /* garment vertices of the seam and dart polylines */
    int32_t *layout_offsets;         /* layout_count + 1 */
    uint8_t *layout_is_dart;         /* layout_count */
    int32_t layout_count;
    int goals_met;
    int32_t failing_panels;          /* of the final pattern */
    double worst_strain;             /* of the final pattern, over every pose */
    char reasons[1024];
    /* The run's own goals and its verdict rounds (accept_pattern). */
    goal_setting goals;
    /* Seam truing (on by default): the garment before it, and what it did. */
    int truing;
    double *original_positions, *original_poses;
    pz_truing_result truing_result;
    const pz_mesh *garment;          /* the garment choose_panels segmented (for the verdict's goals) */
    pz_field *field;                 /* the cross-field of the original surface, computed once */
    /* Monotone panel counts (ladder_cuts): the looser settings' final cuts, seeded into this run's layout. */
    int ladder_done;                 /* 1: the layout and its verdict rounds were made by solve_setting */
    int seeded;                      /* 1: its own layout had fewer panels than a looser setting's: seeded */
    ladder_rung *rungs;
    int32_t rung_count, rung_capacity;
    int32_t seed_panels;             /* the most panels among the parent settings */
    double ladder_ms;
    pz_ctx *note_ctx;                /* the command's context, for notes from the report callbacks */
    double pattern_residual_rms_mm;  /* the pattern's mirror symmetry (measure_pattern_symmetry), -1 unknown */
    double pattern_residual_max_mm;
} run_state;

/* ---------------------------------------------------------------- options */

static pz_status parse_run_options(const pz_cli_args *args, run_state *state, pz_ctx *ctx)
{
    state->max_corners = DEFAULT_MAX_CORNERS;
    state->max_strain = DEFAULT_MAX_STRAIN;
    state->darts = 1;
    state->truing = 1;
    state->prepare_auto = 1;
    const char *text;
    if ((text = pz_cli_value(args, PZ_CLI_OPT_MAX_CORNERS))) {
        char *end = NULL;
        errno = 0;
        long corners = strtol(text, &end, 10);
        if (end == text || *end || errno == ERANGE || corners < 1 || corners > 1000)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --max-corners: '%s' is not a whole number in 1..1000", text);
        state->max_corners = (int32_t)corners;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_MAX_STRAIN))) {
        char *end = NULL;
        errno = 0;
        double strain = strtod(text, &end);
        if (end == text || *end || errno == ERANGE || !isfinite(strain) || strain < 0 || strain > 10)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --max-strain: '%s' is not a number in 0..10", text);
        state->max_strain = strain;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_SYMMETRY))) {
        static const char *const names[] = {"auto", "off", "x", "y", "z"};
        static const pz_symmetry_mode modes[] = {PZ_SYMMETRY_AUTO, PZ_SYMMETRY_OFF, PZ_SYMMETRY_X, PZ_SYMMETRY_Y,
                                                 PZ_SYMMETRY_Z};
        int found = 0;
        for (int i = 0; i < 5; ++i)
            if (strcmp(text, names[i]) == 0)
                state->symmetry = modes[i], found = 1;
        if (!found)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --symmetry: '%s' is not auto, off, x, y or z", text);
    }
    if (args->dart_path_count > 1)
        return pz_error(ctx, PZ_ERR_USAGE, "run: --darts given twice");
    if (args->dart_path_count == 1) {
        if (strcmp(args->dart_paths[0], "on") != 0 && strcmp(args->dart_paths[0], "off") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --darts: '%s' is not on or off", args->dart_paths[0]);
        state->darts = strcmp(args->dart_paths[0], "on") == 0;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_PREPARE))) {
        if (strcmp(text, "auto") != 0 && strcmp(text, "off") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --prepare: '%s' is not auto or off", text);
        state->prepare_auto = strcmp(text, "auto") == 0;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_TRUING))) {
        if (strcmp(text, "on") != 0 && strcmp(text, "off") != 0)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --truing: '%s' is not on or off", text);
        state->truing = strcmp(text, "on") == 0;
    }
    if (pz_cli_value(args, PZ_CLI_OPT_PANELS))
        state->prepare_auto = 0;  /* the user's panels refer to the input's faces as they are */
    if ((text = pz_cli_value(args, PZ_CLI_OPT_SKETCH))) {
        if (!*text)
            return pz_error(ctx, PZ_ERR_USAGE, "run: --sketch: empty file name");
        state->sketch_path = text;
    }
    if ((text = pz_cli_value(args, PZ_CLI_OPT_GRAIN))) {
        /* flatten checks the text itself; run only needs the direction for the goals. */
        if (sscanf(text, "%lf,%lf,%lf", &state->grain[0], &state->grain[1], &state->grain[2]) == 3) {
            double length = sqrt(state->grain[0] * state->grain[0] + state->grain[1] * state->grain[1] +
                                 state->grain[2] * state->grain[2]);
            if (length > 0 && isfinite(length)) {
                for (int k = 0; k < 3; ++k)
                    state->grain[k] /= length;
                state->grain_given = 1;
            }
        }
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- preparation */

static pz_status prepare_mesh(void *user, pz_mesh **mesh, int *changed, pz_ctx *ctx)
{
    run_state *state = user;
    *changed = 0;
    if (!state->prepare_auto)
        return PZ_OK;
    double start = pz_seconds();
    pz_prepare_options options = {0};
    options.name = state->args->positionals[0];
    int quiet = ctx->quiet;
    ctx->quiet = 1;  /* the steps are summarized below, not noted one by one */
    pz_status status = pz_prepare_auto(*mesh, &options, &state->prepared, ctx);
    ctx->quiet = quiet;
    state->prepare_ms = pz_cli_elapsed_ms(start, pz_seconds());
    if (status != PZ_OK)
        return status;
    const pz_prepare_report *report = &state->prepared->report;
    int any_change = report->output_faces != report->input_faces || report->output_vertices != report->input_vertices;
    for (int i = 0; i < PZ_PREPARE_STEP_COUNT; ++i) {
        const pz_prepare_step *step = &report->steps[i];
        /* A remesh that was tried and undone says why; one that was not needed stays quiet. */
        int tried = i == PZ_PREPARE_REMESH && strstr(step->detail, "undone") != NULL;
        if ((step->ran || tried) && i != PZ_PREPARE_HAUSDORFF)
            pz_note(ctx, "run: prepare: %s%s: %s", step->name, step->ran ? "" : " (not kept)", step->detail);
    }
    if (any_change) {
        pz_mesh_free(mesh);
        *mesh = state->prepared->mesh;
        state->prepared->mesh = NULL;
        *changed = 1;
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- segmentation */

static void on_progress(void *user, const char *stage, int32_t panel_count, double worst_strain)
{
    pz_ctx *ctx = user;
    if (worst_strain >= 0)
        pz_note(ctx, "run: %s: %d panels, worst strain %.4f", stage, (int)panel_count, worst_strain);
    else
        pz_note(ctx, "run: %s: %d panels", stage, (int)panel_count);
}

/* The --sketch curves plus the seams preparation welded (a designer's seams survive the weld). */
static pz_status gather_sketch(const run_state *state, const pz_mesh *mesh, pz_sketch **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_sketch *given = NULL;
    if (state->sketch_path) {
        pz_status status = pz_sketch_read(state->sketch_path, mesh->unit_scale, &given, ctx);
        if (status != PZ_OK)
            return status;
    }
    const pz_prepare_result *prepared = state->prepared;
    int32_t welded = prepared && prepared->mesh == NULL ? prepared->seam_count : 0;
    if (welded == 0) {
        *out = given;
        return PZ_OK;
    }
    int32_t given_curves = given ? given->curve_count : 0;
    int32_t given_points = given ? given->curve_offsets[given_curves] : 0;
    int32_t points = given_points + prepared->seam_offsets[welded];
    pz_sketch *sketch = calloc(1, sizeof *sketch);
    if (sketch) {
        sketch->curve_offsets = malloc(((size_t)given_curves + (size_t)welded + 1) * sizeof(int32_t));
        sketch->points = malloc(((size_t)points + 1) * 3 * sizeof(double));
    }
    if (!sketch || !sketch->curve_offsets || !sketch->points) {
        pz_sketch_free(&sketch);
        pz_sketch_free(&given);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory gathering sketches");
    }
    int32_t at = 0;
    for (int32_t c = 0; c < given_curves; ++c)
        sketch->curve_offsets[sketch->curve_count++] = given->curve_offsets[c];
    if (given_points)
        memcpy(sketch->points, given->points, 3 * (size_t)given_points * sizeof(double));
    at = given_points;
    for (int32_t s = 0; s < welded; ++s) {
        int32_t first = prepared->seam_offsets[s], last = prepared->seam_offsets[s + 1];
        if (last - first < 2)
            continue;
        sketch->curve_offsets[sketch->curve_count++] = at;
        for (int32_t i = first; i < last; ++i, ++at)
            memcpy(sketch->points + 3 * (size_t)at, mesh->positions + 3 * (size_t)prepared->seam_vertices[i],
                   3 * sizeof(double));
    }
    sketch->curve_offsets[sketch->curve_count] = at;
    pz_sketch_free(&given);
    *out = sketch;
    return PZ_OK;
}

/* The garment as it was before the first truing (each verdict round segments the original surface). */
static pz_status keep_or_restore_original(run_state *state, pz_mesh *garment, pz_ctx *ctx)
{
    size_t positions = (size_t)garment->vertex_count * 3, poses = positions * (size_t)garment->pose_count;
    if (state->original_positions) {
        memcpy(garment->positions, state->original_positions, positions * sizeof(double));
        if (poses)
            memcpy(garment->poses, state->original_poses, poses * sizeof(double));
        return PZ_OK;
    }
    state->original_positions = malloc(positions * sizeof(double) + 1);
    state->original_poses = malloc(poses * sizeof(double) + 1);
    if (!state->original_positions || !state->original_poses)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    memcpy(state->original_positions, garment->positions, positions * sizeof(double));
    if (poses)
        memcpy(state->original_poses, garment->poses, poses * sizeof(double));
    return PZ_OK;
}

/* One layout of the garment under `goals` (vetoes, margin and cache from its verdict rounds), with the
 * seeds (cut edges never removed) when given. progress: the context the segmentation's notes go to. */
static pz_status segment_once(const run_state *state, const pz_mesh *garment, const pz_topology *topology,
                              const pz_sketch *sketch, goal_setting *goals, const uint8_t *seeds, pz_ctx *progress,
                              pz_segment_result **out, pz_ctx *ctx)
{
    pz_segment_options options;
    pz_segment_options_default(&options);
    options.max_corners = goals->max_corners;
    options.max_strain = goals->max_strain;
    options.symmetry = state->symmetry;
    options.darts = state->darts;
    options.sketch = sketch;
    options.seed_cuts = seeds;
    if (state->grain_given)
        memcpy(options.grain, state->grain, sizeof options.grain);
    else
        pz_mesh_vertical_axis(garment, options.grain);
    options.on_progress = on_progress;
    options.user = progress;
    options.vetoed = goals->vetoed;
    options.vetoed_count = goals->vetoed_count;
    if (!goals->cache && !(goals->cache = pz_segment_cache_create()))
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    options.cache = goals->cache;
    /* The first verdict round only vetoes the rejected panels; from the second on, each round asks
     * the evaluations for 10 % more strain margin (at most 50 %): they were too optimistic here. */
    int margin_rounds = goals->verdict_rounds > 1 ? goals->verdict_rounds - 1 : 0;
    options.strain_margin = fmin(VERDICT_MARGIN_MAX, VERDICT_MARGIN_STEP * margin_rounds);
    if (goals->verdict_rounds > 0)
        pz_note(progress, "run: segment again (round %d): the joint flattening rejected %s",
                (int)goals->verdict_rounds + 1, goals->verdict_reasons);
    return pz_segment(garment, topology, state->field, &options, out, ctx);
}

static int verdict_check(goal_setting *goals, const pz_mesh *garment, const pz_segment_result *segment,
                         const pz_pattern *pattern, const pz_metrics *metrics, const double *pose_strain);
static double *strain_of_poses(const pz_pattern *pattern, const double *uv, const pz_fabric *fabric);
static pz_status ladder_parents(run_state *state, pz_mesh *garment, const pz_topology *topology,
                                const pz_sketch *sketch, double max_strain, int32_t max_corners, uint8_t **seeds,
                                int32_t *most_panels, pz_ctx *ctx);
static pz_status solve_setting(run_state *state, pz_mesh *garment, const pz_topology *topology,
                               const pz_sketch *sketch, double max_strain, int32_t max_corners, goal_setting *goals,
                               pz_segment_result **out, int *seeded, int32_t *most_panels, pz_ctx *ctx);

static pz_status choose_panels(void *user, pz_mesh *garment, int32_t **face_panel, int32_t *panel_count,
                               uint8_t **extra_cuts, pz_ctx *ctx)
{
    run_state *state = user;
    state->garment = garment;
    state->goals.max_corners = state->max_corners;
    state->goals.max_strain = state->max_strain;
    pz_status restored = keep_or_restore_original(state, garment, ctx);
    if (restored != PZ_OK)
        return restored;
    pz_topology *topology = NULL;
    pz_sketch *sketch = NULL;
    pz_status status = pz_topology_build(garment, &topology, ctx);
    if (status == PZ_OK)
        status = gather_sketch(state, garment, &sketch, ctx);
    double start = pz_seconds();
    /* The field depends on the original surface only: a verdict round reuses it. */
    if (status == PZ_OK && !state->field) {
        pz_field_options options = {0};
        options.sketch = sketch;
        options.use_poses = 1;
        status = pz_field_compute(garment, topology, &options, &state->field, ctx);
        state->field_ms = pz_cli_elapsed_ms(start, pz_seconds());
        if (status == PZ_OK)
            pz_note(ctx, "run: field: %.0f ms, %d singularities", state->field_ms,
                    (int)state->field->singularity_count);
    }
    double field_end = pz_seconds();
    /* Goals stricter than the defaults: the layout is made here, verdict rounds included, so that it has at
     * least as many panels as every looser setting of the ladder (solve_setting); the flatten pipeline's
     * own verdict then accepts it as it is (the same flattening: accept_pattern). */
    int stricter = state->max_strain < DEFAULT_MAX_STRAIN || state->max_corners < DEFAULT_MAX_CORNERS;
    if (status == PZ_OK && stricter && !state->ladder_done) {
        state->ladder_done = 1;
        state->field_singularities = state->field->singularity_count;
        pz_segment_result_free(&state->segment);
        status = solve_setting(state, garment, topology, sketch, state->max_strain, state->max_corners, &state->goals,
                               &state->segment, &state->seeded, &state->seed_panels, ctx);
        if (status == PZ_OK)
            status = keep_or_restore_original(state, garment, ctx);
        if (status == PZ_OK)
            pz_note(ctx, "run: %d looser settings laid out first in %.0f ms (at most %d panels); this layout: %d panels%s",
                    (int)state->rung_count, state->ladder_ms, (int)state->seed_panels, (int)state->segment->panel_count,
                    state->seeded ? ", seeded with their cuts (its own layout had fewer)" : "");
    } else if (status == PZ_OK) {
        state->field_singularities = state->field->singularity_count;
        pz_segment_result_free(&state->segment);
        status = segment_once(state, garment, topology, sketch, &state->goals, NULL, ctx, &state->segment, ctx);
    }
    state->segment_ms = pz_cli_elapsed_ms(field_end, pz_seconds());
    if (status == PZ_OK && state->truing) {
        status = pz_segment_true_seams(garment, topology, state->segment->edge_cut, NULL, &state->truing_result, ctx);
        if (status == PZ_OK)
            pz_note(ctx, "run: truing: %d seam vertices moved (at most %.1f mm), %d neighbours relaxed; "
                    "mean turn between seam edges %.1f -> %.1f degrees", (int)state->truing_result.moved_vertices,
                    state->truing_result.max_move_mm, (int)state->truing_result.relaxed_vertices,
                    state->truing_result.mean_turn_before_deg, state->truing_result.mean_turn_after_deg);
    }
    if (status == PZ_OK) {
        const pz_segment_result *segment = state->segment;
        size_t faces = (size_t)garment->face_count, edges = (size_t)topology->edge_count;
        *face_panel = malloc((faces + 1) * sizeof(int32_t));
        *extra_cuts = malloc(edges + 1);
        if (!*face_panel || !*extra_cuts)
            status = pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
        else {
            memcpy(*face_panel, segment->face_panel, faces * sizeof(int32_t));
            memcpy(*extra_cuts, segment->extra_cuts, edges);
            *panel_count = segment->panel_count;
        }
        pz_note(ctx, "run: segment: %.0f ms, %d panels, %d darts%s", state->segment_ms, (int)segment->panel_count,
                (int)segment->dart_count, segment->goals_met ? "" : " (goals not met)");
    }
    pz_sketch_free(&sketch);
    pz_topology_free(&topology);
    return status;
}

/* ---------------------------------------------------------------- monotone panel counts */

/*
 * A stricter goal must never give fewer panels (issue 5). A greedy layout
 * depends on its path, so this is built in: goals (S, C) stricter than the
 * defaults have parents on a fixed grid, (the next S rung up, C) when
 * S < 0.05 (rungs at multiples of 0.01) and (S, C + 1) when C < 8; each
 * parent's FINAL cut edges (its own ladder, layout and verdict rounds, as a
 * run with those goals makes them) are seeded into this layout and never
 * removed, so every parent panel is a union of panels here.
 * docs/segment.md, "Monotone panel counts".
 */
#define LADDER_RUNGS_PER_UNIT 100  /* S rungs at the multiples of 0.01 */

static double ladder_strain_above(double strain)
{
    int rung = (int)floor(strain * LADDER_RUNGS_PER_UNIT + 1e-9) + 1;
    /* A division, not rung * 0.01: 3 / 100.0 is the double a user's "0.03" parses to, 3 * 0.01 is not. */
    double above = rung / (double)LADDER_RUNGS_PER_UNIT;
    return above >= DEFAULT_MAX_STRAIN - 1e-12 ? DEFAULT_MAX_STRAIN : above;
}

/* The flattening `panelize flatten` would make of the pattern with the run's options (its back-end
 * choice for textile and lscm; wirewarp and springmass rungs are judged on textile). */
static pz_status ladder_flatten(const run_state *state, const pz_pattern *pattern, double max_strain, double *uv,
                                pz_ctx *ctx)
{
    return pz_flatten_pattern_like_cli(state->args, state->garment, pattern, max_strain, uv, NULL, ctx);
}

/* The fabric constants flatten measures with (--fabric or its defaults). */
static pz_fabric ladder_fabric(const run_state *state)
{
    pz_fabric fabric = {0.946, 0.548, 0.159};
    pz_ctx quiet;
    pz_ctx_init(&quiet);
    quiet.quiet = 1;
    pz_flatten_pattern_like_cli(state->args, state->garment, NULL, 0, NULL, &fabric, &quiet);
    return fabric;
}

/* One verdict round of a rung, as pz_flatten_execute makes it for the run: pattern, joint flattening,
 * rest-pose metrics, verdict. Sets *accepted. A pattern that cannot be built or flattened is accepted
 * as laid out (the run with those goals would have stopped there). */
static pz_status ladder_round(const run_state *state, pz_mesh *garment, const pz_segment_result *segment,
                              goal_setting *goals, int *accepted, pz_ctx *ctx)
{
    pz_ctx quiet;
    pz_ctx_init(&quiet);
    quiet.quiet = 1;
    pz_correspondences none;
    memset(&none, 0, sizeof none);
    pz_pattern *pattern = NULL;
    pz_metrics *metrics = NULL;
    double *uv = NULL;
    *accepted = 1;
    pz_status status = pz_pattern_build(garment, segment->face_panel, segment->extra_cuts, &none,
                                        state->args->positionals[0], &pattern, &quiet);
    if (status == PZ_OK && !(uv = calloc(2 * (size_t)pattern->mesh->vertex_count + 2, sizeof(double))))
        status = PZ_ERR_NOMEM;
    if (status == PZ_OK)
        status = ladder_flatten(state, pattern, goals->max_strain, uv, &quiet);
    pz_fabric fabric = ladder_fabric(state);
    if (status == PZ_OK)
        status = pz_metrics_compute(pattern, uv, 0, &fabric, &metrics, &quiet);
    double *pose_strain = NULL;
    if (status == PZ_OK && pattern->mesh->pose_count > 0 && !(pose_strain = strain_of_poses(pattern, uv, &fabric)))
        status = PZ_ERR_NOMEM;
    if (status == PZ_OK)
        *accepted = verdict_check(goals, garment, segment, pattern, metrics, pose_strain);
    free(pose_strain);
    pz_metrics_free(&metrics);
    free(uv);
    pz_pattern_free(&pattern);
    if (status == PZ_ERR_NOMEM)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory laying out the looser goals");
    return PZ_OK;
}

/* Layouts and verdict rounds under `goals` until the verdict accepts, as the run with those goals makes
 * them; *out is the last layout (the garment is left trued for it). */
static pz_status verdict_rounds(run_state *state, pz_mesh *garment, const pz_topology *topology,
                                const pz_sketch *sketch, goal_setting *goals, const uint8_t *seeds,
                                pz_segment_result **out, pz_ctx *ctx)
{
    pz_ctx quiet;
    pz_ctx_init(&quiet);
    quiet.quiet = 1;
    pz_status status = PZ_OK;
    for (int accepted = 0; status == PZ_OK && !accepted;) {
        pz_segment_result_free(out);
        status = keep_or_restore_original(state, garment, ctx);
        if (status == PZ_OK)
            status = segment_once(state, garment, topology, sketch, goals, seeds, &quiet, out, ctx);
        if (status == PZ_OK && state->truing)
            status = pz_segment_true_seams(garment, topology, (*out)->edge_cut, NULL, NULL, ctx);
        if (status == PZ_OK)
            status = ladder_round(state, garment, *out, goals, &accepted, ctx);
    }
    return status;
}

/*
 * The final layout of the setting (max_strain, max_corners) with at least as
 * many panels as each of its parents: its own layout when that has enough,
 * otherwise the layout seeded with the parents' cuts (a refinement of each).
 * *goals receives the setting's verdict state, *seeded whether the seeds were
 * needed, *most_panels the parents' largest count (0 without parents).
 */
static pz_status solve_setting(run_state *state, pz_mesh *garment, const pz_topology *topology,
                               const pz_sketch *sketch, double max_strain, int32_t max_corners, goal_setting *goals,
                               pz_segment_result **out, int *seeded, int32_t *most_panels, pz_ctx *ctx)
{
    uint8_t *seeds = NULL;
    *seeded = 0;
    double start = pz_seconds();
    pz_status status = ladder_parents(state, garment, topology, sketch, max_strain, max_corners, &seeds, most_panels,
                                      ctx);
    if (goals == &state->goals)
        state->ladder_ms = pz_cli_elapsed_ms(start, pz_seconds());  /* the run's own: its looser settings' time */
    goals->max_corners = max_corners;
    goals->max_strain = max_strain;
    if (status == PZ_OK)
        status = verdict_rounds(state, garment, topology, sketch, goals, NULL, out, ctx);
    if (status == PZ_OK && seeds && (*out)->panel_count < *most_panels) {
        goal_setting_clear(goals);
        memset(goals, 0, sizeof *goals);
        goals->max_corners = max_corners;
        goals->max_strain = max_strain;
        *seeded = 1;
        status = verdict_rounds(state, garment, topology, sketch, goals, seeds, out, ctx);
    }
    free(seeds);
    return status;
}

/* The final cut edges of the setting (max_strain, max_corners), from the memo or made now (solve_setting).
 * *index: its rung in state->rungs. */
static pz_status ladder_cuts(run_state *state, pz_mesh *garment, const pz_topology *topology, const pz_sketch *sketch,
                             double max_strain, int32_t max_corners, int32_t *index, pz_ctx *ctx)
{
    for (int32_t i = 0; i < state->rung_count; ++i)
        if (state->rungs[i].max_strain == max_strain && state->rungs[i].max_corners == max_corners) {
            *index = i;
            return PZ_OK;
        }
    double start = pz_seconds();
    goal_setting goals;
    memset(&goals, 0, sizeof goals);
    pz_segment_result *segment = NULL;
    int seeded = 0;
    int32_t most_panels = 0;
    pz_status status = solve_setting(state, garment, topology, sketch, max_strain, max_corners, &goals, &segment,
                                     &seeded, &most_panels, ctx);
    if (status == PZ_OK && state->rung_count == state->rung_capacity) {
        int32_t capacity = state->rung_capacity ? 2 * state->rung_capacity : 8;
        ladder_rung *grown = realloc(state->rungs, (size_t)capacity * sizeof *grown);
        if (!grown)
            status = pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
        else
            state->rungs = grown, state->rung_capacity = capacity;
    }
    if (status == PZ_OK) {
        ladder_rung *rung = state->rungs + state->rung_count;
        rung->max_strain = max_strain;
        rung->max_corners = max_corners;
        rung->panels = segment->panel_count;
        rung->cuts = malloc((size_t)topology->edge_count + 1);
        if (!rung->cuts)
            status = pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
        else {
            memcpy(rung->cuts, segment->edge_cut, (size_t)topology->edge_count);
            *index = state->rung_count++;
            pz_note(ctx, "run: looser goals S = %g, C = %d: %d panels%s%s, %d verdict rounds, %.0f ms", max_strain,
                    (int)max_corners, (int)segment->panel_count, seeded ? " (seeded with their looser goals' cuts)" : "",
                    segment->goals_met ? "" : " (goals not met)", (int)goals.verdict_rounds,
                    pz_cli_elapsed_ms(start, pz_seconds()));
        }
    }
    pz_segment_result_free(&segment);
    goal_setting_clear(&goals);
    return status;
}

/* The union of the final cuts of the parents of (max_strain, max_corners) into *seeds (NULL: no parent,
 * the goals are not stricter than the defaults) and the most panels among them. */
static pz_status ladder_parents(run_state *state, pz_mesh *garment, const pz_topology *topology,
                                const pz_sketch *sketch, double max_strain, int32_t max_corners, uint8_t **seeds,
                                int32_t *most_panels, pz_ctx *ctx)
{
    *seeds = NULL;
    *most_panels = 0;
    double parent_strain[2] = {ladder_strain_above(max_strain), max_strain};
    int32_t parent_corners[2] = {max_corners, max_corners + 1};
    int has_parent[2] = {max_strain < DEFAULT_MAX_STRAIN, max_corners < DEFAULT_MAX_CORNERS};
    if (!has_parent[0] && !has_parent[1])
        return PZ_OK;
    if (!(*seeds = calloc((size_t)topology->edge_count + 1, 1)))
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    for (int k = 0; k < 2; ++k) {
        if (!has_parent[k])
            continue;
        int32_t index = -1;
        pz_status status = ladder_cuts(state, garment, topology, sketch, parent_strain[k], parent_corners[k],
                                       &index, ctx);
        if (status != PZ_OK)
            return status;
        const ladder_rung *rung = state->rungs + index;  /* after the call: the memo may have moved */
        for (int32_t e = 0; e < topology->edge_count; ++e)
            (*seeds)[e] |= rung->cuts[e];
        if (rung->panels > *most_panels)
            *most_panels = rung->panels;
    }
    return PZ_OK;
}

/*
 * The final verdict (docs/run.md): the segmentation judged each panel on its
 * own flattening; the joint flattening couples the panels through their seams
 * (equal lengths) and can push one past the strain goal or make a dart's legs
 * cross. Such panels are vetoed (pz_segment_options.vetoed) and the layout is
 * made again, at most MAX_VERDICT_ROUNDS times; then the last pattern stands,
 * marked by judge_goals. Returns 1 to accept the pattern.
 */
/* The garment's faces bucketed by pattern panel, each bucket increasing: panel p's faces are
 * (*order)[(*offsets)[p] .. (*offsets)[p + 1] - 1]. 0 when out of memory; the caller frees both. */
static int faces_by_panel(const pz_pattern *pattern, int32_t **offsets, int32_t **order)
{
    int32_t panels = pattern->panel_count, faces = pattern->mesh->face_count;
    *offsets = calloc((size_t)panels + 2, sizeof(int32_t));
    *order = malloc(((size_t)faces + 1) * sizeof(int32_t));
    if (!*offsets || !*order)
        return 0;
    for (int32_t f = 0; f < faces; ++f)
        ++(*offsets)[pattern->face_panel[f] + 2];
    for (int32_t p = 0; p < panels; ++p)
        (*offsets)[p + 2] += (*offsets)[p + 1];
    for (int32_t f = 0; f < faces; ++f)
        (*order)[(*offsets)[pattern->face_panel[f] + 1]++] = f;
    return 1;
}

static pz_status judge_panels(const pz_mesh *garment, const pz_pattern *pattern, const pz_metrics *metrics,
                              const double *pose_strain, int32_t max_corners, double max_strain,
                              pz_segment_panel *panels, pz_ctx *ctx);

/* The verdict on one flattening under `goals`: 1 accepts; 0 vetoes the failing panels for the next
 * layout. A layout that already misses its goals (unreachable ones) is accepted at once: making it
 * again cannot help, and each round costs a layout and a joint flattening. */
static int verdict_check(goal_setting *goals, const pz_mesh *garment, const pz_segment_result *segment,
                         const pz_pattern *pattern, const pz_metrics *metrics, const double *pose_strain)
{
    if (!segment || !garment || !segment->goals_met || goals->verdict_rounds >= MAX_VERDICT_ROUNDS)
        return 1;
    int32_t panels = pattern->panel_count, added = 0, *offsets = NULL, *order = NULL;
    goals->verdict_reasons[0] = '\0';
    int bucketed = faces_by_panel(pattern, &offsets, &order);
    pz_segment_panel *judged = calloc((size_t)panels + 1, sizeof *judged);
    uint64_t *grown = realloc(goals->vetoed, ((size_t)goals->vetoed_count + panels + 1) * sizeof(uint64_t));
    if (grown)
        goals->vetoed = grown;
    pz_ctx quiet_ctx;
    pz_ctx_init(&quiet_ctx);
    quiet_ctx.quiet = 1;
    /* Every goal, judged as the report will judge it: strain and injectivity on the joint flattening,
     * disk and corners on the trued outline. */
    if (!bucketed || !judged || !grown ||
        judge_panels(garment, pattern, metrics, pose_strain, goals->max_corners, goals->max_strain, judged,
                     &quiet_ctx) !=
            PZ_OK) {
        free(offsets), free(order), free(judged);
        return 1;
    }
    pz_goal_options options = {goals->max_corners, goals->max_strain, {0, 0, 1}, 0};
    for (int32_t p = 0; p < panels; ++p) {
        if (!judged[p].goals.failures)
            continue;
        goals->vetoed[goals->vetoed_count + added++] =
            pz_segment_face_set_key(order + offsets[p], offsets[p + 1] - offsets[p]);
        /* Why, for the note the next round prints. */
        char text[256];
        pz_goal_describe(&judged[p].goals, &options, text, sizeof text);
        size_t used = strlen(goals->verdict_reasons);
        snprintf(goals->verdict_reasons + used, sizeof goals->verdict_reasons - used, "%spanel %d (%d faces): %s",
                 used ? "; " : "", (int)p, (int)(offsets[p + 1] - offsets[p]), text);
    }
    free(offsets);
    free(order);
    free(judged);
    if (added == 0)
        return 1;
    goals->vetoed_count += added;
    ++goals->verdict_rounds;
    return 0;
}

static int accept_pattern(void *user, const pz_pattern *pattern, const double *uv, const pz_metrics *metrics)
{
    run_state *state = user;
    if (state->ladder_done)
        return 1;  /* solve_setting ran the verdict rounds on this very flattening */
    /* The goal holds in every pose: the flatten pipeline gives the rest pose's metrics, the other poses
     * are measured here on the same pattern points. */
    double *pose_strain = NULL;
    if (state->segment && state->segment->goals_met && pattern->mesh->pose_count > 0 &&
        state->goals.verdict_rounds < MAX_VERDICT_ROUNDS) {
        pz_fabric fabric = ladder_fabric(state);
        pose_strain = strain_of_poses(pattern, uv, &fabric);
    }
    int accepted = verdict_check(&state->goals, state->garment, state->segment, pattern, metrics, pose_strain);
    free(pose_strain);
    return accepted;
}

/* Each panel's worst |warp| or |weft| strain over the extra poses (poses 1 .. pose_count of the cut mesh);
 * NULL when out of memory or a measurement fails. The caller frees it. */
static double *strain_of_poses(const pz_pattern *pattern, const double *uv, const pz_fabric *fabric)
{
    double *strain = calloc((size_t)pattern->panel_count + 1, sizeof(double));
    pz_ctx quiet;
    pz_ctx_init(&quiet);
    quiet.quiet = 1;
    for (int32_t pose = 1; strain && pose <= pattern->mesh->pose_count; ++pose) {
        pz_metrics *metrics = NULL;
        if (pz_metrics_compute(pattern, uv, pose, fabric, &metrics, &quiet) != PZ_OK) {
            free(strain);
            return NULL;
        }
        for (int32_t p = 0; p < pattern->panel_count && p < metrics->panel_count; ++p) {
            const pz_panel_metrics *panel = &metrics->panels[p];
            strain[p] = fmax(strain[p], fmax(fabs(panel->strain_warp.max), fabs(panel->strain_weft.max)));
        }
        pz_metrics_free(&metrics);
    }
    return strain;
}

static const int32_t *panel_mirror(void *user, const pz_pattern *pattern)
{
    run_state *state = user;
    const pz_segment_result *segment = state->segment;
    if (!segment || segment->panel_count != pattern->panel_count || !segment->symmetry.found)
        return NULL;
    free(state->panel_mirror);
    state->panel_mirror = malloc(((size_t)segment->panel_count + 1) * sizeof(int32_t));
    if (!state->panel_mirror)
        return NULL;  /* no pairs: every piece is then cut once, which is still right */
    for (int32_t p = 0; p < segment->panel_count; ++p)
        state->panel_mirror[p] = segment->panels[p].mirror_panel;
    return state->panel_mirror;
}

/* ---------------------------------------------------------------- layout curves */

/*
 * The layout as polylines of garment vertices, from the pattern itself so
 * that --panels and segmentation look the same: one polyline per seam (its
 * side a) and one per dart (tip, then leg a).
 */
static pz_status build_layout(run_state *state, const pz_pattern *pattern, pz_ctx *ctx)
{
    if (state->layout_offsets)
        return PZ_OK;
    int64_t total = 0;
    int32_t count = pattern->seam_count + pattern->dart_count;
    for (int32_t s = 0; s < pattern->seam_count; ++s)
        total += pattern->seams[s].pair_count;
    for (int32_t d = 0; d < pattern->dart_count; ++d)
        total += pattern->darts[d].pair_count + 1;
    state->layout_offsets = malloc(((size_t)count + 1) * sizeof(int32_t));
    state->layout_vertices = malloc(((size_t)total + 1) * sizeof(int32_t));
    state->layout_is_dart = calloc((size_t)count + 1, 1);
    if (!state->layout_offsets || !state->layout_vertices || !state->layout_is_dart)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    int32_t at = 0, curve = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s, ++curve) {
        state->layout_offsets[curve] = at;
        for (int32_t i = 0; i < pattern->seams[s].pair_count; ++i)
            state->layout_vertices[at++] = pattern->vertex_origin[pattern->seams[s].side_a[i]];
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d, ++curve) {
        const pz_dart *dart = &pattern->darts[d];
        state->layout_offsets[curve] = at;
        state->layout_is_dart[curve] = 1;
        state->layout_vertices[at++] = pattern->vertex_origin[dart->tip];
        for (int32_t i = 0; i < dart->pair_count; ++i)
            state->layout_vertices[at++] = pattern->vertex_origin[dart->leg_a[i]];
    }
    state->layout_offsets[count] = at;
    state->layout_count = count;
    return PZ_OK;
}

static void layout_curves(void *user, const pz_pattern *pattern, const int32_t **vertices, const int32_t **offsets,
                          int32_t *count)
{
    run_state *state = user;
    pz_ctx quiet;
    pz_ctx_init(&quiet);
    quiet.quiet = 1;
    if (build_layout(state, pattern, &quiet) != PZ_OK) {
        *count = 0;  /* out of memory: garment.glb then shows the cut mesh's own seams */
        return;
    }
    *vertices = state->layout_vertices;
    *offsets = state->layout_offsets;
    *count = state->layout_offsets ? state->layout_count : 0;
}

/* layout.obj: the garment's vertices used by the layout (in the input's units, like garment.obj), one
 * group and one polyline (`l`) per seam or dart. */
static pz_status write_layout(void *user, FILE *file, const pz_pattern *pattern, pz_ctx *ctx)
{
    run_state *state = user;
    pz_status status = build_layout(state, pattern, ctx);
    if (status != PZ_OK)
        return status;
    const pz_mesh *mesh = pattern->mesh;
    double scale = mesh->unit_scale > 0 ? mesh->unit_scale : 1.0;
    /* The cut mesh's vertex of each garment vertex (any copy has the garment's position). */
    int32_t garment_vertices = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (pattern->vertex_origin[v] + 1 > garment_vertices)
            garment_vertices = pattern->vertex_origin[v] + 1;
    int32_t *copy = malloc(((size_t)garment_vertices + 1) * sizeof(int32_t));
    if (!copy)
        return pz_error(ctx, PZ_ERR_NOMEM, "layout.obj: out of memory");
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        copy[pattern->vertex_origin[v]] = v;
    fprintf(file, "# panelize layout: %d seams, %d darts (polylines on the garment)\n", (int)pattern->seam_count,
            (int)pattern->dart_count);
    int32_t seam = 0, dart = 0;
    for (int32_t c = 0; c < state->layout_count; ++c) {
        int32_t first = state->layout_offsets[c], last = state->layout_offsets[c + 1];
        if (state->layout_is_dart[c])
            fprintf(file, "g dart_%d\n", (int)dart++);
        else
            fprintf(file, "g seam_%d_panels_%d_%d\n", (int)seam, (int)pattern->seams[seam].panel_a,
                    (int)pattern->seams[seam].panel_b), ++seam;
        for (int32_t i = first; i < last; ++i) {
            const double *p = mesh->positions + 3 * (size_t)copy[state->layout_vertices[i]];
            fprintf(file, "v %.9g %.9g %.9g\n", p[0] / scale, p[1] / scale, p[2] / scale);
        }
        fputs("l", file);
        for (int32_t i = first; i < last; ++i)
            fprintf(file, " %d", (int)(i + 1));
        fputc('\n', file);
    }
    free(copy);
    if (ferror(file))
        return pz_error(ctx, PZ_ERR_CREATE, "layout.obj: write error");
    return PZ_OK;
}

/* ---------------------------------------------------------------- goals and report */

/* The final goals of every panel: disk and corners from the layout, strain and injectivity from the
 * final flattening (the rest pose's metrics; pose_strain, when given, the worst |strain| of each panel
 * over the extra poses). Fills panels[p].goals and .corners. */
static pz_status judge_panels(const pz_mesh *garment, const pz_pattern *pattern, const pz_metrics *metrics,
                              const double *pose_strain, int32_t max_corners, double max_strain,
                              pz_segment_panel *panels, pz_ctx *ctx)
{
    int32_t panel_count = pattern->panel_count;
    const int32_t *cut_faces = pattern->mesh->faces;  /* the garment's faces, in order, on cut-mesh copies */
    pz_topology *topology = NULL;
    int32_t *face_ids = NULL, *face_offsets = NULL;
    uint8_t *edge_cut = NULL;
    pz_status status = pz_topology_build(garment, &topology, ctx);
    if (status == PZ_OK) {
        int bucketed = faces_by_panel(pattern, &face_offsets, &face_ids);
        edge_cut = calloc((size_t)topology->edge_count + 1, 1);
        if (!bucketed || !edge_cut)
            status = pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory judging the goals");
    }
    if (status == PZ_OK) {
        /* An edge is cut when its two faces use different copies of one of its ends. */
        for (int32_t e = 0; e < topology->edge_count; ++e) {
            int32_t h = topology->edge_halfedge[2 * e], t = topology->edge_halfedge[2 * e + 1];
            if (t >= 0)
                edge_cut[e] = cut_faces[h] != cut_faces[pz_he_next(t)] || cut_faces[pz_he_next(h)] != cut_faces[t];
        }
    }
    for (int32_t p = 0; p < panel_count && status == PZ_OK; ++p) {
        pz_goal_result goals;
        /* Only the disk test and the corners are taken from here: a huge strain bound keeps the
         * evaluation's own flattening from mattering; the final strain decides. */
        pz_goal_options shape_only = {max_corners, 1e9, {0, 0, 1}, 0};
        status = pz_segment_goals(garment, topology, edge_cut, face_ids + face_offsets[p],
                                  face_offsets[p + 1] - face_offsets[p], &shape_only, &goals, ctx);
        if (status != PZ_OK)
            break;
        const pz_panel_metrics *panel = &metrics->panels[p];
        double strain = fmax(fmax(fabs(panel->strain_warp.max), fabs(panel->strain_weft.max)), 0.0);
        if (pose_strain)
            strain = fmax(strain, pose_strain[p]);
        goals.failures &= PZ_GOAL_NOT_DISK | PZ_GOAL_CORNERS;
        goals.max_abs_strain = strain;
        goals.flipped_triangles = panel->flipped_triangles;
        if (strain > max_strain)
            goals.failures |= PZ_GOAL_STRAIN;
        if (panel->flipped_triangles > 0 || panel->boundary_self_intersections > 0)
            goals.failures |= PZ_GOAL_NOT_INJECTIVE;
        panels[p].goals = goals;
        panels[p].corners = goals.corners;
    }
    free(edge_cut);
    free(face_offsets);
    free(face_ids);
    pz_topology_free(&topology);
    return status;
}

/* Each panel's worst |warp| or |weft| strain over every pose, from report.json's panels (whose figures
 * are the worst over the poses measured); NULL without extra poses or when out of memory. */
static double *strain_over_poses(cJSON *root, const pz_mesh *garment, int32_t panel_count)
{
    if (garment->pose_count == 0)
        return NULL;
    double *strain = calloc((size_t)panel_count + 1, sizeof(double));
    cJSON *list = cJSON_GetObjectItem(root, "panels");
    int32_t p = 0;
    for (cJSON *item = list ? list->child : NULL; strain && item && p < panel_count; item = item->next, ++p) {
        static const char *const keys[] = {"strain_warp", "strain_weft"};
        for (int k = 0; k < 2; ++k) {
            cJSON *max = cJSON_GetObjectItem(cJSON_GetObjectItem(item, keys[k]), "max");
            if (cJSON_IsNumber(max))
                strain[p] = fmax(strain[p], fabs(max->valuedouble));
        }
    }
    return strain;
}

/* The report's verdict: judge_panels over every pose, then state->goals_met, the reasons (a summary, then
 * the failing panels) and one line on stderr when the goals are missed. */
static pz_status judge_goals(run_state *state, cJSON *root, const pz_mesh *garment, const pz_pattern *pattern,
                             const pz_metrics *metrics, pz_segment_panel *panels, pz_ctx *ctx)
{
    double *pose_strain = strain_over_poses(root, garment, pattern->panel_count);
    pz_status status = judge_panels(garment, pattern, metrics, pose_strain, state->max_corners, state->max_strain,
                                    panels, ctx);
    free(pose_strain);
    state->goals_met = 1;
    state->failing_panels = 0;
    state->worst_strain = 0;
    state->reasons[0] = '\0';
    if (status != PZ_OK)
        return status;
    int32_t over_strain = 0;
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        state->failing_panels += panels[p].goals.failures != 0;
        over_strain += (panels[p].goals.failures & PZ_GOAL_STRAIN) != 0;
        state->worst_strain = fmax(state->worst_strain, panels[p].goals.max_abs_strain);
    }
    if (state->failing_panels == 0)
        return PZ_OK;
    state->goals_met = 0;
    int written = snprintf(state->reasons, sizeof state->reasons,
                           "%d of %d panels miss the goals (%d exceed S = %g, worst strain %.3g): ",
                           (int)state->failing_panels, (int)pattern->panel_count, (int)over_strain,
                           state->max_strain, state->worst_strain);
    size_t used = written > 0 && (size_t)written < sizeof state->reasons ? (size_t)written : 0;
    pz_goal_options goal_options = {state->max_corners, state->max_strain, {0, 0, 1}, 0};
    for (int32_t p = 0, listed = 0; p < pattern->panel_count; ++p) {
        if (!panels[p].goals.failures)
            continue;
        char text[256];
        pz_goal_describe(&panels[p].goals, &goal_options, text, sizeof text);
        written = snprintf(state->reasons + used, sizeof state->reasons - used, "%spanel %d: %s",
                           listed++ ? "; " : "", (int)p, text);
        if (written < 0 || used + (size_t)written >= sizeof state->reasons) {
            /* Cut at a whole panel and say so, rather than mid-word. */
            state->reasons[used] = '\0';
            snprintf(state->reasons + used, sizeof state->reasons - used, "%s...", listed > 1 ? "; " : "");
            break;
        }
        used += (size_t)written;
    }
    pz_note(state->note_ctx, "run: goals %s: %d of %d panels miss them, %d exceed S = %g, worst strain %.3g%s",
            state->segment && !state->segment->goals_met ? "unreachable" : "not met", (int)state->failing_panels,
            (int)pattern->panel_count, (int)over_strain, state->max_strain, state->worst_strain,
            state->segment && !state->segment->goals_met ? " (the layout could not meet them; best effort written)"
                                                         : "");
    return PZ_OK;
}

/* ---------------------------------------------------------------- pattern symmetry */

/*
 * The pattern's own mirror symmetry (docs/segment.md, "Symmetry"): for each
 * mirrored pair of panels (and each panel that is its own mirror image), the
 * 2D reflection that best maps every vertex's pattern point onto its mirror
 * vertex's point in the partner panel (least squares: the points reflected,
 * then the best rotation and translation, Kabsch in 2D), and the distances
 * left. Layout residual 0 says the seams are placed symmetrically; this says
 * the flattened pieces are mirror images of each other.
 */
typedef struct mirror_fit {
    double sum_sq;       /* squared residuals summed over the points */
    double max;          /* the largest residual, mm */
    int64_t count;
} mirror_fit;

/* Fits one panel pair: points a[i] (panel p) -> b[i] (its mirror panel), n pairs. */
static void fit_reflection(const double *a, const double *b, int32_t n, mirror_fit *fit)
{
    if (n < 3)
        return;
    double ca[2] = {0, 0}, cb[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i) {
        ca[0] += a[2 * i], ca[1] += -a[2 * i + 1];  /* reflected about the u axis */
        cb[0] += b[2 * i], cb[1] += b[2 * i + 1];
    }
    for (int k = 0; k < 2; ++k)
        ca[k] /= n, cb[k] /= n;
    double h00 = 0, h01 = 0, h10 = 0, h11 = 0;
    for (int32_t i = 0; i < n; ++i) {
        double x = a[2 * i] - ca[0], y = -a[2 * i + 1] - ca[1];
        double u = b[2 * i] - cb[0], v = b[2 * i + 1] - cb[1];
        h00 += x * u, h01 += x * v, h10 += y * u, h11 += y * v;
    }
    double angle = atan2(h01 - h10, h00 + h11), c = cos(angle), s = sin(angle);
    for (int32_t i = 0; i < n; ++i) {
        double x = a[2 * i] - ca[0], y = -a[2 * i + 1] - ca[1];
        double du = c * x - s * y + cb[0] - b[2 * i], dv = s * x + c * y + cb[1] - b[2 * i + 1];
        double d2 = du * du + dv * dv;
        fit->sum_sq += d2;
        fit->max = fmax(fit->max, sqrt(d2));
        ++fit->count;
    }
}

/* The RMS and largest residual (mm) over every mirrored panel pair; -1 when there is no pair. */
static pz_status pattern_mirror_residual(const pz_pattern *pattern, const double *uv, const int32_t *vertex_mirror,
                                         int32_t garment_vertices, const int32_t *panel_mirror, double *rms,
                                         double *max, pz_ctx *ctx)
{
    *rms = *max = -1;
    const pz_mesh *cut = pattern->mesh;
    int32_t *vertex_panel = malloc(((size_t)cut->vertex_count + 1) * sizeof(int32_t));
    int32_t *copy_start = calloc((size_t)garment_vertices + 2, sizeof(int32_t));
    int32_t *copies = malloc(((size_t)cut->vertex_count + 1) * sizeof(int32_t));
    double *a = malloc(((size_t)cut->vertex_count + 1) * 2 * sizeof(double));
    double *b = malloc(((size_t)cut->vertex_count + 1) * 2 * sizeof(double));
    if (!vertex_panel || !copy_start || !copies || !a || !b) {
        free(vertex_panel), free(copy_start), free(copies), free(a), free(b);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory measuring the pattern's symmetry");
    }
    for (int32_t f = 0; f < cut->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            vertex_panel[cut->faces[3 * f + k]] = pattern->face_panel[f];
    /* The cut-mesh copies of each garment vertex (CSR), to find a vertex's mirror in a given panel. */
    for (int32_t v = 0; v < cut->vertex_count; ++v)
        ++copy_start[pattern->vertex_origin[v] + 2];
    for (int32_t g = 0; g < garment_vertices; ++g)
        copy_start[g + 2] += copy_start[g + 1];
    for (int32_t v = 0; v < cut->vertex_count; ++v)
        copies[copy_start[pattern->vertex_origin[v] + 1]++] = v;
    mirror_fit fit = {0, 0, 0};
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        int32_t m = panel_mirror[p];
        if (m < p)
            continue;  /* each pair once (m == p: a panel that is its own mirror image) */
        int32_t n = 0;
        for (int32_t v = 0; v < cut->vertex_count; ++v) {
            int32_t g = pattern->vertex_origin[v], mirror = vertex_panel[v] == p ? vertex_mirror[g] : -1;
            if (mirror < 0 || mirror >= garment_vertices)
                continue;
            for (int32_t i = copy_start[mirror]; i < copy_start[mirror + 1]; ++i)
                if (vertex_panel[copies[i]] == m) {
                    memcpy(a + 2 * n, uv + 2 * v, 2 * sizeof(double));
                    memcpy(b + 2 * n, uv + 2 * copies[i], 2 * sizeof(double));
                    ++n;
                    break;
                }
        }
        fit_reflection(a, b, n, &fit);
    }
    if (fit.count > 0) {
        *rms = sqrt(fit.sum_sq / (double)fit.count);
        *max = fit.max;
    }
    free(vertex_panel), free(copy_start), free(copies), free(a), free(b);
    return PZ_OK;
}

/* state->pattern_residual_*: the final pattern's mirror symmetry, measured on its points (uv). Left at -1
 * when it cannot be measured (no symmetry found, panels not the segmentation's). */
static void measure_pattern_symmetry(run_state *state, const pz_pattern *pattern, const double *uv)
{
    state->pattern_residual_rms_mm = state->pattern_residual_max_mm = -1;
    const pz_segment_result *segment = state->segment;
    if (!segment || !segment->symmetry.found || segment->panel_count != pattern->panel_count)
        return;
    pz_ctx quiet;
    pz_ctx_init(&quiet);
    quiet.quiet = 1;
    int32_t *mirror = malloc(((size_t)pattern->panel_count + 1) * sizeof(int32_t));
    for (int32_t p = 0; mirror && p < pattern->panel_count; ++p)
        mirror[p] = segment->panels[p].mirror_panel;
    if (mirror)
        pattern_mirror_residual(pattern, uv, segment->symmetry.vertex_mirror, segment->symmetry.vertex_count, mirror,
                                &state->pattern_residual_rms_mm, &state->pattern_residual_max_mm, &quiet);
    free(mirror);
}

static int add_number(cJSON *object, const char *name, double value)
{
    return cJSON_AddNumberToObject(object, name, value) != NULL;
}

static int extend_panels(run_state *state, cJSON *root, const pz_pattern *pattern, const pz_segment_panel *panels)
{
    cJSON *list = cJSON_GetObjectItem(root, "panels");
    int ok = 1;
    int32_t *darts = calloc((size_t)pattern->panel_count + 1, sizeof(int32_t));
    if (!darts)
        return 0;
    for (int32_t d = 0; d < pattern->dart_count; ++d)
        ++darts[pattern->darts[d].panel];
    int32_t p = 0;
    for (cJSON *item = list ? list->child : NULL; item && p < pattern->panel_count; item = item->next, ++p) {
        ok &= add_number(item, "corners", panels[p].corners);
        ok &= add_number(item, "darts", darts[p]);
        ok &= add_number(item, "mirror_panel", state->panel_mirror ? state->panel_mirror[p] : -1);
        char text[256];
        pz_goal_options options = {state->max_corners, state->max_strain, {0, 0, 1}, 0};
        pz_goal_describe(&panels[p].goals, &options, text, sizeof text);
        ok &= cJSON_AddBoolToObject(item, "goals_met", panels[p].goals.failures == 0) != NULL;
        if (panels[p].goals.failures)
            ok &= cJSON_AddStringToObject(item, "goals", text) != NULL;
    }
    free(darts);
    return ok;
}

static int extend_segmentation(const run_state *state, cJSON *root)
{
    cJSON *object = cJSON_AddObjectToObject(root, "segmentation");
    if (!object)
        return 0;
    const pz_segment_result *segment = state->segment;
    int ok = cJSON_AddStringToObject(object, "panels", segment ? "automatic" : "given") != NULL;
    ok &= add_number(object, "max_corners", state->max_corners);
    ok &= add_number(object, "max_strain", state->max_strain);
    ok &= cJSON_AddBoolToObject(object, "darts", state->darts) != NULL;
    ok &= add_number(object, "field_singularities", state->field_singularities);
    ok &= add_number(object, "verdict_rounds", state->goals.verdict_rounds);
    cJSON *truing = cJSON_AddObjectToObject(object, "truing");
    ok &= truing != NULL && cJSON_AddBoolToObject(truing, "on", state->truing) != NULL;
    if (truing && state->truing) {
        const pz_truing_result *t = &state->truing_result;
        ok &= add_number(truing, "moved_vertices", t->moved_vertices);
        ok &= add_number(truing, "relaxed_vertices", t->relaxed_vertices);
        ok &= add_number(truing, "max_move_mm", pz_cli_round(t->max_move_mm, 3));
        ok &= add_number(truing, "mean_turn_before_deg", pz_cli_round(t->mean_turn_before_deg, 2));
        ok &= add_number(truing, "mean_turn_after_deg", pz_cli_round(t->mean_turn_after_deg, 2));
    }
    ok &= add_number(object, "vetoed_panels", state->goals.vetoed_count);
    /* Monotone panel counts: the looser settings laid out first, their cuts kept (docs/segment.md). */
    cJSON *ladder = cJSON_AddObjectToObject(object, "looser_goals");
    ok &= ladder != NULL;
    if (ladder) {
        ok &= add_number(ladder, "settings", state->rung_count);
        ok &= add_number(ladder, "most_panels", state->seed_panels);
        ok &= cJSON_AddBoolToObject(ladder, "seeded", state->seeded) != NULL;
        cJSON *timings = cJSON_AddObjectToObject(ladder, "timings_ms");
        ok &= timings && add_number(timings, "total", pz_cli_round(state->ladder_ms, 3));
    }
    if (!segment)
        return ok;
    ok &= add_number(object, "candidates", segment->candidate_count);
    ok &= add_number(object, "inserted", segment->inserted_count);
    ok &= add_number(object, "removed", segment->removed_count);
    ok &= add_number(object, "evaluations", segment->evaluation_count);
    ok &= add_number(object, "dart_count", segment->dart_count);
    ok &= cJSON_AddBoolToObject(object, "layout_goals_met", segment->goals_met) != NULL;
    cJSON *symmetry = cJSON_AddObjectToObject(object, "symmetry");
    ok &= symmetry != NULL;
    if (symmetry) {
        const pz_symmetry *plane = &segment->symmetry;
        static const char *const axes[] = {"x", "y", "z"};
        ok &= cJSON_AddBoolToObject(symmetry, "found", plane->found) != NULL;
        ok &= cJSON_AddStringToObject(symmetry, "axis", plane->found && plane->axis >= 0 && plane->axis < 3
                                                             ? axes[plane->axis] : "none") != NULL;
        ok &= add_number(symmetry, "offset", plane->found ? plane->offset : 0);
        ok &= add_number(symmetry, "mesh_residual_mm", plane->found ? plane->residual_mm : 0);
        ok &= add_number(symmetry, "layout_residual_mm", plane->found ? segment->symmetry_residual_mm : 0);
        ok &= add_number(symmetry, "pattern_residual_mm", pz_cli_round(state->pattern_residual_rms_mm, 6));
        ok &= add_number(symmetry, "pattern_residual_max_mm", pz_cli_round(state->pattern_residual_max_mm, 6));
    }
    cJSON *timings = cJSON_AddObjectToObject(object, "timings_ms");
    ok &= timings != NULL;
    if (timings) {
        ok &= add_number(timings, "graph", segment->graph_ms);
        ok &= add_number(timings, "candidates", segment->candidates_ms);
        ok &= add_number(timings, "insert", segment->insert_ms);
        ok &= add_number(timings, "remove", segment->remove_ms);
        ok &= add_number(timings, "darts", segment->darts_ms);
        ok &= add_number(timings, "total", segment->total_ms);
    }
    return ok;
}

static int extend_prepare(const run_state *state, cJSON *root)
{
    cJSON *object = cJSON_AddObjectToObject(root, "prepare");
    if (!object)
        return 0;
    int ok = cJSON_AddStringToObject(object, "mode", state->prepare_auto ? "auto" : "off") != NULL;
    if (!state->prepared)
        return ok;
    const pz_prepare_report *report = &state->prepared->report;
    cJSON *steps = cJSON_AddArrayToObject(object, "steps");
    ok &= steps != NULL;
    for (int i = 0; steps && i < PZ_PREPARE_STEP_COUNT; ++i) {
        cJSON *step = cJSON_CreateObject();
        ok &= step && cJSON_AddItemToArray(steps, step);
        if (!step)
            break;
        ok &= cJSON_AddStringToObject(step, "name", report->steps[i].name ? report->steps[i].name : "") != NULL;
        ok &= cJSON_AddBoolToObject(step, "ran", report->steps[i].ran) != NULL;
        ok &= cJSON_AddStringToObject(step, "detail", report->steps[i].detail) != NULL;
    }
    ok &= add_number(object, "input_faces", report->input_faces);
    ok &= add_number(object, "output_faces", report->output_faces);
    ok &= add_number(object, "hausdorff_mm", report->hausdorff);
    ok &= add_number(object, "welded_seams", state->prepared->seam_count);
    return ok;
}

static int extend_report(void *user, cJSON *root, const pz_mesh *garment, const pz_pattern *pattern,
                         const double *uv, const pz_metrics *metrics)
{
    run_state *state = user;
    pz_ctx quiet_ctx;
    pz_ctx_init(&quiet_ctx);
    quiet_ctx.quiet = 1;
    pz_segment_panel *panels = calloc((size_t)pattern->panel_count + 1, sizeof *panels);
    int ok = panels && judge_goals(state, root, garment, pattern, metrics, panels, &quiet_ctx) == PZ_OK;
    if (ok)
        ok &= extend_panels(state, root, pattern, panels);
    free(panels);
    cJSON *summary = cJSON_GetObjectItem(root, "summary");
    if (ok && summary) {
        ok &= cJSON_AddBoolToObject(summary, "goals_met", state->goals_met) != NULL;
        if (!state->goals_met)
            ok &= cJSON_AddStringToObject(summary, "goals_reasons", state->reasons) != NULL;
    }
    cJSON *timings = cJSON_GetObjectItem(root, "timings_ms");
    if (ok && timings) {
        ok &= add_number(timings, "prepare", pz_cli_round(state->prepare_ms, 3));
        ok &= add_number(timings, "field", pz_cli_round(state->field_ms, 3));
        ok &= add_number(timings, "segment", pz_cli_round(state->segment_ms, 3));
    }
    measure_pattern_symmetry(state, pattern, uv);
    if (ok)
        ok &= extend_segmentation(state, root) && extend_prepare(state, root);
    return ok;
}

static void print_summary(void *user)
{
    const run_state *state = user;
    if (state->segment)
        printf("segmentation:       %d panels, %d darts, symmetry %s\n", (int)state->segment->panel_count,
               (int)state->segment->dart_count, state->segment->symmetry.found ? "yes" : "no");
    printf("goals met:          %s%s%s\n", state->goals_met ? "yes" : "no", state->goals_met ? "" : ": ",
           state->goals_met ? "" : state->reasons);
}

/* ---------------------------------------------------------------- the command */

static void run_state_clear(run_state *state)
{
    pz_prepare_result_free(&state->prepared);
    pz_segment_result_free(&state->segment);
    free(state->panel_mirror);
    free(state->layout_vertices);
    free(state->layout_offsets);
    free(state->layout_is_dart);
    goal_setting_clear(&state->goals);
    for (int32_t i = 0; i < state->rung_count; ++i)
        free(state->rungs[i].cuts);
    free(state->rungs);
    pz_field_free(&state->field);
    free(state->original_positions);
    free(state->original_poses);
    memset(state, 0, sizeof *state);
}

pz_status pz_cli_run(const pz_cli_args *args, pz_ctx *ctx)
{
    run_state state;
    memset(&state, 0, sizeof state);
    state.args = args;
    state.note_ctx = ctx;
    pz_status status = parse_run_options(args, &state, ctx);
    if (status == PZ_OK && args->positional_count > 1)
        status = pz_error(ctx, PZ_ERR_USAGE, "run: expected one GARMENT, got %d files", args->positional_count);
    if (status != PZ_OK)
        return status;
    static const pz_flatten_extra_file extra_files[] = {{"layout.obj", write_layout}};
    pz_flatten_extension extension = {0};
    extension.user = &state;
    extension.prepare_mesh = prepare_mesh;
    extension.choose_panels = choose_panels;
    extension.panels_source = "segmentation";
    extension.strain_limit = state.max_strain;
    extension.accept_pattern = accept_pattern;
    extension.panel_mirror = panel_mirror;
    extension.layout_curves = layout_curves;
    extension.extend_report = extend_report;
    extension.print_summary = print_summary;
    extension.extra_file_count = 1;
    extension.extra_files = extra_files;
    status = pz_flatten_execute(args, &extension, ctx);
    run_state_clear(&state);
    return status;
}
