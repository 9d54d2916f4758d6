/*
 * segment/mirror.c -- the layout of a mirror-symmetric garment, made on one
 * half and copied to the other (pietroni2022 Sec. 3, Fig. 3a: "splitting
 * the mesh along the symmetry plane, running the method on one side, and
 * then reflecting the result"; Sec. 4.2, "Symmetry"; Fig. 11: the seam on
 * the plane removed at the end where the goals allow; docs/segment.md,
 * "Symmetry").
 *
 * The garment is not split: its faces are given a half (the side of the
 * plane their centroid lies on; a component of one half smaller than
 * ISLAND_SHARE of the area, where the plane grazes a fold, joins the other
 * half) and the edges between the halves are cut first, as removable paths,
 * one per chain. Candidates are traced on half 0 alone, so they end on the
 * plane cut like the paper's paths end on the split mesh's border, and each
 * is inserted with its mirror image (segment/insert.c): no path crosses the
 * plane, so a path and its image never cross each other in an X. The
 * removal (segment/removal.c) uncuts each segment with its mirror segment
 * and the plane's segments last: where they go, a panel and its mirror image
 * merge into one panel that is its own mirror image.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A component of one half smaller than this share of the garment's area joins the other half. */
#define ISLAND_SHARE 0.02

/* Each panel's mirror panel and half for one labelling (seg_panel_failures). */
struct seg_panel_mirrors {
    int64_t labelling;    /* the labelling the map belongs to */
    int32_t *mirror;      /* panel count */
    uint8_t *half;        /* panel count: 0, 1, or 2 with faces on both halves */
    int32_t capacity;
};

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

/* ---------------------------------------------------------------- halves */

static double face_area(const pz_mesh *mesh, int32_t f)
{
    const int32_t *c = mesh->faces + 3 * (size_t)f;
    double u[3], v[3], n[3];
    pz_vec3_sub(mesh->positions + 3 * (size_t)c[1], mesh->positions + 3 * (size_t)c[0], u);
    pz_vec3_sub(mesh->positions + 3 * (size_t)c[2], mesh->positions + 3 * (size_t)c[0], v);
    pz_vec3_cross(u, v, n);
    return 0.5 * pz_vec3_norm(n);
}

/*
 * Flips to the other half every component (faces of `which` half joined
 * across edges not cut yet) whose area is below ISLAND_SHARE of `total`.
 * stack: face_count. The cuts made before the plane's are the sketches and
 * seeds: a designer's centre line drawn near the plane leaves strips between
 * it and the plane that become their neighbours' half, so the halves meet
 * along the designer's line and no sliver is left between two seams.
 */
static void flip_islands(const seg_layout *layout, uint8_t *half, uint8_t which, double total, int32_t *stack,
                         uint8_t *seen)
{
    const pz_topology *t = layout->topology;
    memset(seen, 0, (size_t)t->face_count);
    for (int32_t start = 0; start < t->face_count; ++start) {
        if (seen[start] || half[start] != which)
            continue;
        int32_t top = 0, size = 0;
        double area = 0;
        stack[top++] = start;
        seen[start] = 1;
        while (size < top) { /* the stack keeps every face of the component: flipped afterwards if small */
            int32_t f = stack[size++];
            area += face_area(layout->mesh, f);
            for (int k = 0; k < 3; ++k) {
                int32_t twin = t->twin[3 * f + k];
                int32_t g = twin >= 0 ? pz_he_face(twin) : -1;
                if (g >= 0 && !seen[g] && half[g] == which && !layout->edge_cut[t->halfedge_edge[3 * f + k]]) {
                    seen[g] = 1;
                    stack[top++] = g;
                }
            }
        }
        if (area < ISLAND_SHARE * total)
            for (int32_t i = 0; i < top; ++i)
                half[stack[i]] = (uint8_t)!which;
    }
}

/* Each face's half: the side of the plane its centroid lies on, islands flipped. 0 when out of memory. */
static int face_halves(const seg_layout *layout, uint8_t *half)
{
    const pz_mesh *mesh = layout->mesh;
    const pz_symmetry *s = &layout->symmetry;
    double total = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *c = mesh->faces + 3 * (size_t)f;
        double centroid[3];
        for (int k = 0; k < 3; ++k)
            centroid[k] = (mesh->positions[3 * (size_t)c[0] + k] + mesh->positions[3 * (size_t)c[1] + k] +
                           mesh->positions[3 * (size_t)c[2] + k]) / 3;
        half[f] = pz_vec3_dot(s->normal, centroid) > s->offset;
        total += face_area(mesh, f);
    }
    int32_t *stack = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    uint8_t *seen = malloc((size_t)mesh->face_count + 1);
    if (!stack || !seen) {
        free(stack), free(seen);
        return 0;
    }
    flip_islands(layout, half, 1, total, stack, seen);
    flip_islands(layout, half, 0, total, stack, seen);
    free(stack), free(seen);
    return 1;
}

