/*
 * segment/goals.c -- does one panel meet the goals of pietroni2022 Sec. 3.1?
 *
 * A panel is a set of garment faces plus the layout's cut flags. Everything
 * is computed on the garment's own half-edges, so a panel whose outline
 * touches itself at a vertex (a pinch) is handled without building a
 * non-manifold mesh:
 *
 *  1. Opening. Every corner (half-edge h, the corner at its source) of a
 *     panel face is joined (union-find) with the corner across each uncut
 *     edge whose two faces are both in the panel. A class of corners is a
 *     vertex of the *opened* panel (the panel cut along its own slits).
 *     Outline half-edges are those whose twin is missing, outside the panel,
 *     or across a cut edge (a slit: the panel on both sides).
 *  2. Disk: the opened panel is one face component, has one outline loop and
 *     V - E + F = 1.
 *  3. Corners (docs/segment.md): walking each outline loop, an outline vertex
 *     is a *junction* corner when the neighbour across the outline changes
 *     there (another panel: the face component across the cut, found by a
 *     flood fill over uncut edges; the open border; the panel itself across
 *     a slit), or when it is a slit's tip (the outline comes back along the
 *     same edge). It is a *turn* corner when the outline turns by more than
 *     TURN_CORNER_DEG in the tangent plane, the turn being measured between
 *     the chords to the outline points TURN_WINDOW_EDGES mean edge lengths
 *     behind and ahead, so the staircase of a mesh-edge path does not count;
 *     a turn corner must be the largest turn within that window and lie
 *     farther than the window from every junction corner (one geometric
 *     corner counts once).
 *  3b. Piece shape (docs/segment.md, "Piece shapes"): the panel's share of
 *     the garment's area and its width (pz_piece_width over the opened
 *     panel), and whether the input forces them (a whole component; narrow
 *     by its border rather than by a seam).
 *  4. Strain and injectivity, only for a disk within the corner bound (a
 *     panel failing those must be split anyway): the panel is extracted (its
 *     vertices split at pinches only), turned into a one-panel pz_pattern
 *     whose extra cuts are its slits (so slits ending inside become darts
 *     with the dart term), flattened by pz_param_textile (few iterations,
 *     one thread: callers evaluate panels in parallel) and measured with
 *     pz_metrics_compute: the worst |warp| or |weft| strain, flipped
 *     triangles and boundary self-intersections, the extent across the
 *     grain and the darts' intakes.
 *
 * Cost: O(F_panel) for 1-3 plus the flood fills of the neighbouring panels
 * (O(F) at worst, scratch of O(F) per call), and the flattening (a few
 * sparse solves of the panel). Thread-safe: no shared state.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"
#include "param/param.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Textile iterations of an evaluation: the strain settles within a few
 * local/global steps from the LSCM start (docs/segment.md). */
#define DEFAULT_TEXTILE_ITERATIONS 5
#define TURN_CORNER_DEG 50.0
#define TURN_WINDOW_EDGES 2.0

/* Neighbour labels of an outline edge besides a panel id (>= 0). */
#define NEIGHBOUR_BORDER (-1)
#define NEIGHBOUR_SELF (-2)

typedef struct panel_walk {
    const pz_mesh *mesh;
    const pz_topology *topology;
    const uint8_t *edge_cut;
    const int32_t *face_ids;
    int32_t count;
    const int32_t *face_panel; /* face_count: the panels' labels when known (face_ids is one of them), or NULL */
    int32_t *local;        /* face_count: index in face_ids, or -1 (scratch: -1 again when done) */
    int32_t *corner_root;  /* 3 * count: union-find over panel corners (index 3 i + k) */
    uint8_t *on_outline;   /* 3 * count: the half-edge is on the opened panel's outline */
    int32_t *neighbour;    /* face_count: flood-fill label of faces outside the panel, -1 unset (scratch) */
    int32_t *stack;        /* face_count */
    int32_t *labelled;     /* face_count: the faces given a neighbour label, to unset them when done */
    int32_t labelled_count;
    int32_t next_label;
    seg_goal_scratch *scratch; /* kept panels (kept_flattening) */
} panel_walk;

/* A panel flattened before, kept with its textile set-up (pz_textile_setup) for the next evaluation of the
 * same panel (kept_flattening). */
typedef struct kept_panel {
    int32_t *key;                /* its faces in order, then its slits (panel corner indices); NULL: a free slot */
    int32_t key_length, face_count;
    pz_pattern *pattern;
    pz_textile_solver *solver;
    uint64_t used;               /* last use (eviction) */
    /* The figures of its flattening, once measured: the same faces and slits flatten the same way (the
     * flattening does not see the neighbours), so a later evaluation takes them instead of solving again. */
    int measured;
    pz_goal_result figures;
} kept_panel;

/* At most this many kept panels per scratch, of at most KEPT_FACE_RATIO x the mesh's faces and KEPT_FACES
 * faces in all (a kept panel takes about 270 bytes per face: 100,000 faces are 27 MB per thread). On the
 * shared garments a panel comes back within 4x the mesh's faces of other evaluations; on the 50K bodice
 * (one thread) the 100,000 faces save 36 of its 46 repeated analyses. */
#define KEPT_PANELS 64
#define KEPT_FACE_RATIO 4
#define KEPT_FACES 100000

/* Face-indexed arrays of panel_walk, all -1 between evaluations (local, neighbour) so that an evaluation
 * costs O(its panel and neighbours) rather than O(F) to initialize them. One per thread. The kept
 * panels belong to one mesh and one set of goal options (those of their first use: others clear them). */
struct seg_goal_scratch {
    int32_t face_count;
    int32_t *local, *neighbour, *stack, *labelled;
    kept_panel kept[KEPT_PANELS];
    int64_t kept_faces;
    uint64_t clock;
    const pz_mesh *kept_mesh;
    pz_goal_options kept_options;
    const pz_mesh *area_mesh;   /* the mesh garment_area was measured on (one mesh per layout) */
    double garment_area;
};

