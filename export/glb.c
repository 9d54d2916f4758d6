/*
 * export/glb.c -- garment.glb: the 3D garment (rest pose) with one colour per
 * panel (COLOR_0), the pattern as TEXCOORD_0 and the seams as lines, so any
 * glTF viewer shows the pieces on the body.
 *
 *  - Vertices are the cut mesh's (pattern->mesh): a garment vertex on a seam
 *    is written once per panel, because its pattern coordinates differ.
 *    Positions are the cut mesh's, i.e. the garment's, written in metres
 *    (glTF's unit; the shim scales the millimetres).
 *  - Colours: panels that share a seam never share a colour: a greedy
 *    colouring of the panel adjacency (panels by decreasing neighbour count,
 *    then by index; each takes the first palette colour none of its coloured
 *    neighbours has), deterministic; 12 palette colours, more generated
 *    (export/glb_shim.cpp) if a panel ever needs them.
 *  - TEXCOORD_0: each vertex's uv goes through its piece's marker placement
 *    (copy 0) and is divided by the fabric width (u) and the marker length
 *    (v), so the texture space is the marker: a render of marker.svg's fabric
 *    rectangle laid over [0, 1]^2 puts every piece where it is cut. The
 *    second piece of a mirrored pair has no placement of its own: it takes
 *    its partner's mirrored copy, aligned by the centroids of the cut lines
 *    (the pieces are mirror images within 1 mm RMS, pz_pieces_build) and
 *    turned by the copy's rotation. Pieces the marker left out (wider than
 *    the fabric), and the hidden partners of such pieces, get a layout of
 *    their own after the marker's end: rows of their cut-line boxes from
 *    (0, length + gap), as wide as the fabric (a piece wider than the fabric
 *    alone in its row), in piece order, so their texcoords lie beyond v = 1
 *    (u may pass 1) and never on the marker's pieces or on one another.
 *    Without a marker, uv is normalized by the pattern's bounding box.
 *    glTF's v runs down: the shim flips it.
 *  - Seams: inputs->layout_* polylines (garment vertex ids) when given, else
 *    every pattern seam's side A and every dart's tip and leg A, as a LINES
 *    primitive over garment positions.
 * Errors: those of pz_glb_write_garment (export/glb_shim.h), PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "export/glb_shim.h"
#include "export/xml_text.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ texcoords */

/* A similarity-free map of a panel's uv into marker space: p -> s * (p - from) + to, s = +-1 per axis. */
typedef struct uv_map {
    double from[2], to[2];
    double sign[2];
    int placed;
} uv_map;

static void centroid(const double *points, int32_t count, double out[2])
{
    double area = 0, cx = 0, cy = 0;
    for (int32_t i = 0; i < count; ++i) {
        const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % count)];
        double cross = a[0] * b[1] - b[0] * a[1];
        area += cross, cx += (a[0] + b[0]) * cross, cy += (a[1] + b[1]) * cross;
    }
    if (fabs(area) > 1e-12) {
        out[0] = cx / (3 * area), out[1] = cy / (3 * area);
        return;
    }
    out[0] = out[1] = 0;
    for (int32_t i = 0; i < count; ++i)
        out[0] += points[2 * i] / count, out[1] += points[2 * i + 1] / count;
}

/* The placement of (piece, copy), or NULL. */
static const pz_marker_placement *find_placement(const pz_marker *marker, int32_t piece, int32_t copy)
{
    for (int32_t p = 0; p < marker->placement_count; ++p)
        if (marker->placements[p].piece == piece && marker->placements[p].copy == copy)
            return &marker->placements[p];
    return NULL;
}

/* How piece `index`'s points reach the marker: through its own copy 0, or its partner's mirrored copy 1. */
static uv_map piece_map(const pz_pieces *pieces, const pz_marker *marker, int32_t index)
{
    uv_map map = {{0, 0}, {0, 0}, {1, 1}, 0};
    const pz_piece *piece = &pieces->pieces[index];
    const pz_marker_placement *placement = NULL;
    const pz_piece *source = piece;
    if (!piece->mirrored) {
        placement = find_placement(marker, index, 0);
    } else if (piece->mirror_piece >= 0 && piece->mirror_piece < pieces->piece_count) {
        source = &pieces->pieces[piece->mirror_piece];
        placement = find_placement(marker, piece->mirror_piece, 1);
    }
    if (!placement)
        return map;
    double placed_centre[2], own_centre[2];
    centroid(source->cut, source->cut_count, placed_centre);
    pz_marker_place_points(source, placement, placed_centre, 1, map.to);
    centroid(piece->cut, piece->cut_count, own_centre);
    map.from[0] = own_centre[0], map.from[1] = own_centre[1];
    /* Own copy: the placement's own transform; a partner's copy: only its rotation (the mirror is built in). */
    double flip = placement->rotation_deg == 180 ? -1.0 : 1.0;
    map.sign[0] = (piece->mirrored ? 1.0 : (placement->mirrored ? -1.0 : 1.0)) * flip;
    map.sign[1] = flip;
    map.placed = 1;
    return map;
}