/* ---------------------------------------------------------------- the cut along the plane */

static int32_t plane_degree(const seg_layout *layout, int32_t v)
{
    int32_t degree = 0;
    for (int32_t i = layout->vertex_edge_offsets[v]; i < layout->vertex_edge_offsets[v + 1]; ++i)
        degree += layout->edge_plane[layout->vertex_edges[i]];
    return degree;
}

static int32_t other_end(const seg_layout *layout, int32_t e, int32_t v)
{
    int32_t h = layout->topology->edge_halfedge[2 * e];
    int32_t a = pz_he_from(layout->topology, h);
    return a == v ? pz_he_to(layout->topology, h) : a;
}

/* The unvisited plane edge at v, or -1. */
static int32_t next_plane_edge(const seg_layout *layout, int32_t v, const uint8_t *visited)
{
    for (int32_t i = layout->vertex_edge_offsets[v]; i < layout->vertex_edge_offsets[v + 1]; ++i) {
        int32_t e = layout->vertex_edges[i];
        if (layout->edge_plane[e] && !visited[e])
            return e;
    }
    return -1;
}

/* Walks the chain of plane edges from v along e to the next node (or round a cycle) and inserts it. */
static pz_status insert_chain(seg_layout *layout, int32_t v, int32_t e, uint8_t *visited, int32_t *chain, pz_ctx *ctx)
{
    int32_t n = 0, start = v;
    int closed = 0;
    chain[n++] = v;
    while (e >= 0) {
        visited[e] = 1;
        v = other_end(layout, e, v);
        if (v == start) {
            closed = 1;
            break;
        }
        chain[n++] = v;
        int node = layout->topology->vertex_on_boundary[v] || plane_degree(layout, v) != 2;
        e = node ? -1 : next_plane_edge(layout, v, visited);
    }
    pz_trace_path path;
    memset(&path, 0, sizeof path);
    pz_status status = pz_trace_path_through(layout->graph, layout->mesh, layout->topology, chain, n, closed, &path,
                                             ctx);
    if (!status)
        status = seg_add_path(layout, &path, 0, ctx);
    pz_trace_path_clear(&path);
    return status;
}

/*
 * The vertices of the plane cut map to the cut vertex nearest their mirror
 * image (the cut stands for the plane, its own mirror image), a border one
 * to the nearest cut vertex on the border: a path traced on half 0 that ends
 * on the cut then has a mirror image that ends on it too, not an edge away
 * (a slit). On an exactly symmetric mesh that is the exact mirror vertex.
 * Brute force over the cut's P vertices: P^2 with P of the order of sqrt(V).
 */
static pz_status mirror_on_cut(seg_layout *layout, pz_ctx *ctx)
{
    const pz_topology *t = layout->topology;
    int32_t *cut = malloc(((size_t)t->vertex_count + 1) * sizeof(int32_t)), count = 0;
    if (!cut)
        return nomem(ctx);
    for (int32_t v = 0; v < t->vertex_count; ++v)
        if (plane_degree(layout, v) > 0)
            cut[count++] = v;
    const double *x = layout->mesh->positions;
    for (int32_t i = 0; i < count; ++i) {
        double image[3], best = INFINITY;
        pz_symmetry_reflect_point(&layout->symmetry, x + 3 * (size_t)cut[i], image);
        int32_t found = -1;
        for (int pass = 0; pass < 2 && found < 0; ++pass) /* the same border status first, then any */
            for (int32_t j = 0; j < count; ++j) {
                if (pass == 0 && t->vertex_on_boundary[cut[j]] != t->vertex_on_boundary[cut[i]])
                    continue;
                double d = pz_vec3_distance(image, x + 3 * (size_t)cut[j]);
                if (d < best || (d == best && cut[j] == cut[i]))
                    best = d, found = cut[j];
            }
        layout->symmetry.vertex_mirror[cut[i]] = found;
    }
    free(cut);
    return PZ_OK;
}

void seg_mirror_free(seg_layout *layout)
{
    if (layout->mirrors)
        free(layout->mirrors->mirror), free(layout->mirrors->half);
    free(layout->mirrors);
    free(layout->face_half);
    free(layout->edge_plane);
    layout->mirrors = NULL, layout->face_half = NULL, layout->edge_plane = NULL;
}