seg_goal_scratch *seg_goal_scratch_new(int32_t face_count)
{
    seg_goal_scratch *scratch = calloc(1, sizeof *scratch);
    if (!scratch)
        return NULL;
    size_t bytes = ((size_t)face_count + 1) * sizeof(int32_t);
    scratch->face_count = face_count;
    scratch->local = malloc(bytes);
    scratch->neighbour = malloc(bytes);
    scratch->stack = malloc(bytes);
    scratch->labelled = malloc(bytes);
    if (!scratch->local || !scratch->neighbour || !scratch->stack || !scratch->labelled) {
        seg_goal_scratch_free(scratch);
        return NULL;
    }
    memset(scratch->local, 0xff, bytes);
    memset(scratch->neighbour, 0xff, bytes);
    return scratch;
}

static void kept_clear(kept_panel *kept)
{
    free(kept->key);
    pz_textile_solver_free(&kept->solver);
    pz_pattern_free(&kept->pattern);
    memset(kept, 0, sizeof *kept);
}

void seg_goal_scratch_free(seg_goal_scratch *scratch)
{
    if (!scratch)
        return;
    for (int i = 0; i < KEPT_PANELS; ++i)
        kept_clear(&scratch->kept[i]);
    free(scratch->local);
    free(scratch->neighbour);
    free(scratch->stack);
    free(scratch->labelled);
    free(scratch);
}

static int32_t find_root(int32_t *root, int32_t c)
{
    while (root[c] != c) {
        root[c] = root[root[c]];
        c = root[c];
    }
    return c;
}

static void unite(int32_t *root, int32_t a, int32_t b)
{
    a = find_root(root, a);
    b = find_root(root, b);
    /* The smaller index wins: the classes do not depend on the union order. */
    if (a < b)
        root[b] = a;
    else if (b < a)
        root[a] = b;
}

/* Panel corner index of garment half-edge h (its face must be in the panel). */
static int32_t local_corner(const panel_walk *w, int32_t h)
{
    return 3 * w->local[pz_he_face(h)] + h % 3;
}

/* The twin of h when it lies in the panel across an uncut edge, else -1. */
static int32_t inner_twin(const panel_walk *w, int32_t h, int slits_open)
{
    int32_t t = w->topology->twin[h];
    if (t < 0 || w->local[pz_he_face(t)] < 0)
        return -1;
    if (slits_open && w->edge_cut[w->topology->halfedge_edge[h]])
        return -1;
    return t;
}

/* Joins corners across inner edges (slits kept apart when slits_open). */
static void join_corners(panel_walk *w, int slits_open)
{
    for (int32_t c = 0; c < 3 * w->count; ++c)
        w->corner_root[c] = c;
    for (int32_t i = 0; i < w->count; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t h = 3 * w->face_ids[i] + k;
            int32_t t = inner_twin(w, h, slits_open);
            if (t < 0 || t < h)
                continue;
            /* h runs a -> b, t runs b -> a: corner h (at a) meets next(t), next(h) (at b) meets t. */
            unite(w->corner_root, 3 * i + k, local_corner(w, pz_he_next(t)));
            unite(w->corner_root, 3 * i + (k + 1) % 3, local_corner(w, t));
        }
}

/* The outline half-edge that follows outline half-edge h (around the corner fan at its end). */
static int32_t outline_next(const panel_walk *w, int32_t h)
{
    int32_t g = pz_he_next(h);
    for (int guard = 0; !w->on_outline[local_corner(w, g)] && guard < 1 << 20; ++guard)
        g = pz_he_next(inner_twin(w, g, 1));
    return g;
}

/* Label of the panel across outline half-edge h. */
static int32_t neighbour_label(panel_walk *w, int32_t h)
{
    const pz_topology *t = w->topology;
    int32_t twin = t->twin[h];
    if (twin < 0)
        return NEIGHBOUR_BORDER;
    int32_t face = pz_he_face(twin);
    if (w->local[face] >= 0)
        return NEIGHBOUR_SELF;
    if (w->face_panel) /* the panel is a whole one of these: the others are its neighbours' components */
        return w->face_panel[face];
    if (w->neighbour[face] >= 0)
        return w->neighbour[face];
    /* Flood fill the neighbouring panel across uncut edges. */
    int32_t label = w->next_label++, top = 0;
    w->neighbour[face] = label;
    w->labelled[w->labelled_count++] = face;
    w->stack[top++] = face;
    while (top > 0) {
        int32_t f = w->stack[--top];
        for (int k = 0; k < 3; ++k) {
            int32_t g = t->twin[3 * f + k];
            if (g < 0 || w->edge_cut[t->halfedge_edge[3 * f + k]])
                continue;
            int32_t across = pz_he_face(g);
            if (w->neighbour[across] >= 0 || w->local[across] >= 0)
                continue;
            w->neighbour[across] = label;
            w->labelled[w->labelled_count++] = across;
            w->stack[top++] = across;
        }
    }
    return label;
}

