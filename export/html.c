/*
 * export/html.c -- report.html: one self-contained page (no scripts, no
 * external files, no network) that a person opens to judge a pattern.
 *
 *  - The pieces as inline SVG, laid out like pattern.svg
 *    (pz_pieces_sheet_layout; here the second piece of a mirrored pair is
 *    drawn too, since its strain is its own), every triangle of the cut mesh
 *    filled by its strain: the larger in magnitude of warp and weft strain
 *    (pz_metrics strain_warp / strain_weft), on a diverging scale
 *    (compression blue, 0 white, tension red) symmetric about 0 and spanning
 *    the largest magnitude (at least 1 %), with a legend. Triangles are
 *    grouped into 33 colour bins, one <path> per bin, to keep the file small
 *    (a 50K-face pattern is about 2 MB). Sew lines dashed, cut lines solid,
 *    notches, dart lines, grainlines and names: the pattern itself.
 *  - Tables from report.json's content (inputs->report): summary and marker
 *    as key / value, panels[], seams[] and darts[] one row each, nested
 *    objects flattened one level ("strain_warp max"), timings_ms.
 * The markup is also well-formed XML (every element closed, text escaped),
 * which the test checks with an XML parser.
 * Errors: PZ_ERR_CREATE when the stream fails, PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "export/stream_status.h"
#include "core/util.h"
#include "export/xml_text.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { kColourBins = 33 };

/* ------------------------------------------------------------------ tables */

static void put_value(FILE *file, const cJSON *value)
{
    if (cJSON_IsNumber(value)) {
        pz_put_plain_number(file, value->valuedouble);
    } else if (cJSON_IsString(value)) {
        pz_xml_put_text(file, value->valuestring);
    } else if (cJSON_IsBool(value)) {
        fputs(cJSON_IsTrue(value) ? "yes" : "no", file);
    } else if (cJSON_IsArray(value)) {
        const cJSON *item;
        int first = 1;
        cJSON_ArrayForEach(item, value)
        {
            if (!first)
                fputs(", ", file);
            if (cJSON_IsObject(item) || cJSON_IsArray(item))
                fputs("...", file);
            else
                put_value(file, item);
            first = 0;
        }
    } else if (cJSON_IsNull(value)) {
        fputs("-", file);
    } else {
        fputs("...", file);
    }
}

/* Heading cells of one row object: keys, and "key sub" for nested objects. */
static void put_header_cells(FILE *file, const cJSON *row)
{
    const cJSON *item;
    cJSON_ArrayForEach(item, row)
    {
        if (cJSON_IsObject(item)) {
            const cJSON *sub;
            cJSON_ArrayForEach(sub, item)
            {
                fputs("<th>", file);
                pz_xml_put_text(file, item->string);
                fputc(' ', file);
                pz_xml_put_text(file, sub->string);
                fputs("</th>", file);
            }
        } else {
            fputs("<th>", file);
            pz_xml_put_text(file, item->string);
            fputs("</th>", file);
        }
    }
}

/* The cells of `row` under the columns of `header` (missing values: "-"). */
static void put_row_cells(FILE *file, const cJSON *header, const cJSON *row)
{
    const cJSON *column;
    cJSON_ArrayForEach(column, header)
    {
        const cJSON *value = cJSON_GetObjectItemCaseSensitive(row, column->string);
        if (cJSON_IsObject(column)) {
            const cJSON *sub;
            cJSON_ArrayForEach(sub, column)
            {
                fputs("<td>", file);
                put_value(file, cJSON_IsObject(value) ? cJSON_GetObjectItemCaseSensitive(value, sub->string) : NULL);
                fputs("</td>", file);
            }
        } else {
            fputs("<td>", file);
            put_value(file, value);
            fputs("</td>", file);
        }
    }
}

/* An array of objects as a table (the first object's keys are the columns). */
static void put_array_table(FILE *file, const cJSON *array, const char *title, const char *id)
{
    if (!cJSON_IsArray(array) || cJSON_GetArraySize(array) == 0 || !cJSON_IsObject(cJSON_GetArrayItem(array, 0)))
        return;
    const cJSON *header = cJSON_GetArrayItem(array, 0);
    fprintf(file, "<h2>%s</h2>\n<table id=\"%s\"><thead><tr>", title, id);
    put_header_cells(file, header);
    fputs("</tr></thead><tbody>\n", file);
    const cJSON *row;
    cJSON_ArrayForEach(row, array)
    {
        fputs("<tr>", file);
        put_row_cells(file, header, row);
        fputs("</tr>\n", file);
    }
    fputs("</tbody></table>\n", file);
}

