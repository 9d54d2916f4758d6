/*
 * tests/param/test_true_patterns.c -- our flat pieces against real sewing
 * patterns (the test, and the UV panel rule on real files).
 *
 * Three garments of ../shared/data/garments carry their true pattern as `vt`
 * (INVENTORY.md "GT pattern"). For each: `--panels uv` (pz_pattern_panels_from_uv
 * + pz_pattern_build) must find the true panels, and every UV cut of the file
 * must be a cut of our pattern (and nothing else, since every true island is a
 * disk). Every panel is then flattened with the textile back-end (default
 * options) and with LSCM, and each piece is compared with the true piece:
 *
 *   error = sqrt( sum_c w_c |R p_c + t - q_c|^2 / A ) / sqrt(A)
 *
 * over the face corners c of the piece (p ours, q true, in mm), w_c = the true
 * face area / 3, A = the true piece area: the area-weighted RMS corner
 * distance over the square root of the piece area, after the best rigid
 * motion (R, t). R may be a reflection (some true islands are mirrored; the
 * better of proper and improper Procrustes is taken). 2D weighted Procrustes
 * has a closed form: with centred p, q, a = sum w p.q and b = sum w p x q, the
 * best rotation leaves sum w (|p|^2 + |q|^2) - 2 sqrt(a^2 + b^2).
 *
 * The true pattern's scale. diffavatar-tshirt: "UV normalised by 0.0087" means
 * vt = 0.0087 x (position in cm), so 1 vt unit = 10 / 0.0087 mm; checked by
 * the median ratio of true 2D to 3D edge length (must be ~1). The other two
 * files document no exact factor ("about 6.5x" for the skirt): their true
 * pattern is scaled by one global factor, the one that makes the median edge
 * ratio exactly 1 (never per piece, so a piece that is smaller in the true
 * pattern than on the garment still counts against us).
 *
 * The figure the tests hold us to (the issue: libigl's ARAP is off by 1.4 %
 * and LSCM by 1.5 % on the tshirt; textile with the default options 1.21 %)
 * is asserted for the tshirt; the shirt's and
 * skirt's tables are printed with only sound properties asserted. A second
 * table column gives the similarity error (a uniform scale per piece also
 * fitted): the pure shape difference, for reading the rigid figure.
 *
 * The skirt: INVENTORY.md says "3 panels" but its own UV atlas has 4 islands,
 * and the same skirt's CLO3D DXF (parafashion-skirt-pattern.dxf) has 4 blocks,
 * each "QUANTITY: 1", of areas 75,060 / 79,110 / 79,110 / 75,060 mm^2 -- the
 * 4 UV islands' areas in vt units (mm). 4 is right; the regression test below
 * pins the 4 islands, their pairwise equal areas and their darts.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "io/io.h"
#include "param/param.h"
#include "test_util.h"

#include <math.h>
#include <sys/stat.h>

static pz_ctx ctx;

/* One rigid comparison of a piece: rigid and similarity errors. */
typedef struct piece_error {
    double rigid, similar;
    int mirrored;
    double area_mm2;
} piece_error;

/* Weighted 2D Procrustes of points p onto q (n points, weights w). */
static piece_error compare_piece(const double *p, const double *q, const double *w, int32_t n)
{
    double weight = 0, pc[2] = {0, 0}, qc[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i) {
        weight += w[i];
        for (int k = 0; k < 2; ++k) {
            pc[k] += w[i] * p[2 * i + k];
            qc[k] += w[i] * q[2 * i + k];
        }
    }
    for (int k = 0; k < 2; ++k) {
        pc[k] /= weight;
        qc[k] /= weight;
    }
    double pp = 0, qq = 0, a = 0, b = 0, a_mirror = 0, b_mirror = 0;
    for (int32_t i = 0; i < n; ++i) {
        double px = p[2 * i] - pc[0], py = p[2 * i + 1] - pc[1];
        double qx = q[2 * i] - qc[0], qy = q[2 * i + 1] - qc[1];
        pp += w[i] * (px * px + py * py);
        qq += w[i] * (qx * qx + qy * qy);
        a += w[i] * (px * qx + py * qy);
        b += w[i] * (px * qy - py * qx);
        /* the mirror image (-px, py) of p */
        a_mirror += w[i] * (-px * qx + py * qy);
        b_mirror += w[i] * (-px * qy - py * qx);
    }
    double best = sqrt(a * a + b * b), best_mirror = sqrt(a_mirror * a_mirror + b_mirror * b_mirror);
    piece_error e = {0};
    e.mirrored = best_mirror > best;
    double fit = fmax(best, best_mirror);
    double rigid_residual = fmax(pp + qq - 2 * fit, 0), similar_residual = fmax(qq - fit * fit / pp, 0);
    e.area_mm2 = weight;
    e.rigid = sqrt(rigid_residual / weight) / sqrt(weight);
    e.similar = sqrt(similar_residual / weight) / sqrt(weight);
    return e;
}