static double distance3(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static const double *position(const panel_walk *w, int32_t h)
{
    return w->mesh->positions + 3 * w->topology->faces[h];
}

/* Area-weighted normal of the corner fan of outline half-edge h (the panel faces at its source). */
static void fan_normal(const panel_walk *w, int32_t h, double normal[3])
{
    normal[0] = normal[1] = normal[2] = 0;
    int32_t g = h;
    for (int guard = 0; guard < 64; ++guard) {
        const int32_t *f = w->mesh->faces + 3 * pz_he_face(g);
        const double *a = w->mesh->positions + 3 * f[0], *b = w->mesh->positions + 3 * f[1],
                     *c = w->mesh->positions + 3 * f[2];
        double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        normal[0] += ab[1] * ac[2] - ab[2] * ac[1];
        normal[1] += ab[2] * ac[0] - ab[0] * ac[2];
        normal[2] += ab[0] * ac[1] - ab[1] * ac[0];
        int32_t incoming = pz_he_prev(g);
        if (w->on_outline[local_corner(w, incoming)])
            break;
        g = inner_twin(w, incoming, 1);
    }
    double length = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    for (int i = 0; i < 3 && length > 0; ++i)
        normal[i] /= length;
}

/* Turning angle (degrees) of the outline at loop position i, chords over `window` mm each side. */
static double turn_angle(const panel_walk *w, const int32_t *loop, const double *arc, int32_t n, int32_t i,
                         double window)
{
    int32_t reach = n / 3 > 1 ? n / 3 : 1;
    const double *p = position(w, loop[i]);
    int32_t back = i, ahead = i;
    for (int32_t s = 1; s <= reach; ++s) {
        back = (i - s + n) % n;
        double along = arc[i] - arc[back];
        if (along < 0)
            along += arc[n];
        if (along >= window)
            break;
    }
    for (int32_t s = 1; s <= reach; ++s) {
        ahead = (i + s) % n;
        double along = arc[ahead] - arc[i];
        if (along < 0)
            along += arc[n];
        if (along >= window)
            break;
    }
    const double *pb = position(w, loop[back]), *pa = position(w, loop[ahead]);
    double normal[3], in[3], out[3];
    fan_normal(w, loop[i], normal);
    for (int k = 0; k < 3; ++k) {
        in[k] = p[k] - pb[k];
        out[k] = pa[k] - p[k];
    }
    double din = in[0] * normal[0] + in[1] * normal[1] + in[2] * normal[2];
    double dout = out[0] * normal[0] + out[1] * normal[1] + out[2] * normal[2];
    for (int k = 0; k < 3; ++k) {
        in[k] -= din * normal[k];
        out[k] -= dout * normal[k];
    }
    double lin = sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2]);
    double lout = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    if (lin <= 0 || lout <= 0)
        return 0;
    double cosine = (in[0] * out[0] + in[1] * out[1] + in[2] * out[2]) / (lin * lout);
    return acos(fmax(-1.0, fmin(1.0, cosine))) * 180.0 / 3.14159265358979323846;
}

/* Arc distance along the loop between positions i and j (the shorter way round). */
static double loop_gap(const double *arc, int32_t n, int32_t i, int32_t j)
{
    double d = fabs(arc[i] - arc[j]);
    return fmin(d, arc[n] - d);
}

/* 1 when outline half-edges a and b run along the same mesh edge in opposite directions. */
static int same_edge_back(const panel_walk *w, int32_t a, int32_t b)
{
    const int32_t *f = w->topology->faces;
    return f[a] == f[pz_he_next(b)] && f[pz_he_next(a)] == f[b];
}

/*
 * Drops the dart excursions from an outline loop: at a slit's tip (the loop
 * arrives along an edge and leaves along the same edge) the loop runs up one
 * leg and back down the other; the half-edges of both legs, out to where they
 * stop facing each other (the mouth), are removed. What is left is the
 * outline a cutter sees with the darts closed: the seam trued across each
 * mouth (docs/segment.md, "Corners of a dart"). Compacts loop in place and
 * returns its new length; the loop is left whole when the slits are all of it.
 */
static int32_t close_darts(const panel_walk *w, int32_t *loop, int32_t n, uint8_t *drop)
{
    memset(drop, 0, (size_t)n);
    int32_t dropped = 0;
    for (int32_t i = 0; i < n && n > 2; ++i) {
        int32_t before = (i - 1 + n) % n;
        if (drop[i] || drop[before] || !same_edge_back(w, loop[before], loop[i]))
            continue;
        for (int32_t k = 0; k < n / 2; ++k) {
            int32_t a = ((i - 1 - k) % n + n) % n, b = (i + k) % n;
            if (drop[a] || drop[b] || a == b || !same_edge_back(w, loop[a], loop[b]))
                break;
            drop[a] = drop[b] = 1;
            dropped += 2;
        }
    }
    if (dropped == 0 || dropped >= n - 2)
        return n;
    int32_t kept = 0;
    for (int32_t i = 0; i < n; ++i)
        if (!drop[i])
            loop[kept++] = loop[i];
    return kept;
}

/* Corners of one outline loop (half-edges loop[0..n-1] in order; darts closed first, so loop changes). */
static int32_t loop_corners(panel_walk *w, int32_t *loop, int32_t n, double window, double *arc, double *turn,
                            uint8_t *junction)
{
    n = close_darts(w, loop, n, junction);
    arc[0] = 0;
    for (int32_t i = 0; i < n; ++i)
        arc[i + 1] = arc[i] + distance3(position(w, loop[i]), position(w, pz_he_next(loop[i])));
    int32_t corners = 0;
    for (int32_t i = 0; i < n; ++i) {
        int32_t before = loop[(i - 1 + n) % n];
        /* A slit's tip: the outline arrives along an edge and leaves along the same edge. */
        int tip = w->topology->faces[before] == w->topology->faces[pz_he_next(loop[i])] && n > 2;
        junction[i] = tip || neighbour_label(w, before) != neighbour_label(w, loop[i]);
        corners += junction[i];
    }
    for (int32_t i = 0; i < n; ++i)
        turn[i] = junction[i] ? 0 : turn_angle(w, loop, arc, n, i, window);
    for (int32_t i = 0; i < n; ++i) {
        if (turn[i] <= TURN_CORNER_DEG)
            continue;
        int keep = 1;
        for (int32_t s = -n / 2; s <= n / 2 && keep; ++s) {
            int32_t j = ((i + s) % n + n) % n;
            if (j == i || loop_gap(arc, n, i, j) > window)
                continue;
            if (junction[j] || turn[j] > turn[i] || (turn[j] == turn[i] && j < i))
                keep = 0;
        }
        corners += keep;
    }
    return corners;
}