/* An object as key / value rows (nested objects and arrays shown inline). */
static void put_object_table(FILE *file, const cJSON *object, const char *title, const char *id)
{
    if (!cJSON_IsObject(object))
        return;
    fprintf(file, "<h2>%s</h2>\n<table id=\"%s\" class=\"pairs\"><tbody>\n", title, id);
    const cJSON *item;
    cJSON_ArrayForEach(item, object)
    {
        fputs("<tr><th>", file);
        pz_xml_put_text(file, item->string);
        fputs("</th><td>", file);
        if (cJSON_IsObject(item)) {
            const cJSON *sub;
            int first = 1;
            cJSON_ArrayForEach(sub, item)
            {
                fprintf(file, "%s", first ? "" : "; ");
                pz_xml_put_text(file, sub->string);
                fputs(" ", file);
                put_value(file, sub);
                first = 0;
            }
        } else {
            put_value(file, item);
        }
        fputs("</td></tr>\n", file);
    }
    fputs("</tbody></table>\n", file);
}

/* ------------------------------------------------------------------ strain map */

/* Diverging colour of bin b (0 .. kColourBins-1, middle = 0 strain): blue - white - red (ColorBrewer RdBu ends). */
static void bin_colour(int bin, char out[8])
{
    static const double blue[3] = {33, 102, 172}, red[3] = {178, 24, 43};
    double t = (bin - (kColourBins - 1) / 2.0) / ((kColourBins - 1) / 2.0); /* -1 .. 1 */
    const double *end = t < 0 ? blue : red;
    int rgb[3];
    for (int k = 0; k < 3; ++k)
        rgb[k] = (int)lround(255.0 + fabs(t) * (end[k] - 255.0));
    snprintf(out, 8, "#%02x%02x%02x", rgb[0] & 0xff, rgb[1] & 0xff, rgb[2] & 0xff);
}

/* The strain shown for face f: warp or weft, whichever is larger in magnitude. */
static double face_strain(const pz_metrics *metrics, int32_t f)
{
    double warp = metrics->strain_warp[f], weft = metrics->strain_weft[f];
    return fabs(warp) >= fabs(weft) ? warp : weft;
}

typedef struct strain_map {
    const pz_metrics *metrics; /* per-face strain of the cut mesh, or NULL */
    double scale;              /* colour scale half-range */
    double *offsets;           /* per panel: 2 (sheet offset of its piece), NAN when the panel has no piece */
    double size[2];            /* sheet size */
    int32_t *piece_of_panel;   /* panel -> piece, -1 */
} strain_map;

static void strain_map_clear(strain_map *map)
{
    free(map->offsets);
    free(map->piece_of_panel);
}

static pz_status strain_map_build(const pz_export_inputs *inputs, strain_map *map, pz_ctx *ctx)
{
    const pz_pieces *pieces = inputs->pieces;
    const pz_pattern *pattern = inputs->pattern;
    memset(map, 0, sizeof *map);
    pz_pieces all = *pieces;
    all.pieces = malloc(((size_t)pieces->piece_count + 1) * sizeof(pz_piece));
    double *piece_offsets = malloc(((size_t)pieces->piece_count + 1) * 2 * sizeof(double));
    map->offsets = malloc(((size_t)pattern->panel_count + 1) * 2 * sizeof(double));
    map->piece_of_panel = malloc(((size_t)pattern->panel_count + 1) * sizeof(int32_t));
    if (!all.pieces || !piece_offsets || !map->offsets || !map->piece_of_panel) {
        free(all.pieces);
        free(piece_offsets);
        strain_map_clear(map);
        return pz_error(ctx, PZ_ERR_NOMEM, "report.html: out of memory");
    }
    /* Every piece gets a place, the mirrored ones included (shallow copies: nothing is freed twice). */
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        all.pieces[p] = pieces->pieces[p];
        all.pieces[p].mirrored = 0;
    }
    pz_pieces_sheet_layout(&all, 20.0, 0.0, piece_offsets, map->size);
    for (int32_t k = 0; k < pattern->panel_count; ++k) {
        map->piece_of_panel[k] = -1;
        map->offsets[2 * k] = map->offsets[2 * k + 1] = NAN;
    }
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        int32_t panel = pieces->pieces[p].panel;
        if (panel >= 0 && panel < pattern->panel_count) {
            map->piece_of_panel[panel] = p;
            map->offsets[2 * panel] = piece_offsets[2 * p];
            map->offsets[2 * panel + 1] = piece_offsets[2 * p + 1];
        }
    }
    free(piece_offsets);
    free(all.pieces);
    /* Metrics of another mesh (face counts differ) are not shown: outlines only. */
    map->metrics = inputs->metrics && inputs->metrics->face_count == pattern->mesh->face_count ? inputs->metrics : NULL;
    map->scale = 0.01;
    for (int32_t f = 0; map->metrics && f < map->metrics->face_count; ++f)
        if (isfinite(face_strain(map->metrics, f)))
            map->scale = fmax(map->scale, fabs(face_strain(map->metrics, f)));
    return PZ_OK;
}