/* A garment with a true pattern, read and cut into its UV panels. */
typedef struct garment_case {
    const char *name;
    pz_mesh *mesh;               /* mm */
    pz_pattern *pattern;
    double *true_corner_uv;      /* 3 F x 2, mm */
    double *true_face_area;      /* F, mm^2 */
    double true_scale;           /* mm per vt unit */
    double median_edge_ratio;    /* true 2D / 3D edge length, with true_scale */
} garment_case;

static void garment_case_free(garment_case *g)
{
    pz_pattern_free(&g->pattern);
    pz_mesh_free(&g->mesh);
    free(g->true_corner_uv);
    free(g->true_face_area);
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Ratios of vt edge length to 3D edge length (mm) over every face edge, sorted. */
static double *edge_ratios(const pz_mesh *mesh, double vt_scale, int32_t *count)
{
    double *ratio = malloc((size_t)mesh->face_count * 3 * sizeof(double));
    REQUIRE(ratio, "out of memory");
    int32_t n = 0;
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c) {
        int32_t d = c - c % 3 + (c % 3 + 1) % 3;
        const double *x = mesh->positions + 3 * mesh->faces[c], *y = mesh->positions + 3 * mesh->faces[d];
        const double *s = mesh->uvs + 2 * mesh->corner_uvs[c], *t = mesh->uvs + 2 * mesh->corner_uvs[d];
        double l3 = sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2]));
        double l2 = vt_scale * sqrt((s[0] - t[0]) * (s[0] - t[0]) + (s[1] - t[1]) * (s[1] - t[1]));
        if (l3 > 0)
            ratio[n++] = l2 / l3;
    }
    qsort(ratio, (size_t)n, sizeof(double), compare_doubles);
    *count = n;
    return ratio;
}

/*
 * Reads garments/<file>, converts to mm (`units`), cuts it into its UV panels
 * and computes the true corner positions. vt_scale_mm > 0: the documented mm
 * per vt unit; 0: the global factor that makes the median edge ratio 1.
 * Returns 0 (and prints why) when the file is not there.
 */
static int garment_case_load(garment_case *g, const char *dir, const char *file, pz_units units, double vt_scale_mm)
{
    char path[4096];
    struct stat info;
    memset(g, 0, sizeof *g);
    g->name = file;
    snprintf(path, sizeof path, "%s/garments/%s", dir, file);
    if (stat(path, &info) != 0) {
        char why[4200];
        snprintf(why, sizeof why, "%s missing", path);
        test_skip_part(why);
        return 0;
    }
    REQUIRE_OK(pz_mesh_read(path, &g->mesh, &ctx), ctx);
    pz_mesh_to_mm(g->mesh, units, NULL);
    pz_mesh *mesh = g->mesh;
    REQUIRE(mesh->corner_uvs, "%s has vt", file);
    int32_t n = 0;
    double *ratio = edge_ratios(mesh, 1.0, &n);
    g->true_scale = vt_scale_mm > 0 ? vt_scale_mm : 1.0 / ratio[n / 2];
    free(ratio);
    ratio = edge_ratios(mesh, g->true_scale, &n);
    g->median_edge_ratio = ratio[n / 2];
    printf("%s: true scale %.6g mm per vt unit; true/3D edge ratio p1 %.3f p5 %.3f median %.3f p95 %.3f p99 %.3f\n",
           file, g->true_scale, ratio[n / 100], ratio[n / 20], ratio[n / 2], ratio[n - 1 - n / 20],
           ratio[n - 1 - n / 100]);
    free(ratio);

    int32_t *panels = malloc((size_t)mesh->face_count * sizeof(int32_t)), panel_count = 0;
    uint8_t *extra = NULL;
    REQUIRE(panels, "out of memory");
    REQUIRE_OK(pz_pattern_panels_from_uv(mesh, panels, &panel_count, &extra, &ctx), ctx);
    REQUIRE_OK(pz_pattern_build(mesh, panels, extra, NULL, path, &g->pattern, &ctx), ctx);
    free(panels);
    free(extra);

    g->true_corner_uv = malloc((size_t)mesh->face_count * 6 * sizeof(double));
    g->true_face_area = malloc((size_t)mesh->face_count * sizeof(double));
    REQUIRE(g->true_corner_uv && g->true_face_area, "out of memory");
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        for (int k = 0; k < 2; ++k)
            g->true_corner_uv[2 * c + k] = g->true_scale * mesh->uvs[2 * mesh->corner_uvs[c] + k];
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const double *a = g->true_corner_uv + 6 * f, *b = a + 2, *d = a + 4;
        g->true_face_area[f] = fabs((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0])) / 2;
    }
    return 1;
}