/* Walks every outline loop: counts loops and corners. Returns 0 on out of memory. */
static int walk_outline(panel_walk *w, double window, int32_t *loops_out, int32_t *corners_out)
{
    int32_t outline_count = 0;
    for (int32_t c = 0; c < 3 * w->count; ++c)
        outline_count += w->on_outline[c];
    int32_t *loop = malloc(((size_t)outline_count + 1) * sizeof(int32_t));
    double *arc = malloc(((size_t)outline_count + 2) * sizeof(double));
    double *turn = malloc(((size_t)outline_count + 1) * sizeof(double));
    uint8_t *junction = malloc((size_t)outline_count + 1);
    uint8_t *seen = calloc((size_t)3 * w->count + 1, 1);
    int ok = loop && arc && turn && junction && seen;
    int32_t loops = 0, corners = 0;
    for (int32_t i = 0; ok && i < w->count; ++i)
        for (int k = 0; k < 3; ++k) {
            if (!w->on_outline[3 * i + k] || seen[3 * i + k])
                continue;
            int32_t n = 0, h = 3 * w->face_ids[i] + k;
            while (!seen[local_corner(w, h)] && n < outline_count) {
                seen[local_corner(w, h)] = 1;
                loop[n++] = h;
                h = outline_next(w, h);
            }
            ++loops;
            corners += loop_corners(w, loop, n, window, arc, turn, junction);
        }
    free(loop);
    free(arc);
    free(turn);
    free(junction);
    free(seen);
    *loops_out = loops;
    *corners_out = corners;
    return ok;
}

/* Face components of the opened panel (over inner uncut edges). */
static int32_t opened_components(panel_walk *w)
{
    int32_t *root = w->stack; /* face_count >= count: reused as a union-find over panel faces */
    for (int32_t i = 0; i < w->count; ++i)
        root[i] = i;
    for (int32_t i = 0; i < w->count; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t t = inner_twin(w, 3 * w->face_ids[i] + k, 1);
            if (t >= 0)
                unite(root, i, w->local[pz_he_face(t)]);
        }
    int32_t components = 0;
    for (int32_t i = 0; i < w->count; ++i)
        components += find_root(root, i) == i;
    return components;
}

/* Euler characteristic of the opened panel: corner classes - edges + faces. */
static int32_t opened_euler(const panel_walk *w)
{
    int32_t vertices = 0, half_inner = 0, outline = 0;
    for (int32_t c = 0; c < 3 * w->count; ++c) {
        vertices += w->corner_root[c] == c;
        outline += w->on_outline[c];
    }
    half_inner = 3 * w->count - outline;
    return vertices - (outline + half_inner / 2) + w->count;
}

/* Mean length of the panel's face edges (inner edges counted twice: a scale, not a sum). */
static double mean_edge(const panel_walk *w)
{
    double sum = 0;
    for (int32_t i = 0; i < w->count; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t h = 3 * w->face_ids[i] + k;
            sum += distance3(position(w, h), position(w, pz_he_next(h)));
        }
    return w->count ? sum / (3.0 * w->count) : 0;
}

/* The panel as its own mesh (vertices split at pinches only) and its slits as edge flags over its topology
 * (*slits_out NULL when it has none). */
static pz_status panel_mesh(panel_walk *w, pz_mesh **out, uint8_t **slits_out, pz_ctx *ctx)
{
    *out = NULL;
    *slits_out = NULL;
    join_corners(w, 0);
    int32_t vertex_count = 0;
    int32_t *vertex_of = malloc((size_t)3 * w->count * sizeof(int32_t) + 1);
    if (!vertex_of)
        return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
    for (int32_t c = 0; c < 3 * w->count; ++c)
        vertex_of[c] = find_root(w->corner_root, c) == c ? vertex_count++ : -1;
    pz_mesh *mesh = NULL;
    pz_status status = pz_mesh_create(vertex_count, w->count, &mesh, ctx);
    if (status) {
        free(vertex_of);
        return status;
    }
    for (int32_t c = 0; c < 3 * w->count; ++c) {
        int32_t v = vertex_of[find_root(w->corner_root, c)];
        mesh->faces[c] = v;
        memcpy(mesh->positions + 3 * v, w->mesh->positions + 3 * w->topology->faces[3 * w->face_ids[c / 3] + c % 3],
               3 * sizeof(double));
    }
    mesh->unit_scale = w->mesh->unit_scale;
    /* The extra poses too: a panel meets the strain goal only when it does in every pose. */
    int32_t poses = w->mesh->pose_count, garment_vertices = w->mesh->vertex_count;
    if (poses > 0 && w->mesh->poses) {
        mesh->poses = malloc((size_t)poses * (size_t)vertex_count * 3 * sizeof(double) + 1);
        if (!mesh->poses) {
            free(vertex_of);
            pz_mesh_free(&mesh);
            return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
        }
        mesh->pose_count = poses;
        for (int32_t c = 0; c < 3 * w->count; ++c) {
            int32_t v = vertex_of[find_root(w->corner_root, c)];
            int32_t g = w->topology->faces[3 * w->face_ids[c / 3] + c % 3];
            for (int32_t k = 0; k < poses; ++k)
                memcpy(mesh->poses + 3 * ((size_t)k * vertex_count + v),
                       w->mesh->poses + 3 * ((size_t)k * garment_vertices + g), 3 * sizeof(double));
        }
    }
    free(vertex_of);
    int32_t slit_count = 0;
    for (int32_t c = 0; c < 3 * w->count; ++c) {
        int32_t h = 3 * w->face_ids[c / 3] + c % 3;
        slit_count += inner_twin(w, h, 0) >= 0 && w->edge_cut[w->topology->halfedge_edge[h]];
    }
    if (slit_count == 0) { /* most panels: no slit flags, no topology needed here */
        *out = mesh;
        return PZ_OK;
    }
    pz_topology *topology = NULL;
    if ((status = pz_topology_build(mesh, &topology, ctx))) {
        pz_mesh_free(&mesh);
        return status;
    }
    uint8_t *slits = calloc((size_t)topology->edge_count + 1, 1);
    if (!slits) {
        pz_topology_free(&topology);
        pz_mesh_free(&mesh);
        return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
    }
    for (int32_t c = 0; c < 3 * w->count; ++c) {
        int32_t h = 3 * w->face_ids[c / 3] + c % 3;
        if (inner_twin(w, h, 0) >= 0 && w->edge_cut[w->topology->halfedge_edge[h]])
            slits[topology->halfedge_edge[c]] = 1;
    }
    pz_topology_free(&topology);
    *out = mesh;
    *slits_out = slits;
    return PZ_OK;
}