static int strain_bin(double strain, double scale)
{
    if (!isfinite(strain))
        return (kColourBins - 1) / 2;
    int bin = (int)lround((strain / scale + 1.0) / 2.0 * (kColourBins - 1));
    return bin < 0 ? 0 : bin >= kColourBins ? kColourBins - 1 : bin;
}

/* A point of the sheet in SVG coordinates (y down). */
static void put_point(FILE *file, const char *command, double x, double y, const strain_map *map)
{
    fprintf(file, "%s%.1f %.1f", command, x, map->size[1] - y);
}

static void put_outline(FILE *file, const double *points, int32_t count, const double offset[2],
                        const strain_map *map, const char *style)
{
    fprintf(file, "<path %s d=\"", style);
    for (int32_t i = 0; i < count; ++i)
        put_point(file, i ? "L" : "M", points[2 * i] + offset[0], points[2 * i + 1] + offset[1], map);
    fputs("Z\"/>\n", file);
}

/* Notches (cut inward from the cut line), dart lines and the grainline with its head, in one path. */
static void put_marks(FILE *file, const pz_piece *piece, const double offset[2], const strain_map *map)
{
    fputs("<path fill=\"none\" stroke=\"#000\" stroke-width=\"0.8\" d=\"", file);
    for (int32_t n = 0; n < piece->notch_count; ++n) {
        const pz_notch *notch = &piece->notches[n];
        double x = notch->cut_point[0] + offset[0], y = notch->cut_point[1] + offset[1];
        put_point(file, "M", x, y, map);
        put_point(file, "L", x - notch->depth_mm * notch->direction[0], y - notch->depth_mm * notch->direction[1],
                  map);
    }
    for (int32_t l = 0; l < piece->line_count; ++l)
        for (int32_t i = 0; i < piece->lines[l].point_count; ++i)
            put_point(file, i ? "L" : "M", piece->lines[l].points[2 * i] + offset[0],
                      piece->lines[l].points[2 * i + 1] + offset[1], map);
    double tail[2] = {piece->grain[0][0] + offset[0], piece->grain[0][1] + offset[1]};
    double head[2] = {piece->grain[1][0] + offset[0], piece->grain[1][1] + offset[1]};
    double dx = head[0] - tail[0], dy = head[1] - tail[1], length = hypot(dx, dy);
    put_point(file, "M", tail[0], tail[1], map);
    put_point(file, "L", head[0], head[1], map);
    if (length > 0) {
        dx *= 12 / length, dy *= 12 / length;
        put_point(file, "M", head[0] - dx + 0.4 * dy, head[1] - dy - 0.4 * dx, map);
        put_point(file, "L", head[0], head[1], map);
        put_point(file, "L", head[0] - dx - 0.4 * dy, head[1] - dy + 0.4 * dx, map);
    }
    fputs("\"/>\n", file);
}

static void put_strain_svg(FILE *file, const pz_export_inputs *inputs, const strain_map *map)
{
    const pz_pattern *pattern = inputs->pattern;
    const pz_mesh *mesh = pattern->mesh;
    const double legend = 40.0;
    fprintf(file, "<svg id=\"strain\" width=\"100%%\" viewBox=\"0 0 %.1f %.1f\" "
                  "style=\"max-height:80vh\">\n",
            map->size[0], map->size[1] + legend);
    /* One path per colour bin: the triangles of that strain. */
    for (int bin = 0; bin < kColourBins && map->metrics; ++bin) {
        char colour[8];
        bin_colour(bin, colour);
        int opened = 0;
        for (int32_t f = 0; f < mesh->face_count; ++f) {
            int32_t panel = pattern->face_panel[f];
            if (!isfinite(map->offsets[2 * panel]) || strain_bin(face_strain(map->metrics, f), map->scale) != bin)
                continue;
            if (!opened)
                fprintf(file, "<path fill=\"%s\" stroke=\"%s\" stroke-width=\"0.2\" d=\"", colour, colour);
            opened = 1;
            for (int k = 0; k < 3; ++k) {
                const double *uv = &inputs->uv[2 * mesh->faces[3 * f + k]];
                put_point(file, k ? "L" : "M", uv[0] + map->offsets[2 * panel], uv[1] + map->offsets[2 * panel + 1],
                          map);
            }
            fputc('Z', file);
        }
        if (opened)
            fputs("\"/>\n", file);
    }
    for (int32_t k = 0; k < pattern->panel_count; ++k) {
        int32_t p = map->piece_of_panel[k];
        if (p < 0)
            continue;
        const pz_piece *piece = &inputs->pieces->pieces[p];
        const double *offset = &map->offsets[2 * k];
        put_outline(file, piece->cut, piece->cut_count, offset, map, "fill=\"none\" stroke=\"#000\" stroke-width=\"1\"");
        put_outline(file, piece->sew, piece->sew_count, offset, map,
                    "fill=\"none\" stroke=\"#333\" stroke-width=\"0.6\" stroke-dasharray=\"4 3\"");
        put_marks(file, piece, offset, map);
        fprintf(file, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"14\">", piece->bbox_min[0] + offset[0] + 4,
                map->size[1] - (piece->bbox_max[1] + offset[1]) + 16);
        pz_xml_put_text(file, piece->name);
        fputs("</text>\n", file);
    }
    /* The legend: the bins left to right, with the scale's ends and zero. */
    double width = fmin(400.0, map->size[0]), cell = width / kColourBins, top = map->size[1] + 8;
    for (int bin = 0; bin < kColourBins; ++bin) {
        char colour[8];
        bin_colour(bin, colour);
        fprintf(file, "<rect x=\"%.2f\" y=\"%.1f\" width=\"%.2f\" height=\"12\" fill=\"%s\"/>\n", bin * cell, top,
                cell + 0.3, colour);
    }
    fprintf(file,
            "<text x=\"0\" y=\"%.1f\" font-size=\"12\">%.1f %% (compression)</text>"
            "<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\" text-anchor=\"middle\">0</text>"
            "<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\" text-anchor=\"end\">+%.1f %% (tension)</text>\n",
            top + 26, -100 * map->scale, width / 2, top + 26, width, top + 26, 100 * map->scale);
    fputs("</svg>\n", file);
}