/* 1 when the two sides of garment half-edge h (interior) carry the same UVs at both ends. */
static int same_uv_across(const pz_mesh *mesh, const pz_topology *t, int32_t h)
{
    int32_t o = t->twin[h];
    int32_t ends[2][2] = {{mesh->corner_uvs[h], mesh->corner_uvs[pz_he_next(o)]},
                          {mesh->corner_uvs[pz_he_next(h)], mesh->corner_uvs[o]}};
    for (int i = 0; i < 2; ++i) {
        const double *x = mesh->uvs + 2 * ends[i][0], *y = mesh->uvs + 2 * ends[i][1];
        if (x[0] != y[0] || x[1] != y[1])
            return 0;
    }
    return 1;
}

/*
 * Our cuts are exactly the true pattern's: a garment edge is cut in the
 * pattern (its half-edge lost its twin in the cut mesh) iff its two sides
 * have different true UVs. Counts the true cuts we miss and our extra cuts.
 */
static void check_cuts(const garment_case *g, int32_t *missed, int32_t *extra, int32_t *true_cuts)
{
    pz_topology *t = NULL, *ct = NULL;
    REQUIRE_OK(pz_topology_build(g->mesh, &t, &ctx), ctx);
    REQUIRE_OK(pz_topology_build(g->pattern->mesh, &ct, &ctx), ctx);
    *missed = *extra = *true_cuts = 0;
    for (int32_t h = 0; h < 3 * g->mesh->face_count; ++h) {
        if (t->twin[h] < 0 || t->twin[h] < h)
            continue; /* garment boundary, or the edge was seen from its other side */
        int true_cut = !same_uv_across(g->mesh, t, h), our_cut = ct->twin[h] < 0;
        *true_cuts += true_cut;
        *missed += true_cut && !our_cut;
        *extra += our_cut && !true_cut;
    }
    pz_topology_free(&ct);
    pz_topology_free(&t);
}

/* Compares every piece of `uv` (cut-mesh vertices x 2) with the true pattern; fills errors[panel]. */
static void compare_pattern(const garment_case *g, const double *uv, piece_error *errors)
{
    const pz_pattern *pattern = g->pattern;
    int32_t nf = g->mesh->face_count;
    double *ours = malloc((size_t)nf * 6 * sizeof(double)), *truth = malloc((size_t)nf * 6 * sizeof(double));
    double *weight = malloc((size_t)nf * 3 * sizeof(double));
    REQUIRE(ours && truth && weight, "out of memory");
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        int32_t n = 0;
        for (int32_t f = 0; f < nf; ++f) {
            if (pattern->face_panel[f] != p)
                continue;
            for (int k = 0; k < 3; ++k, ++n) {
                int32_t v = pattern->mesh->faces[3 * f + k];
                ours[2 * n] = uv[2 * v];
                ours[2 * n + 1] = uv[2 * v + 1];
                truth[2 * n] = g->true_corner_uv[6 * f + 2 * k];
                truth[2 * n + 1] = g->true_corner_uv[6 * f + 2 * k + 1];
                weight[n] = g->true_face_area[f] / 3;
            }
        }
        errors[p] = compare_piece(ours, truth, weight, n);
    }
    free(ours);
    free(truth);
    free(weight);
}

/* Area-weighted mean of the per-piece rigid errors. */
static double mean_error(const piece_error *errors, int32_t count, int similar)
{
    double sum = 0, area = 0;
    for (int32_t p = 0; p < count; ++p) {
        sum += errors[p].area_mm2 * (similar ? errors[p].similar : errors[p].rigid);
        area += errors[p].area_mm2;
    }
    return sum / area;
}

