/*
 * studio/result_json.c -- a finished run as the page's JSON (docs/studio.md,
 * "The result"): the garment with a panel per face, the seams and darts in
 * 3D and on both sides of the pattern, the flattened pattern's triangles with
 * their strain, the pieces with their outlines and verdicts, the verdict.
 *
 * The large arrays are printed straight into a memory stream with the
 * decimals they need (positions to 1 micrometre, strain to 1e-5): a 7K-face
 * result is ~0.4 MB and takes a few milliseconds; the small objects go
 * through cJSON.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "studio/internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double studio_round(double value, int decimals)
{
    double scale = pow(10.0, decimals);
    return isfinite(value) ? round(value * scale) / scale : 0.0;
}

/* A number with at most `decimals` decimals, trailing zeros dropped ("12.5", "3", "-0.001"). */
static void put_number(FILE *out, double value, int decimals)
{
    char text[64];
    if (!isfinite(value))
        value = 0;
    int length = snprintf(text, sizeof text, "%.*f", decimals, value);
    if (length <= 0 || (size_t)length >= sizeof text) {
        fputs("0", out);
        return;
    }
    if (strchr(text, '.')) {
        while (length > 0 && text[length - 1] == '0')
            text[--length] = '\0';
        if (length > 0 && text[length - 1] == '.')
            text[--length] = '\0';
    }
    if (strcmp(text, "-0") == 0)
        strcpy(text, "0");
    fputs(text, out);
}

static void put_numbers(FILE *out, const char *key, const double *values, size_t count, int decimals)
{
    fprintf(out, "\"%s\":[", key);
    for (size_t i = 0; i < count; ++i) {
        if (i)
            fputc(',', out);
        put_number(out, values[i], decimals);
    }
    fputc(']', out);
}

static void put_ints(FILE *out, const char *key, const int32_t *values, size_t count)
{
    fprintf(out, "\"%s\":[", key);
    for (size_t i = 0; i < count; ++i)
        fprintf(out, i ? ",%d" : "%d", (int)values[i]);
    fputc(']', out);
}

/* A cJSON tree printed unformatted after "key": and deleted; "null" when it could not be made. */
static void put_cjson(FILE *out, const char *key, cJSON *tree)
{
    char *text = tree ? cJSON_PrintUnformatted(tree) : NULL;
    fprintf(out, "\"%s\":%s", key, text ? text : "null");
    free(text);
    cJSON_Delete(tree);
}

static void put_mesh(FILE *out, const pz_mesh *mesh)
{
    fputc('{', out);
    put_numbers(out, "positions", mesh->positions, (size_t)mesh->vertex_count * 3, 3);
    fputc(',', out);
    put_ints(out, "faces", mesh->faces, (size_t)mesh->face_count * 3);
    fputc('}', out);
}

/* "key": the pattern points of a polyline of cut-mesh vertices. */
static void put_uv(FILE *out, const pz_result *result, const int32_t *cut_vertices, int32_t count, const char *key)
{
    fprintf(out, "\"%s\":[", key);
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 2; ++k) {
            if (i || k)
                fputc(',', out);
            put_number(out, result->uv[2 * (size_t)cut_vertices[i] + k], 3);
        }
    fputc(']', out);
}

/* A polyline of cut-mesh vertices: its 3D points on the garment ("points") and its pattern points. */
static void put_polyline(FILE *out, const pz_result *result, const int32_t *cut_vertices, int32_t count,
                         const char *uv_key)
{
    const pz_pattern *pattern = result->pattern;
    const double *positions = result->garment->positions;
    fputs("\"points\":[", out);
    for (int32_t i = 0; i < count; ++i) {
        const double *p = positions + 3 * (size_t)pattern->vertex_origin[cut_vertices[i]];
        for (int k = 0; k < 3; ++k) {
            if (i || k)
                fputc(',', out);
            put_number(out, p[k], 3);
        }
    }
    fputs("],", out);
    put_uv(out, result, cut_vertices, count, uv_key);
}

/* Every seam and dart: {"kind": "seam"|"dart", "panels": [a, b], "points": 3D, "uv_a", "uv_b"}. */
static void put_seams(FILE *out, const pz_result *result)
{
    const pz_pattern *pattern = result->pattern;
    fputs("\"seams\":[", out);
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        fprintf(out, "%s{\"kind\":\"seam\",\"panels\":[%d,%d],", s ? "," : "", (int)seam->panel_a,
                (int)seam->panel_b);
        put_polyline(out, result, seam->side_a, seam->pair_count, "uv_a");
        fputc(',', out);
        put_uv(out, result, seam->side_b, seam->pair_count, "uv_b");
        fputc('}', out);
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        fprintf(out, "%s{\"kind\":\"dart\",\"panels\":[%d,%d],", pattern->seam_count + d ? "," : "",
                (int)dart->panel, (int)dart->panel);
        put_polyline(out, result, dart->leg_a, dart->pair_count, "uv_a");
        fputc(',', out);
        put_uv(out, result, dart->leg_b, dart->pair_count, "uv_b");
        fputc('}', out);
    }
    fputc(']', out);
}