/*
 * The pieces without a place in the marker (left out, or the hidden partner of one left out): rows of their
 * cut-line boxes after the marker's end, gap apart, as wide as the fabric, in piece order.
 */
static void place_after_marker(const pz_pieces *pieces, const pz_marker *marker, double gap, int32_t panel_count,
                               uv_map *maps)
{
    gap = gap > 0 ? gap : 5.0;
    double x = 0, y = marker->length_mm + gap, row_height = 0;
    for (int32_t i = 0; i < pieces->piece_count; ++i) {
        const pz_piece *piece = &pieces->pieces[i];
        int32_t panel = piece->panel;
        if (panel < 0 || panel >= panel_count || maps[panel].placed || piece->cut_count < 1)
            continue;
        double width = piece->bbox_max[0] - piece->bbox_min[0], height = piece->bbox_max[1] - piece->bbox_min[1];
        if (x > 0 && x + width > marker->fabric_width_mm) {
            x = 0;
            y += row_height + gap;
            row_height = 0;
        }
        maps[panel] = (uv_map){{piece->bbox_min[0], piece->bbox_min[1]}, {x, y}, {1, 1}, 1};
        x += width + gap;
        row_height = fmax(row_height, height);
    }
}

/* Pattern coordinates normalized to the marker (or to the pattern's box without one). */
static pz_status marker_texcoords(const pz_export_inputs *inputs, double *texcoords, pz_ctx *ctx)
{
    const pz_pattern *pattern = inputs->pattern;
    const pz_mesh *mesh = pattern->mesh;
    int32_t *vertex_panel = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    uv_map *maps = calloc((size_t)pattern->panel_count + 1, sizeof *maps);
    if (!vertex_panel || !maps) {
        free(vertex_panel);
        free(maps);
        return pz_error(ctx, PZ_ERR_NOMEM, "garment.glb: out of memory");
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        vertex_panel[v] = -1;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            vertex_panel[mesh->faces[3 * f + k]] = pattern->face_panel[f];
    const pz_marker *marker = inputs->marker;
    const pz_pieces *pieces = inputs->pieces;
    for (int32_t i = 0; marker && pieces && i < pieces->piece_count; ++i) {
        int32_t panel = pieces->pieces[i].panel;
        if (panel >= 0 && panel < pattern->panel_count)
            maps[panel] = piece_map(pieces, marker, i);
    }
    if (marker && pieces)
        place_after_marker(pieces, marker, inputs->options ? inputs->options->gap_mm : 5.0, pattern->panel_count,
                           maps);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int d = 0; d < 2; ++d) {
            lo[d] = fmin(lo[d], inputs->uv[2 * v + d]);
            hi[d] = fmax(hi[d], inputs->uv[2 * v + d]);
        }
    double extent[2] = {marker ? marker->fabric_width_mm : hi[0] - lo[0], marker ? marker->length_mm : hi[1] - lo[1]};
    for (int d = 0; d < 2; ++d)
        extent[d] = extent[d] > 0 ? extent[d] : 1.0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *uv = &inputs->uv[2 * v];
        const uv_map *map = vertex_panel[v] >= 0 ? &maps[vertex_panel[v]] : NULL;
        for (int d = 0; d < 2; ++d) {
            double value = map && map->placed ? map->sign[d] * (uv[d] - map->from[d]) + map->to[d]
                                              : (marker ? 0.0 : uv[d] - lo[d]);
            texcoords[2 * v + d] = value / extent[d];
        }
    }
    free(maps);
    free(vertex_panel);
    return PZ_OK;
}

/* ------------------------------------------------------------------ seams */

typedef struct seam_lines {
    int32_t point_count, index_count;
    double *points;
    int32_t *indices;
} seam_lines;