typedef struct garment_errors {
    double textile, lscm;                 /* area-weighted mean rigid error */
    double textile_similar, lscm_similar;
    double textile_worst, lscm_worst;     /* worst piece, rigid */
    double textile_piece[8];              /* rigid error of the first 8 pieces */
} garment_errors;

/* Flattens with textile (`options`) and LSCM, prints the per-piece table, returns the summary. */
static garment_errors flatten_and_compare(const garment_case *g, const pz_textile_options *options, const char *label)
{
    const pz_pattern *pattern = g->pattern;
    int32_t nv = pattern->mesh->vertex_count, np = pattern->panel_count;
    double *uv_textile = malloc((size_t)nv * 2 * sizeof(double)), *uv_lscm = malloc((size_t)nv * 2 * sizeof(double));
    piece_error *textile = calloc((size_t)np, sizeof *textile), *lscm = calloc((size_t)np, sizeof *lscm);
    REQUIRE(uv_textile && uv_lscm && textile && lscm, "out of memory");
    pz_textile_result result = {0};
    REQUIRE_OK(pz_param_textile(pattern, options, uv_textile, &result, &ctx), ctx);
    REQUIRE_OK(pz_param_lscm_pattern(pattern, NULL, uv_lscm, &ctx), ctx);
    compare_pattern(g, uv_textile, textile);
    compare_pattern(g, uv_lscm, lscm);

    double *area_3d = malloc((size_t)g->mesh->face_count * sizeof(double));
    REQUIRE(area_3d, "out of memory");
    pz_geom_face_areas(g->mesh, area_3d);
    printf("%s: textile (%s) %d iterations; per piece (error = area-weighted RMS corner distance / sqrt(area), "
           "%%):\n", g->name, label, result.iterations_run);
    printf("  piece  faces  true mm^2  3D mm^2  mirrored  textile rigid  textile similar  lscm rigid  lscm similar\n");
    garment_errors e = {0};
    for (int32_t p = 0; p < np; ++p) {
        int32_t faces = 0;
        double piece_3d = 0;
        for (int32_t f = 0; f < g->mesh->face_count; ++f)
            if (pattern->face_panel[f] == p) {
                ++faces;
                piece_3d += area_3d[f];
            }
        printf("  %5d  %5d  %9.0f  %7.0f  %8s  %13.2f  %15.2f  %10.2f  %12.2f\n", (int)p, (int)faces,
               textile[p].area_mm2, piece_3d, textile[p].mirrored ? "yes" : "no", 100 * textile[p].rigid,
               100 * textile[p].similar, 100 * lscm[p].rigid, 100 * lscm[p].similar);
        e.textile_worst = fmax(e.textile_worst, textile[p].rigid);
        if (p < 8)
            e.textile_piece[p] = textile[p].rigid;
        e.lscm_worst = fmax(e.lscm_worst, lscm[p].rigid);
    }
    e.textile = mean_error(textile, np, 0);
    e.lscm = mean_error(lscm, np, 0);
    e.textile_similar = mean_error(textile, np, 1);
    e.lscm_similar = mean_error(lscm, np, 1);
    printf("  all (area-weighted)                          %13.2f  %15.2f  %10.2f  %12.2f\n", 100 * e.textile,
           100 * e.textile_similar, 100 * e.lscm, 100 * e.lscm_similar);
    free(area_3d);
    free(uv_textile);
    free(uv_lscm);
    free(textile);
    free(lscm);
    return e;
}

/* The comparison itself, checked on a synthetic case: a piece against its own mirror image, moved. */
static void test_procrustes(void)
{
    enum { n = 5 };
    double p[2 * n] = {0, 0, 3, 0, 3, 1, 1, 2, 0, 1}, q[2 * n], w[n] = {1, 2, 1, 1, 3};
    double angle = 0.7, c = cos(angle), s = sin(angle);
    for (int i = 0; i < n; ++i) {
        double x = -p[2 * i], y = p[2 * i + 1]; /* mirrored */
        q[2 * i] = c * x - s * y + 10;
        q[2 * i + 1] = s * x + c * y - 4;
    }
    piece_error e = compare_piece(p, q, w, n);
    CHECK(e.mirrored && e.rigid < 1e-9, "a moved mirror image matches: rigid %g mirrored %d", e.rigid, e.mirrored);
    for (int i = 0; i < 2 * n; ++i)
        q[i] *= 1.1;
    e = compare_piece(p, q, w, n);
    CHECK(e.rigid > 1e-2 && e.similar < 1e-9, "a scaled copy: rigid %g > 0, similar %g = 0", e.rigid, e.similar);
    q[0] += 0.5;
    e = compare_piece(p, q, w, n);
    CHECK(e.similar > 1e-3, "a moved corner is a shape difference: %g", e.similar);
}