/* The flattened triangles with each one's worst warp or weft strain (rest pose). */
static void put_pattern(FILE *out, const pz_result *result)
{
    const pz_mesh *cut = result->pattern->mesh;
    fputs("\"pattern\":{", out);
    put_numbers(out, "uv", result->uv, (size_t)cut->vertex_count * 2, 3);
    fputc(',', out);
    put_ints(out, "faces", cut->faces, (size_t)cut->face_count * 3);
    fputs(",\"strain\":[", out);
    const pz_metrics *metrics = result->metrics_count > 0 ? result->metrics[0] : NULL;
    for (int32_t f = 0; f < cut->face_count; ++f) {
        double strain = 0;
        if (metrics && f < metrics->face_count)
            strain = fmax(fabs(metrics->strain_warp[f]), fabs(metrics->strain_weft[f]));
        if (f)
            fputc(',', out);
        put_number(out, strain, 5);
    }
    fputs("]}", out);
}

/* One piece per panel: name, outline (its sew line in the pattern), size, strain and verdict. */
static cJSON *pieces_json(const pz_result *result)
{
    cJSON *pieces = cJSON_CreateArray();
    const pz_pieces *made = result->pieces;
    for (int32_t p = 0; pieces && made && p < made->piece_count; ++p) {
        const pz_piece *piece = &made->pieces[p];
        cJSON *item = cJSON_CreateObject();
        if (!item || !cJSON_AddItemToArray(pieces, item))
            break;
        cJSON_AddNumberToObject(item, "panel", piece->panel);
        cJSON_AddStringToObject(item, "name", piece->name);
        cJSON_AddBoolToObject(item, "mirrored", piece->mirrored);
        cJSON_AddNumberToObject(item, "width_mm", studio_round(piece->bbox_max[0] - piece->bbox_min[0], 1));
        cJSON_AddNumberToObject(item, "height_mm", studio_round(piece->bbox_max[1] - piece->bbox_min[1], 1));
        cJSON_AddNumberToObject(item, "area_mm2", studio_round(piece->sew_area_mm2, 0));
        cJSON *outline = cJSON_AddArrayToObject(item, "outline");
        for (int32_t i = 0; outline && i < piece->sew_count; ++i) {
            const double *uv = result->uv + 2 * (size_t)piece->sew_vertex[i];
            cJSON_AddItemToArray(outline, cJSON_CreateNumber(studio_round(uv[0], 2)));
            cJSON_AddItemToArray(outline, cJSON_CreateNumber(studio_round(uv[1], 2)));
        }
        if (result->verdict.panels && piece->panel >= 0 && piece->panel < result->pattern->panel_count) {
            const pz_goal_result *goal = &result->verdict.panels[piece->panel];
            char problems[512];
            pz_goal_describe(goal, &result->options.goals, problems, sizeof problems);
            cJSON_AddNumberToObject(item, "strain", studio_round(goal->max_abs_strain, 5));
            cJSON_AddNumberToObject(item, "corners", goal->corners);
            cJSON_AddBoolToObject(item, "goals_met", goal->failures == 0);
            cJSON_AddStringToObject(item, "problems", problems);
        }
        if (result->panel_grain_turn && piece->panel >= 0 && piece->panel < result->pattern->panel_count)
            cJSON_AddNumberToObject(item, "grain_turn_deg",
                                    studio_round(result->panel_grain_turn[piece->panel] * 57.29577951308232, 1));
    }
    return pieces;
}

static cJSON *verdict_json(const pz_result *result)
{
    const pz_verdict *verdict = &result->verdict;
    cJSON *item = cJSON_CreateObject();
    if (!item)
        return NULL;
    cJSON_AddBoolToObject(item, "goals_met", verdict->goals_met);
    cJSON_AddBoolToObject(item, "reachable", verdict->reachable);
    cJSON_AddNumberToObject(item, "failing_panels", verdict->failing_panels);
    cJSON_AddNumberToObject(item, "worst_strain", studio_round(verdict->worst_strain, 5));
    cJSON_AddNumberToObject(item, "worst_seam_mismatch", studio_round(verdict->worst_seam_mismatch, 5));
    cJSON_AddNumberToObject(item, "area_over_strain", studio_round(verdict->area_over_strain, 5));
    cJSON_AddStringToObject(item, "reasons", verdict->reasons);
    cJSON_AddNumberToObject(item, "max_strain", result->options.goals.max_strain);
    cJSON_AddNumberToObject(item, "max_corners", result->options.goals.max_corners);
    cJSON_AddNumberToObject(item, "looser_written_strain", result->looser_written_strain);
    cJSON_AddBoolToObject(item, "symmetry_used", result->symmetry_used);
    return item;
}

char *studio_result_json(const pz_result *result, int run_id, double run_ms, size_t *length)
{
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    if (!out)
        return NULL;
    fprintf(out, "{\"run\":%d,\"ms\":%.0f,\"panel_count\":%d,\"garment\":", run_id, run_ms,
            (int)result->pattern->panel_count);
    put_mesh(out, result->garment);
    fputc(',', out);
    put_ints(out, "face_panel", result->pattern->face_panel, (size_t)result->pattern->mesh->face_count);
    fputc(',', out);
    put_seams(out, result);
    fputc(',', out);
    put_pattern(out, result);
    fputc(',', out);
    put_cjson(out, "pieces", pieces_json(result));
    fputc(',', out);
    put_cjson(out, "verdict", verdict_json(result));
    fputc('}', out);
    int failed = ferror(out);
    if (fclose(out) != 0 || failed) {
        free(text);
        return NULL;
    }
    if (length)
        *length = size;
    return text;
}

char *studio_mesh_json(const pz_mesh *mesh)
{
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    if (!out)
        return NULL;
    put_mesh(out, mesh);
    int failed = ferror(out);
    if (fclose(out) != 0 || failed) {
        free(text);
        return NULL;
    }
    return text;
}