/*
 * The smallest opening angle (degrees) over the pattern's darts: at the tip,
 * between the directions to the two mouth vertices (leg_a[0], leg_b[0]).
 * -1 without darts. A dart that barely opens takes in no fabric: Sec. 3.1
 * asks for "sufficiently large" openings.
 */
static double min_dart_opening(const pz_pattern *pattern, const double *uv)
{
    double smallest = -1;
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = pattern->darts + d;
        if (dart->pair_count < 1)
            continue;
        const double *tip = uv + 2 * dart->tip, *a = uv + 2 * dart->leg_a[0], *b = uv + 2 * dart->leg_b[0];
        double angle = fabs(atan2((a[0] - tip[0]) * (b[1] - tip[1]) - (a[1] - tip[1]) * (b[0] - tip[0]),
                                  (a[0] - tip[0]) * (b[0] - tip[0]) + (a[1] - tip[1]) * (b[1] - tip[1])));
        angle *= 180.0 / 3.14159265358979323846;
        if (smallest < 0 || angle < smallest)
            smallest = angle;
    }
    return smallest;
}

/* The smallest intake over the pattern's darts (metrics of its flattening), -1 without darts. */
static double min_dart_intake(const pz_metrics *metrics)
{
    double smallest = -1;
    for (int32_t d = 0; d < metrics->dart_count; ++d)
        if (smallest < 0 || metrics->darts[d].intake_mm < smallest)
            smallest = metrics->darts[d].intake_mm;
    return smallest;
}

/* The flattened panel's extent across the grain: the warp runs along v (param/param.h), so the extent in u,
 * which must fit the fabric's width when the piece lies grain-true on it. */
static double across_grain(const pz_pattern *pattern, const double *uv)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v) {
        lo = fmin(lo, uv[2 * v]);
        hi = fmax(hi, uv[2 * v]);
    }
    return hi >= lo ? hi - lo : 0;
}

/* The textile set-up of the disk panel (panel_mesh, one-panel pattern, pz_textile_setup) into *kept. */
static pz_status kept_setup(panel_walk *w, const pz_goal_options *options, kept_panel *kept, pz_ctx *ctx)
{
    pz_mesh *mesh = NULL;
    uint8_t *slits = NULL;
    int32_t *zeros = calloc((size_t)w->count + 1, sizeof(int32_t));
    if (!zeros)
        return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
    pz_status status = panel_mesh(w, &mesh, &slits, ctx);
    if (!status)
        status = pz_pattern_build(mesh, zeros, slits, NULL, "panel", &kept->pattern, ctx);
    if (!status) {
        pz_textile_options textile = {0};
        textile.iterations = options->textile_iterations > 0 ? options->textile_iterations
                                                              : DEFAULT_TEXTILE_ITERATIONS;
        textile.threads = 1;
        textile.strain_limit = options->max_strain;
        textile.grain_given = 1;
        memcpy(textile.grain, options->grain, sizeof textile.grain);
        textile.use_poses = kept->pattern->mesh->pose_count > 0;
        status = pz_textile_setup(kept->pattern, &textile, &kept->solver, ctx);
    }
    free(slits);
    pz_mesh_free(&mesh);
    free(zeros);
    return status;
}

/* The kept panel used least recently (a free slot first, unless occupied_only). */
static int kept_least_used(const seg_goal_scratch *scratch, int occupied_only)
{
    int best = -1;
    for (int i = 0; i < KEPT_PANELS; ++i)
        if ((!occupied_only || scratch->kept[i].key) && (best < 0 || scratch->kept[i].used < scratch->kept[best].used))
            best = i;
    return best;
}

static void kept_drop(seg_goal_scratch *scratch, int slot)
{
    scratch->kept_faces -= scratch->kept[slot].face_count;
    kept_clear(&scratch->kept[slot]);
}

/*
 * The panel's flattening set-up: kept from an earlier evaluation of the same panel (the same faces in the
 * same order and the same slits, so the same pattern and solver), else made and kept. The layout evaluates
 * a panel again whenever its neighbours change (its cache is keyed on them: the corners depend on them),
 * and the flattening, which does not, then costs its iterations only (docs/param.md, "Set-up and solve").
 * *kept points into the scratch, or to `local` when the panel is not kept (the caller clears it).
 */
static pz_status kept_flattening(panel_walk *w, const pz_goal_options *options, kept_panel *local,
                                 kept_panel **kept, pz_ctx *ctx)
{
    seg_goal_scratch *scratch = w->scratch;
    const pz_goal_options *seen = &scratch->kept_options;
    if (scratch->kept_mesh != w->mesh || seen->max_strain != options->max_strain ||
        seen->textile_iterations != options->textile_iterations || memcmp(seen->grain, options->grain, sizeof seen->grain)) {
        for (int i = 0; i < KEPT_PANELS; ++i)
            kept_clear(&scratch->kept[i]);
        scratch->kept_faces = 0;
        scratch->kept_mesh = w->mesh;
        scratch->kept_options = *options;
    }
    memset(local, 0, sizeof *local);
    if (!(local->key = malloc((size_t)4 * w->count * sizeof(int32_t))))
        return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
    memcpy(local->key, w->face_ids, (size_t)w->count * sizeof(int32_t));
    local->key_length = local->face_count = w->count;
    for (int32_t c = 0; c < 3 * w->count; ++c) {
        int32_t h = 3 * w->face_ids[c / 3] + c % 3;
        if (inner_twin(w, h, 0) >= 0 && w->edge_cut[w->topology->halfedge_edge[h]])
            local->key[local->key_length++] = c;
    }
    for (int i = 0; i < KEPT_PANELS; ++i) {
        kept_panel *k = &scratch->kept[i];
        if (k->key && k->key_length == local->key_length &&
            !memcmp(k->key, local->key, (size_t)k->key_length * sizeof(int32_t))) {
            k->used = ++scratch->clock;
            free(local->key);
            local->key = NULL;
            *kept = k;
            return PZ_OK;
        }
    }
    *kept = local;
    pz_status status = kept_setup(w, options, local, ctx);
    int64_t room = (int64_t)KEPT_FACE_RATIO * scratch->face_count;
    room = room < KEPT_FACES ? room : KEPT_FACES;
    if (status || local->face_count > room)
        return status;
    /* Keep it, giving up the least recently used panels until it fits. */
    while (scratch->kept_faces + local->face_count > room)
        kept_drop(scratch, kept_least_used(scratch, 1));
    int slot = kept_least_used(scratch, 0);
    kept_drop(scratch, slot);
    scratch->kept[slot] = *local;
    scratch->kept[slot].used = ++scratch->clock;
    scratch->kept_faces += local->face_count;
    memset(local, 0, sizeof *local);
    *kept = &scratch->kept[slot];
    return PZ_OK;
}