/*
 * The test: the tshirt's 4 true panels and cuts, and our pieces at
 * least as close to the true ones as libigl's ARAP (1.4 %) and LSCM (1.5 %).
 */
static void test_tshirt(const char *dir)
{
    garment_case g;
    if (!garment_case_load(&g, dir, "diffavatar-tshirt.obj", PZ_UNITS_CM, 10.0 / 0.0087))
        return;
    CHECK(fabs(g.median_edge_ratio - 1) < 0.02, "tshirt: documented vt scale gives median edge ratio %g",
          g.median_edge_ratio);
    CHECK(g.pattern->panel_count == 4, "tshirt: 4 true panels, got %d", (int)g.pattern->panel_count);
    int32_t missed, extra, true_cuts;
    check_cuts(&g, &missed, &extra, &true_cuts);
    printf("tshirt: %d true cut edges, %d missed, %d extra\n", (int)true_cuts, (int)missed, (int)extra);
    CHECK(missed == 0 && extra == 0, "tshirt: our cuts are the true ones (%d missed, %d extra)", (int)missed,
          (int)extra);
    pz_textile_options defaults = {0}, no_seam_term = {.weights_given = 1, .weight_stretch = 5, .weight_rigid = 1,
                                                       .weight_dart = 5, .weight_seam = 0};
    garment_errors e = flatten_and_compare(&g, &defaults, "default options");
    garment_errors free_seams = flatten_and_compare(&g, &no_seam_term, "weights 5,1,5,0: no seam term");
    /*
     * libigl's ARAP flattens each piece on its own; our textile does too once
     * the seam term (pietroni2022 Eq. 8) is off. With the default weights the
     * seam term makes the side, shoulder and underarm seams mirror images,
     * while the four sleeve caps, convex where the armholes are concave
     * (reflection residual 8 % of their length at the LSCM start), are held
     * to equal length only (param/textile.c, classify_seams): measured 1.21 %
     * (1.43 % when every seam was forced into a reflection).
     */
    CHECK(free_seams.textile <= 0.014, "tshirt: textile without seam term %.2f %% <= libigl ARAP's 1.4 %%",
          100 * free_seams.textile);
    CHECK(e.textile <= 0.014, "tshirt: textile (defaults) %.2f %% <= libigl ARAP's 1.4 %%", 100 * e.textile);
    /* Pieces 0 and 1 are the sleeves, 2 and 3 the front and back (numbered by first face). */
    CHECK(e.textile_piece[2] <= 0.01 && e.textile_piece[3] <= 0.01,
          "tshirt: textile body pieces %.2f %%, %.2f %% <= 1 %%",
          100 * e.textile_piece[2], 100 * e.textile_piece[3]);
    CHECK(e.lscm <= 0.015 + 0.001, "tshirt: LSCM error %.2f %% <= libigl LSCM's 1.5 %%", 100 * e.lscm);
    garment_case_free(&g);
}

/* The shirt (5 panels): figures reported; the panel count and cuts asserted. */
static void test_shirt(const char *dir)
{
    garment_case g;
    if (!garment_case_load(&g, dir, "diffavatar-shirt.obj", PZ_UNITS_CM, 0))
        return;
    CHECK(g.pattern->panel_count == 5, "shirt: 5 true panels, got %d", (int)g.pattern->panel_count);
    int32_t missed, extra, true_cuts;
    check_cuts(&g, &missed, &extra, &true_cuts);
    printf("shirt: %d true cut edges, %d missed, %d extra\n", (int)true_cuts, (int)missed, (int)extra);
    CHECK(missed == 0 && extra == 0, "shirt: our cuts are the true ones (%d missed, %d extra)", (int)missed,
          (int)extra);
    pz_textile_options defaults = {0};
    garment_errors e = flatten_and_compare(&g, &defaults, "default options");
    CHECK(e.lscm < 0.10, "shirt: LSCM pieces are the true shapes within 10 %% (%.2f %%)", 100 * e.lscm);
    garment_case_free(&g);
}

/*
 * The skirt: 4 UV islands (see the file comment: the CLO3D DXF has 4 pieces
 * too), in two mirror pairs of equal true area, each with two darts sewn in
 * 3D and open in the pattern (UV cuts inside the island, ending at a tip).
 */