/* Appends polyline `vertices` (ids into `positions`) as segments. */
static void add_polyline(seam_lines *lines, const double *positions, const int32_t *vertices, int32_t count)
{
    for (int32_t i = 0; i < count; ++i) {
        memcpy(&lines->points[3 * (size_t)lines->point_count], &positions[3 * (size_t)vertices[i]],
               3 * sizeof(double));
        if (i > 0) {
            lines->indices[lines->index_count++] = lines->point_count - 1;
            lines->indices[lines->index_count++] = lines->point_count;
        }
        ++lines->point_count;
    }
}

static pz_status seam_lines_build(const pz_export_inputs *inputs, seam_lines *lines, pz_ctx *ctx)
{
    memset(lines, 0, sizeof *lines);
    const pz_pattern *pattern = inputs->pattern;
    int from_layout = inputs->layout_vertices && inputs->layout_offsets && inputs->garment;
    size_t total = 0;
    if (from_layout) {
        total = (size_t)inputs->layout_offsets[inputs->layout_curve_count];
    } else {
        for (int32_t s = 0; s < pattern->seam_count; ++s)
            total += (size_t)pattern->seams[s].pair_count;
        for (int32_t d = 0; d < pattern->dart_count; ++d)
            total += (size_t)pattern->darts[d].pair_count + 1;
    }
    lines->points = malloc((total + 1) * 3 * sizeof(double));
    lines->indices = malloc((total + 1) * 2 * sizeof(int32_t));
    if (!lines->points || !lines->indices)
        return pz_error(ctx, PZ_ERR_NOMEM, "garment.glb: out of memory");
    if (from_layout) {
        for (int32_t c = 0; c < inputs->layout_curve_count; ++c) {
            int32_t begin = inputs->layout_offsets[c], end = inputs->layout_offsets[c + 1];
            for (int32_t i = begin; i < end; ++i)
                if (inputs->layout_vertices[i] < 0 || inputs->layout_vertices[i] >= inputs->garment->vertex_count)
                    return pz_error(ctx, PZ_ERR_INTERNAL, "garment.glb: layout curve %d leaves the garment", (int)c);
            add_polyline(lines, inputs->garment->positions, &inputs->layout_vertices[begin], end - begin);
        }
        return PZ_OK;
    }
    /* The cut mesh keeps the garment's positions: its seam sides are the seams on the body. */
    const double *positions = pattern->mesh->positions;
    for (int32_t s = 0; s < pattern->seam_count; ++s)
        add_polyline(lines, positions, pattern->seams[s].side_a, pattern->seams[s].pair_count);
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        add_polyline(lines, positions, &dart->tip, 1);
        lines->indices[lines->index_count++] = lines->point_count - 1; /* tip to the first leg point */
        lines->indices[lines->index_count++] = lines->point_count;
        add_polyline(lines, positions, dart->leg_a, dart->pair_count);
        if (dart->pair_count == 0)
            lines->index_count -= 2;
    }
    return PZ_OK;
}

/* ------------------------------------------------------------------ panel colours */

typedef struct panel_degree {
    int32_t panel, degree;
} panel_degree;

static int compare_degree(const void *a, const void *b)
{
    const panel_degree *p = a, *q = b;
    if (p->degree != q->degree)
        return (p->degree < q->degree) - (p->degree > q->degree);
    return (p->panel > q->panel) - (p->panel < q->panel);
}

static int compare_int64(const void *a, const void *b)
{
    int64_t p = *(const int64_t *)a, q = *(const int64_t *)b;
    return (p > q) - (p < q);
}

/*
 * colour (panel_count): a colour index per panel such that panels sharing a seam differ. Greedy (Welsh-Powell
 * order): O(S log S + P log P + sum of degrees) for S seams and P panels.
 */