pz_status seg_plane_cut(seg_layout *layout, pz_ctx *ctx)
{
    if (!layout->symmetry.found || !layout->symmetry.face_mirror)
        return PZ_OK;
    const pz_topology *t = layout->topology;
    layout->face_half = malloc((size_t)t->face_count + 1);
    layout->edge_plane = calloc((size_t)t->edge_count + 1, 1);
    layout->mirrors = calloc(1, sizeof *layout->mirrors);
    if (!layout->face_half || !layout->edge_plane || !layout->mirrors || !face_halves(layout, layout->face_half))
        return nomem(ctx);
    layout->mirrors->labelling = -1;
    int32_t counts[2] = {0, 0}, plane_edges = 0;
    for (int32_t f = 0; f < t->face_count; ++f)
        ++counts[layout->face_half[f]];
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t a = t->edge_halfedge[2 * e], b = t->edge_halfedge[2 * e + 1];
        layout->edge_plane[e] = b >= 0 && layout->face_half[pz_he_face(a)] != layout->face_half[pz_he_face(b)];
        plane_edges += layout->edge_plane[e];
    }
    if (counts[0] == 0 || counts[1] == 0 || plane_edges == 0) {
        /* The plane misses the garment: no halves (the mirror image still pairs the paths). */
        seg_mirror_free(layout);
        return PZ_OK;
    }
    uint8_t *visited = calloc((size_t)t->edge_count + 1, 1);
    int32_t *chain = malloc(((size_t)t->vertex_count + 1) * sizeof(int32_t));
    pz_status status = visited && chain ? mirror_on_cut(layout, ctx) : nomem(ctx);
    /* Chains from nodes first, then the cycles that have none; vertex and edge order keep it deterministic. */
    for (int pass = 0; pass < 2 && !status; ++pass)
        for (int32_t v = 0; v < t->vertex_count && !status; ++v) {
            int node = t->vertex_on_boundary[v] || plane_degree(layout, v) != 2;
            if (pass == 0 && !node)
                continue;
            for (int32_t e; !status && (e = next_plane_edge(layout, v, visited)) >= 0;)
                status = insert_chain(layout, v, e, visited, chain, ctx);
        }
    free(visited), free(chain);
    return status;
}

/* ---------------------------------------------------------------- candidates of one half */

pz_status seg_trace_half(seg_layout *layout, int32_t sources, pz_trace_paths **out, pz_ctx *ctx)
{
    *out = NULL;
    const pz_topology *t = layout->topology;
    int32_t *faces = malloc(((size_t)t->face_count + 1) * sizeof(int32_t)), count = 0;
    if (!faces)
        return nomem(ctx);
    for (int32_t f = 0; f < t->face_count; ++f)
        if (layout->face_half[f] == 0)
            faces[count++] = f;
    pz_status status = seg_trace_faces(layout, faces, count, sources, out, ctx);
    free(faces);
    if (!status && !*out) { /* the half has no topology of its own (pinched at a vertex): the whole garment */
        pz_trace_candidate_options options = {0};
        options.border_sources = options.interior_sources = sources;
        options.threads = layout->threads;
        status = pz_trace_candidates(layout->graph, layout->mesh, t, &options, out, ctx);
    }
    return status;
}

/* ---------------------------------------------------------------- mirror panels */

static int compare_int64(const void *l, const void *r)
{
    int64_t a = *(const int64_t *)l, b = *(const int64_t *)r;
    return (a > b) - (a < b);
}

/*
 * The panel holding most of a panel's faces' mirror faces (face_mirror: the
 * face nearest each mirrored centroid), so a panel straddling the plane is
 * its own mirror. Votes are (panel, mirror panel) pairs sorted and counted:
 * O(F log F), whatever the panel count.
 */
pz_status seg_mirror_panels(const seg_layout *layout, int32_t *mirror_panel, pz_ctx *ctx)
{
    for (int32_t p = 0; p < layout->panel_count; ++p)
        mirror_panel[p] = -1;
    const int32_t *face_mirror = layout->symmetry.face_mirror;
    if (!layout->symmetry.found || !face_mirror)
        return PZ_OK;
    int32_t faces = layout->topology->face_count, count = 0;
    int64_t panels = layout->panel_count;
    int64_t *votes = malloc(((size_t)faces + 1) * sizeof(int64_t));
    if (!votes)
        return nomem(ctx);
    for (int32_t f = 0; f < faces; ++f)
        if (face_mirror[f] >= 0)
            votes[count++] = layout->face_panel[f] * panels + layout->face_panel[face_mirror[f]];
    qsort(votes, (size_t)count, sizeof(int64_t), compare_int64);
    int32_t best_votes = 0;
    for (int32_t i = 0; i < count;) {
        int32_t j = i;
        while (j < count && votes[j] == votes[i])
            ++j;
        int32_t p = (int32_t)(votes[i] / panels), q = (int32_t)(votes[i] % panels);
        if (i == 0 || votes[i] / panels != votes[i - 1] / panels)
            best_votes = 0; /* a new panel's runs start */
        if (j - i > best_votes) {
            best_votes = j - i;
            mirror_panel[p] = q;
        }
        i = j;
    }
    free(votes);
    return PZ_OK;
}