static void test_skirt(const char *dir)
{
    garment_case g;
    if (!garment_case_load(&g, dir, "parafashion-skirt.obj", PZ_UNITS_AUTO, 0))
        return;
    const pz_pattern *pattern = g.pattern;
    REQUIRE(pattern->panel_count == 4, "skirt: 4 UV islands (the DXF's 4 pieces), got %d", (int)pattern->panel_count);
    double area[4] = {0};
    int32_t faces[4] = {0};
    for (int32_t f = 0; f < g.mesh->face_count; ++f) {
        area[pattern->face_panel[f]] += g.true_face_area[f];
        ++faces[pattern->face_panel[f]];
    }
    printf("skirt: pieces of %d, %d, %d, %d faces; true areas %.0f, %.0f, %.0f, %.0f mm^2\n", (int)faces[0],
           (int)faces[1], (int)faces[2], (int)faces[3], area[0], area[1], area[2], area[3]);
    /* Islands are numbered by first face: fronts 0 and 3, backs 1 and 2 (the DXF's pairs). */
    CHECK(fabs(area[0] - area[3]) < 1e-3 * area[0] && fabs(area[1] - area[2]) < 1e-3 * area[1],
          "skirt: two pairs of equal pieces (%g %g, %g %g)", area[0], area[3], area[1], area[2]);
    CHECK(fabs(area[1] / area[0] - 79110.0 / 75060.0) < 0.01, "skirt: back/front area ratio %g as in the DXF",
          area[1] / area[0]);
    int32_t missed, extra, true_cuts;
    check_cuts(&g, &missed, &extra, &true_cuts);
    printf("skirt: %d true cut edges, %d missed, %d extra\n", (int)true_cuts, (int)missed, (int)extra);
    CHECK(missed == 0 && extra == 0, "skirt: our cuts are the true ones (%d missed, %d extra)", (int)missed,
          (int)extra);
    /* Two darts per piece: the UV cuts inside each island are slits ending at a tip. */
    int32_t darts[4] = {0};
    for (int32_t d = 0; d < pattern->dart_count; ++d)
        ++darts[pattern->darts[d].panel];
    CHECK(pattern->dart_count == 8 && darts[0] == 2 && darts[1] == 2 && darts[2] == 2 && darts[3] == 2,
          "skirt: 2 darts per piece (%d %d %d %d)", (int)darts[0], (int)darts[1], (int)darts[2], (int)darts[3]);
    CHECK(pattern->seam_count == 4, "skirt: 4 seams (2 side, centre front, centre back), got %d",
          (int)pattern->seam_count);
    /* In the true pattern every dart is a symmetric V: legs of equal length, mirror images about the tip. */
    double *true_uv = calloc((size_t)pattern->mesh->vertex_count * 2, sizeof(double));
    REQUIRE(true_uv, "out of memory");
    for (int32_t c = 0; c < 3 * g.mesh->face_count; ++c)
        memcpy(true_uv + 2 * pattern->mesh->faces[c], g.true_corner_uv + 2 * c, 2 * sizeof(double));
    pz_metrics *m = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, true_uv, 0, NULL, &m, &ctx), ctx);
    double worst_leg = 0, worst_symmetry = 0;
    for (int32_t d = 0; d < m->dart_count; ++d) {
        worst_leg = fmax(worst_leg, m->darts[d].mismatch_rel);
        worst_symmetry = fmax(worst_symmetry, m->darts[d].symmetry_residual_mm);
    }
    printf("skirt true pattern: darts' legs differ by at most %.2f %%, symmetry residual at most %.2f mm\n",
           100 * worst_leg, worst_symmetry);
    CHECK(worst_leg < 0.01 && worst_symmetry < 1, "skirt: true darts are symmetric (%g, %g mm)", worst_leg,
          worst_symmetry);
    pz_metrics_free(&m);
    free(true_uv);
    pz_textile_options defaults = {0};
    flatten_and_compare(&g, &defaults, "default options");
    garment_case_free(&g);
}

int main(void)
{
    pz_ctx_init(&ctx);
    test_procrustes();
    const char *dir = test_shared_data();
    if (!dir) {
        test_skip_part("the true patterns (no ../shared/data)");
        return test_finish();
    }
    test_tshirt(dir);
    test_shirt(dir);
    test_skirt(dir);
    return test_finish();
}