static pz_status colour_panels(const pz_pattern *pattern, int32_t *colour, pz_ctx *ctx)
{
    int32_t panels = pattern->panel_count, seams = pattern->seam_count, edges = 0;
    int64_t *pairs = malloc(2 * ((size_t)seams + 1) * sizeof(int64_t));
    int32_t *start = calloc((size_t)panels + 2, sizeof(int32_t));
    int32_t *neighbours = malloc(2 * ((size_t)seams + 1) * sizeof(int32_t));
    panel_degree *order = malloc(((size_t)panels + 1) * sizeof(panel_degree));
    uint8_t *taken = calloc((size_t)panels + 2, 1);
    pz_status status = PZ_OK;
    if (!pairs || !start || !neighbours || !order || !taken) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "garment.glb: out of memory");
        goto done;
    }
    /* Both directions of every seam between two panels, once each (several seams may join a pair). */
    for (int32_t s = 0; s < seams; ++s) {
        int64_t a = pattern->seams[s].panel_a, b = pattern->seams[s].panel_b;
        if (a == b || a < 0 || b < 0 || a >= panels || b >= panels)
            continue;
        pairs[edges++] = a * panels + b;
        pairs[edges++] = b * panels + a;
    }
    qsort(pairs, (size_t)edges, sizeof(int64_t), compare_int64);
    int32_t unique = 0;
    for (int32_t i = 0; i < edges; ++i)
        if (i == 0 || pairs[i] != pairs[i - 1])
            pairs[unique++] = pairs[i];
    for (int32_t i = 0; i < unique; ++i)   /* CSR: sorted by panel, so each panel's run is contiguous */
        ++start[pairs[i] / panels + 1];
    for (int32_t p = 0; p < panels; ++p)
        start[p + 1] += start[p];
    for (int32_t i = 0; i < unique; ++i)
        neighbours[i] = (int32_t)(pairs[i] % panels);
    for (int32_t p = 0; p < panels; ++p) {
        order[p] = (panel_degree){p, start[p + 1] - start[p]};
        colour[p] = -1;
    }
    qsort(order, (size_t)panels, sizeof(panel_degree), compare_degree);
    for (int32_t i = 0; i < panels; ++i) {
        int32_t p = order[i].panel, degree = order[i].degree;
        for (int32_t j = start[p]; j < start[p + 1]; ++j)   /* colours above the degree are never needed */
            if (colour[neighbours[j]] >= 0 && colour[neighbours[j]] <= degree)
                taken[colour[neighbours[j]]] = 1;
        int32_t c = 0;
        while (taken[c])
            ++c;
        colour[p] = c;
        for (int32_t j = start[p]; j < start[p + 1]; ++j)
            if (colour[neighbours[j]] >= 0 && colour[neighbours[j]] <= degree)
                taken[colour[neighbours[j]]] = 0;
    }
done:
    free(pairs);
    free(start);
    free(neighbours);
    free(order);
    free(taken);
    return status;
}

/* ------------------------------------------------------------------ the writer */

pz_status pz_export_write_glb(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    const pz_mesh *mesh = inputs->pattern->mesh;
    double *texcoords = malloc(((size_t)mesh->vertex_count + 1) * 2 * sizeof(double));
    int32_t *vertex_panel = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    int32_t *colour = malloc(((size_t)inputs->pattern->panel_count + 1) * sizeof(int32_t));
    seam_lines lines = {0};
    pz_status status = texcoords && vertex_panel && colour ? PZ_OK
                                                           : pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    if (status == PZ_OK)
        status = colour_panels(inputs->pattern, colour, ctx);
    if (status == PZ_OK)
        status = marker_texcoords(inputs, texcoords, ctx);
    if (status == PZ_OK)
        status = seam_lines_build(inputs, &lines, ctx);
    if (status == PZ_OK) {
        memset(vertex_panel, 0, (size_t)mesh->vertex_count * sizeof(int32_t));
        for (int32_t f = 0; f < mesh->face_count; ++f)
            for (int k = 0; k < 3; ++k)
                vertex_panel[mesh->faces[3 * f + k]] = colour[inputs->pattern->face_panel[f]];
        /* glTF strings are UTF-8 (tinygltf's JSON writer throws on anything else). */
        char garment_name[sizeof inputs->pieces->garment_name + 8];
        pz_utf8_clean(inputs->pieces && inputs->pieces->garment_name[0] ? inputs->pieces->garment_name : "garment",
                      garment_name, sizeof garment_name);
        pz_glb_garment garment = {
            .vertex_count = mesh->vertex_count,
            .positions = mesh->positions,
            .vertex_group = vertex_panel,
            .texcoords = texcoords,
            .face_count = mesh->face_count,
            .faces = mesh->faces,
            .line_point_count = lines.point_count,
            .line_points = lines.points,
            .line_index_count = lines.index_count,
            .line_indices = lines.indices,
            .name = garment_name,
        };
        status = pz_glb_write_garment(&garment, file, name, ctx);
    }
    free(lines.points);
    free(lines.indices);
    free(vertex_panel);
    free(colour);
    free(texcoords);
    return status;
}