/* ------------------------------------------------------------------ the page */

static const char *const kStyle =
    "body{font-family:sans-serif;margin:1.5em;color:#222}"
    "table{border-collapse:collapse;margin:0.5em 0 1.5em;font-size:0.85em}"
    "th,td{border:1px solid #ccc;padding:2px 6px;text-align:right}"
    "th{background:#f0f0f0}table.pairs th{text-align:left}"
    "h1{font-size:1.4em}h2{font-size:1.1em;margin-top:1.2em}";

pz_status pz_export_write_report_html(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    strain_map map;
    pz_status status = strain_map_build(inputs, &map, ctx);
    if (status != PZ_OK)
        return status;
    const pz_pieces *pieces = inputs->pieces;
    const cJSON *report = inputs->report;
    fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n<title>", file);
    pz_xml_put_text(file, pieces->garment_name);
    fprintf(file, " - panelize report</title>\n<style>%s</style>\n</head>\n<body>\n<h1>", kStyle);
    pz_xml_put_text(file, pieces->garment_name);
    fputs(" (size ", file);
    pz_xml_put_text(file, pieces->size_name);
    fprintf(file, "): %d pieces</h1>\n", (int)pieces->piece_count);
    if (inputs->marker)
        fprintf(file,
                "<p>Marker: %.1f mm of fabric %.0f mm wide, efficiency %.1f %% (no nesting of these pieces on this "
                "width passes %.1f %%: none is shorter than %.1f mm).</p>\n",
                inputs->marker->length_mm, inputs->marker->fabric_width_mm, 100 * inputs->marker->efficiency,
                100 * inputs->marker->efficiency_bound, inputs->marker->shortest_possible_mm);
    fputs("<h2>Strain on the pieces</h2>\n<p>Per triangle, the larger of warp and weft strain (pattern to "
          "garment stretch minus 1); dashed: sew line, solid: cut line.</p>\n",
          file);
    put_strain_svg(file, inputs, &map);
    strain_map_clear(&map);
    put_object_table(file, cJSON_GetObjectItemCaseSensitive(report, "summary"), "Summary", "summary");
    put_object_table(file, cJSON_GetObjectItemCaseSensitive(report, "marker"), "Marker", "marker");
    put_array_table(file, cJSON_GetObjectItemCaseSensitive(report, "tradeoff"),
                    "Trade-off: the pieces each strain goal needs", "tradeoff");
    put_object_table(file, cJSON_GetObjectItemCaseSensitive(report, "strain_outlook"), "Can S be met?", "outlook");
    put_array_table(file, cJSON_GetObjectItemCaseSensitive(report, "panels"), "Panels", "panels");
    put_array_table(file, cJSON_GetObjectItemCaseSensitive(report, "seams"), "Seams", "seams");
    put_array_table(file, cJSON_GetObjectItemCaseSensitive(report, "darts"), "Darts", "darts");
    put_object_table(file, cJSON_GetObjectItemCaseSensitive(report, "timings_ms"), "Timings (ms)", "timings");
    fputs("<p>Written by panelize " PZ_VERSION_STRING ".</p>\n</body>\n</html>\n", file);
    return pz_export_stream_status(file, 0, name, ctx);
}