/* ---------------------------------------------------------------- mirrored paths */

int seg_path_in_half(const seg_layout *layout, const pz_trace_path *path, uint8_t half)
{
    if (!layout->face_half)
        return 1;
    const pz_topology *t = layout->topology;
    int32_t n = path->vertex_count, edges = path->closed ? n : n - 1;
    for (int32_t i = 0; i < edges; ++i) {
        int32_t e = seg_edge_between(layout, path->vertices[i], path->vertices[(i + 1) % n]);
        if (e < 0)
            return 0;
        int32_t a = t->edge_halfedge[2 * e], b = t->edge_halfedge[2 * e + 1];
        if (layout->face_half[pz_he_face(a)] != half && (b < 0 || layout->face_half[pz_he_face(b)] != half))
            return 0;
    }
    return 1;
}

/* ---------------------------------------------------------------- pairs are judged together */

/* The map of the current labelling: each panel's mirror panel and half (2: both). 0 when out of memory. */
static int panel_mirrors(const seg_layout *layout)
{
    struct seg_panel_mirrors *m = layout->mirrors;
    if (m->labelling == layout->labelling && m->mirror)
        return 1;
    if (m->capacity < layout->panel_count) {
        int32_t *grown = realloc(m->mirror, ((size_t)layout->panel_count + 1) * sizeof(int32_t));
        uint8_t *half = realloc(m->half, (size_t)layout->panel_count + 1);
        if (grown)
            m->mirror = grown;
        if (half)
            m->half = half;
        if (!grown || !half)
            return 0;
        m->capacity = layout->panel_count;
    }
    pz_ctx quiet;
    pz_ctx_init(&quiet);
    quiet.quiet = 1;
    if (seg_mirror_panels(layout, m->mirror, &quiet) != PZ_OK)
        return 0;
    for (int32_t p = 0; p < layout->panel_count; ++p) {
        int32_t in_half_1 = 0, count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
        for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
            in_half_1 += layout->face_half[layout->panel_faces[i]];
        m->half[p] = in_half_1 == 0 ? 0 : in_half_1 == count ? 1 : 2;
    }
    m->labelling = layout->labelling;
    return 1;
}

/* The partner of panel p when p and it are a mirror pair across the halves (p on one, it on the other), -1. */
static int32_t partner(const seg_layout *layout, int32_t p)
{
    if (!layout->face_half || !layout->mirrors || !panel_mirrors(layout))
        return -1;
    const struct seg_panel_mirrors *m = layout->mirrors;
    int32_t q = m->mirror[p];
    if (q < 0 || q == p || q >= layout->panel_count || m->half[p] == 2 || m->half[q] == 2 || m->half[p] == m->half[q])
        return -1;
    return q;
}

/*
 * A mirror pair is one pattern piece, cut twice (the panel of half 0,
 * flattened, and its reflection), so the pair fails when either panel does,
 * with one exception: the copy's outline is not the piece's. Its junctions
 * sit an edge or two off the mirror images of the other side's (the mirrored
 * paths close their gaps through the nearest vertices), which would count
 * corners the piece does not have: the copy's corners are its partner's.
 */
unsigned seg_panel_failures(const seg_layout *layout, int32_t p)
{
    unsigned own = layout->panel_goals[p].failures;
    int32_t q = partner(layout, p);
    if (q < 0)
        return own;
    unsigned other = layout->panel_goals[q].failures;
    return layout->mirrors->half[p] == 0 ? own | (other & ~(unsigned)PZ_GOAL_CORNERS)
                                         : other | (own & ~(unsigned)PZ_GOAL_CORNERS);
}

int32_t seg_panel_partner(const seg_layout *layout, int32_t p)
{
    return partner(layout, p);
}

int seg_pair_goals(const seg_layout *layout, int32_t p, pz_goal_result *goals)
{
    *goals = layout->panel_goals[p];
    goals->failures = seg_panel_failures(layout, p);
    int32_t q = partner(layout, p);
    if (q < 0 || layout->mirrors->half[p] != 1)
        return 0;
    goals->corners = layout->panel_goals[q].corners; /* the piece's outline is its partner's, reflected */
    return 1;
}