/* Flattens the disk panel and measures strain and injectivity into out. */
static pz_status flatten_panel(panel_walk *w, const pz_goal_options *options, pz_goal_result *out, pz_ctx *ctx)
{
    pz_metrics *metrics = NULL;
    double *uv = NULL;
    kept_panel local, *kept = NULL;
    pz_status status = kept_flattening(w, options, &local, &kept, ctx);
    const pz_pattern *pattern = kept ? kept->pattern : NULL;
    if (!status && kept->measured) {
        out->darts = kept->figures.darts;
        out->min_dart_opening_deg = kept->figures.min_dart_opening_deg;
        out->min_dart_intake_mm = kept->figures.min_dart_intake_mm;
        out->across_grain_mm = kept->figures.across_grain_mm;
        out->max_abs_strain = kept->figures.max_abs_strain;
        out->flipped_triangles = kept->figures.flipped_triangles;
        out->boundary_self_intersections = kept->figures.boundary_self_intersections;
        out->failures = pz_goal_judge(options, out);
        return PZ_OK;
    }
    if (!status && !(uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double) + 1)))
        status = pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
    if (!status)
        status = pz_textile_solve(kept->solver, uv, NULL, ctx);
    if (!status)
        status = pz_metrics_compute(pattern, uv, 0, NULL, &metrics, ctx);
    /* The strain is the worst over the rest pose and every extra pose (the flips do not depend on it). */
    double worst_strain = metrics ? metrics->max_abs_strain : 0;
    for (int32_t pose = 1; !status && pose <= pattern->mesh->pose_count; ++pose) {
        pz_metrics *posed = NULL;
        status = pz_metrics_compute(pattern, uv, pose, NULL, &posed, ctx);
        if (!status)
            worst_strain = fmax(worst_strain, posed->max_abs_strain);
        pz_metrics_free(&posed);
    }
    if (!status) {
        out->darts = pattern->dart_count;
        out->min_dart_opening_deg = min_dart_opening(pattern, uv);
        out->min_dart_intake_mm = min_dart_intake(metrics);
        out->across_grain_mm = across_grain(pattern, uv);
        out->max_abs_strain = worst_strain;
        for (int32_t p = 0; p < metrics->panel_count; ++p) {
            out->flipped_triangles += metrics->panels[p].flipped_triangles;
            out->boundary_self_intersections += metrics->panels[p].boundary_self_intersections;
        }
        out->failures = pz_goal_judge(options, out);
        if (kept != &local) {
            kept->measured = 1;
            kept->figures = *out;
        }
    }
    pz_metrics_free(&metrics);
    free(uv);
    if (kept == &local)
        kept_clear(&local);
    return status;
}

/* Frees the walk's own arrays and leaves the scratch as it found it (local and neighbour all -1). */
static void walk_free(panel_walk *w)
{
    for (int32_t i = 0; w->local && i < w->count; ++i)
        w->local[w->face_ids[i]] = -1;
    for (int32_t i = 0; i < w->labelled_count; ++i)
        w->neighbour[w->labelled[i]] = -1;
    free(w->corner_root);
    free(w->on_outline);
}

static double face_area(const pz_mesh *mesh, int32_t f)
{
    const int32_t *v = mesh->faces + 3 * f;
    const double *a = mesh->positions + 3 * v[0], *b = mesh->positions + 3 * v[1], *c = mesh->positions + 3 * v[2];
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* The garment's area (all its faces), measured once per mesh and scratch. */
static double garment_area(panel_walk *w)
{
    seg_goal_scratch *scratch = w->scratch;
    if (scratch->area_mesh != w->mesh) {
        scratch->garment_area = 0;
        for (int32_t f = 0; f < w->mesh->face_count; ++f)
            scratch->garment_area += face_area(w->mesh, f);
        scratch->area_mesh = w->mesh;
    }
    return scratch->garment_area;
}

/* The opened panel's width (pz_piece_width) from its whole outline, or with seams_only from the outline
 * half-edges that have a panel across (seams and slits), over its corner classes (join_corners(w, 1) done). */
static pz_status opened_width(panel_walk *w, int seams_only, double *width, pz_ctx *ctx)
{
    int32_t corners = 3 * w->count, vertex_count = 0;
    int32_t *vertex_of = malloc((size_t)corners * sizeof(int32_t) + 1);
    int32_t *faces = malloc((size_t)corners * sizeof(int32_t) + 1);
    double *points = malloc((size_t)corners * 3 * sizeof(double) + 1);
    uint8_t *source = calloc((size_t)corners + 1, 1);
    pz_status status = PZ_OK;
    if (!vertex_of || !faces || !points || !source)
        status = pz_error(ctx, PZ_ERR_NOMEM, "segment goals: out of memory");
    for (int32_t c = 0; !status && c < corners; ++c)
        if (find_root(w->corner_root, c) == c) {
            memcpy(points + 3 * vertex_count, position(w, 3 * w->face_ids[c / 3] + c % 3), 3 * sizeof(double));
            vertex_of[c] = vertex_count++;
        }
    for (int32_t c = 0; !status && c < corners; ++c) {
        faces[c] = vertex_of[find_root(w->corner_root, c)];
        int32_t h = 3 * w->face_ids[c / 3] + c % 3;
        if (w->on_outline[c] && (!seams_only || w->topology->twin[h] >= 0)) {
            source[vertex_of[find_root(w->corner_root, c)]] = 1;
            source[vertex_of[find_root(w->corner_root, 3 * (c / 3) + (c + 1) % 3)]] = 1;
        }
    }
    if (!status)
        status = pz_piece_width(vertex_count, points, 3, w->count, faces, source, width, ctx);
    free(vertex_of);
    free(faces);
    free(points);
    free(source);
    return status;
}

/*
 * The panel's shape (docs/segment.md, "Piece shapes"): its share of the garment's area and its width. A
 * whole component (no panel across its outline) is as small and narrow as the input made it. Another
 * panel is narrow by the input's own boundary when it reaches at least min_piece_width_mm away from its
 * seams and slits: then what makes it narrow is its border on both sides (a strap, the garment's own
 * narrow part), not a seam the layout cut (a band between a seam and the hem, however long, is narrow
 * by that seam).
 */
static pz_status measure_shape(panel_walk *w, const pz_goal_options *options, pz_goal_result *out, pz_ctx *ctx)
{
    double area = 0, total = garment_area(w);
    int whole = 1;
    for (int32_t i = 0; i < w->count; ++i) {
        area += face_area(w->mesh, w->face_ids[i]);
        for (int k = 0; k < 3; ++k) {
            int32_t t = w->topology->twin[3 * w->face_ids[i] + k];
            whole &= t < 0 || w->local[pz_he_face(t)] >= 0;
        }
    }
    out->area_share = total > 0 ? area / total : -1;
    out->area_forced = out->width_forced = whole;
    if (options->min_piece_width_mm <= 0)
        return PZ_OK;
    pz_status status = opened_width(w, 0, &out->min_width_mm, ctx);
    if (status || whole || !(out->min_width_mm < options->min_piece_width_mm))
        return status;
    double from_seams = 0;  /* twice the farthest reach from the seams */
    status = opened_width(w, 1, &from_seams, ctx);
    out->width_forced = !status && from_seams >= 2 * options->min_piece_width_mm;
    return status;
}

/* Steps 1-3, then 4 when the panel is a disk within the corner bound. */
static pz_status evaluate_walk(panel_walk *w, const pz_goal_options *options, pz_goal_result *out, pz_ctx *ctx)
{
    for (int32_t c = 0; c < 3 * w->count; ++c)
        w->on_outline[c] = inner_twin(w, 3 * w->face_ids[c / 3] + c % 3, 1) < 0;
    join_corners(w, 1);
    int32_t components = opened_components(w);
    int32_t euler = opened_euler(w);
    if (!walk_outline(w, TURN_WINDOW_EDGES * mean_edge(w), &out->boundary_loops, &out->corners))
        return pz_error(ctx, PZ_ERR_NOMEM, "segment goals: out of memory");
    out->disk = components == 1 && out->boundary_loops == 1 && euler == 1;
    pz_status status = measure_shape(w, options, out, ctx);
    if (status)
        return status;
    out->failures = pz_goal_judge(options, out);
    /* A panel that fails on topology or corners must be split anyway: flattening it would only cost. One
     * under a shape goal is flattened all the same: whether it meets S steers the layout as before (a
     * sliver on the way is usually merged again by the removal; docs/segment.md, "Piece shapes"). */
    if ((out->failures & (PZ_GOAL_NOT_DISK | PZ_GOAL_CORNERS)) || options->textile_iterations < 0)
        return PZ_OK;
    return flatten_panel(w, options, out, ctx);
}

pz_status seg_goals(const pz_mesh *mesh, const pz_topology *topology, const uint8_t *edge_cut,
                    const int32_t *face_panel, const int32_t *face_ids, int32_t count, const pz_goal_options *options,
                    seg_goal_scratch *scratch, pz_goal_result *out, pz_ctx *ctx)
{
    if (!mesh || !topology || !edge_cut || !face_ids || !options || !out || !scratch || count <= 0 ||
        scratch->face_count != topology->face_count)
        return pz_error(ctx, PZ_ERR_USAGE, "segment goals: no panel, options or scratch");
    if (options->max_strain < 0 || options->max_corners < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "segment goals: negative strain or corner bound");
    memset(out, 0, sizeof *out);
    out->max_abs_strain = -1;
    out->max_seam_mismatch = -1;
    out->min_dart_opening_deg = -1;
    out->area_share = out->min_width_mm = -1;
    out->across_grain_mm = out->min_dart_intake_mm = -1;
    panel_walk w;
    memset(&w, 0, sizeof w);
    w.mesh = mesh, w.topology = topology, w.edge_cut = edge_cut, w.face_ids = face_ids, w.face_panel = face_panel;
    w.neighbour = scratch->neighbour, w.stack = scratch->stack, w.labelled = scratch->labelled;
    w.scratch = scratch;
    w.corner_root = malloc((size_t)3 * count * sizeof(int32_t));
    w.on_outline = malloc((size_t)3 * count);
    if (!w.corner_root || !w.on_outline) {
        walk_free(&w);
        return pz_error(ctx, PZ_ERR_NOMEM, "segment goals: out of memory");
    }
    w.local = scratch->local;
    for (int32_t i = 0; i < count; ++i, ++w.count) {
        if (face_ids[i] < 0 || face_ids[i] >= topology->face_count || w.local[face_ids[i]] >= 0) {
            walk_free(&w);
            return pz_error(ctx, PZ_ERR_USAGE, "segment goals: face %d out of range or repeated", (int)face_ids[i]);
        }
        w.local[face_ids[i]] = i;
    }
    pz_status status = evaluate_walk(&w, options, out, ctx);
    walk_free(&w);
    return status;
}

pz_status pz_segment_goals(const pz_mesh *mesh, const pz_topology *topology, const uint8_t *edge_cut,
                           const int32_t *face_ids, int32_t count, const pz_goal_options *options,
                           pz_goal_result *out, pz_ctx *ctx)
{
    if (!topology)
        return pz_error(ctx, PZ_ERR_USAGE, "segment goals: no panel or no options");
    seg_goal_scratch *scratch = seg_goal_scratch_new(topology->face_count);
    if (!scratch)
        return pz_error(ctx, PZ_ERR_NOMEM, "segment goals: out of memory");
    pz_status status = seg_goals(mesh, topology, edge_cut, NULL, face_ids, count, options, scratch, out, ctx);
    seg_goal_scratch_free(scratch);
    return status;
}

void pz_goal_options_default(pz_goal_options *goals)
{
    memset(goals, 0, sizeof *goals);
    goals->max_corners = 8;
    goals->max_strain = 0.05;
    goals->grain[2] = 1;
    goals->max_seam_mismatch = 0.005;
    goals->min_piece_width_mm = 40;
    goals->min_piece_area = 0.01;
    goals->min_dart_intake_mm = 6;
}

/* C when the options leave it 0 (the default's). */
static int32_t corner_bound(const pz_goal_options *goals)
{
    if (goals && goals->max_corners > 0)
        return goals->max_corners;
    pz_goal_options defaults;
    pz_goal_options_default(&defaults);
    return defaults.max_corners;
}

unsigned pz_goal_judge(const pz_goal_options *goals, const pz_goal_result *figures)
{
    unsigned failures = figures->failures & PZ_GOAL_VETOED;
    if (!figures->disk)
        failures |= PZ_GOAL_NOT_DISK;
    if (figures->corners > corner_bound(goals))
        failures |= PZ_GOAL_CORNERS;
    if (figures->max_abs_strain >= 0 || isnan(figures->max_abs_strain)) {
        if (!(figures->max_abs_strain <= goals->max_strain))
            failures |= PZ_GOAL_STRAIN;
        if (figures->flipped_triangles > 0 || figures->boundary_self_intersections > 0)
            failures |= PZ_GOAL_NOT_INJECTIVE;
    }
    if (goals->max_seam_mismatch > 0 && !(figures->max_seam_mismatch <= goals->max_seam_mismatch) &&
        !(figures->max_seam_mismatch < 0))
        failures |= PZ_GOAL_SEAM_MISMATCH;
    if (!figures->width_forced && goals->min_piece_width_mm > 0 && figures->min_width_mm >= 0 &&
        figures->min_width_mm < goals->min_piece_width_mm)
        failures |= PZ_GOAL_NARROW;
    if (!figures->area_forced && goals->min_piece_area > 0 && figures->area_share > 0 &&
        figures->area_share < goals->min_piece_area)
        failures |= PZ_GOAL_SMALL;
    if (goals->max_piece_width_mm > 0 && figures->across_grain_mm > goals->max_piece_width_mm)
        failures |= PZ_GOAL_FABRIC_WIDTH;
    if (goals->min_dart_intake_mm > 0 && figures->darts > 0 && figures->min_dart_intake_mm >= 0 &&
        figures->min_dart_intake_mm < goals->min_dart_intake_mm)
        failures |= PZ_GOAL_DART_INTAKE;
    return failures;
}

void pz_goal_describe(const pz_goal_result *result, const pz_goal_options *options, char *buf, size_t size)
{
    if (!buf || size == 0)
        return;
    buf[0] = '\0';
    if (!result || !result->failures) {
        snprintf(buf, size, "ok");
        return;
    }
    int32_t max_corners = corner_bound(options);
    double max_strain = options ? options->max_strain : 0;
    size_t used = 0;
    const char *separator = "";
#define APPEND(...)                                                                 \
    do {                                                                            \
        if (used < size) {                                                          \
            int n = snprintf(buf + used, size - used, "%s", separator);             \
            used += n > 0 ? (size_t)n : 0;                                          \
        }                                                                           \
        if (used < size) {                                                          \
            int n = snprintf(buf + used, size - used, __VA_ARGS__);                 \
            used += n > 0 ? (size_t)n : 0;                                          \
        }                                                                           \
        separator = ", ";                                                           \
    } while (0)
    if (result->failures & PZ_GOAL_NOT_DISK)
        APPEND("not a disk (%d boundary loops)", (int)result->boundary_loops);
    if (result->failures & PZ_GOAL_CORNERS)
        APPEND("%d corners > %d", (int)result->corners, (int)max_corners);
    if (result->failures & PZ_GOAL_STRAIN)
        APPEND("strain %.3g > %g", result->max_abs_strain, max_strain);
    if (result->failures & PZ_GOAL_NOT_INJECTIVE) {
        if (result->flipped_triangles > 0)
            APPEND("%d flipped triangles", (int)result->flipped_triangles);
        else
            APPEND("outline self-intersects");
    }
    if (result->failures & PZ_GOAL_SEAM_MISMATCH)
        APPEND("seam mismatch %.2g%% > %g%%", 100 * result->max_seam_mismatch,
               100 * (options ? options->max_seam_mismatch : 0));
    if (result->failures & PZ_GOAL_NARROW)
        APPEND("%.3g mm wide < %g mm", result->min_width_mm, options ? options->min_piece_width_mm : 0);
    if (result->failures & PZ_GOAL_SMALL)
        APPEND("%.2g%% of the area < %g%%", 100 * result->area_share, 100 * (options ? options->min_piece_area : 0));
    if (result->failures & PZ_GOAL_FABRIC_WIDTH)
        APPEND("%.0f mm across the grain > %g mm of fabric", result->across_grain_mm,
               options ? options->max_piece_width_mm : 0);
    if (result->failures & PZ_GOAL_DART_INTAKE)
        APPEND("dart intake %.2g mm < %g mm", result->min_dart_intake_mm, options ? options->min_dart_intake_mm : 0);
    if (result->failures & PZ_GOAL_VETOED)
        APPEND("failed in the joint flattening");
#undef APPEND
}
