/*
 * tests/param/test_springmass.c -- spring-mass flattening (pz_param_springmass):
 *  - open cylinder and open cone (developable): E_ang and E_len below 1e-6,
 *    no flipped face (wang2002 Table 1 example I is a cone);
 *  - the cone and a trimmed doubly curved patch (a 25-degree cap of the
 *    hemisphere, a disk of the saddle): E_area and E_shape within 1%
 *    (wang2002 Table 1), no flipped face, no boundary self-intersection;
 *  - IISERM: on a 5K-face hemisphere patch (60-degree cap), heap relaxation
 *    does at least 5x less work than full relaxation (a deterministic count of
 *    node moves, global iterations counted as one move per vertex: the clock
 *    is bench_springmass's job); its phase one leaves more energy, and the
 *    global release of phase two ends both within 0.1% of each other; with
 *    the paper's node sweeps alone in phase two (local_release_only) heap
 *    still does 5x less work and ends at most 10% above full relaxation's
 *    energy; multi-path does more work than single path;
 *  - orthotropic: changes the pattern, lowers the orthotropic energy (as
 *    pz_metrics_compute measures it) against the isotropic springs, and the
 *    warp follows the grain given (x or y) near the seed;
 *  - energy map: on a flat sheet with one bump the maximum-energy vertex lies
 *    on the bump; on the hemisphere the cutting line starts on the boundary
 *    and runs inward (boundary distance rising along it) to the pole;
 *  - trial cuts (mccartney2005 Sec. 4): a spherical cap is a dart (sides
 *    splay apart), the saddle a gusset (sides overlap), a nearly flat cap
 *    (8 degrees, opening 0.014% of its area) none;
 *  - energy.svg is written (triangles and the cutting line);
 *  - the bodice halves (heap): injective (no flipped face, no crossing of the
 *    outline: heap's phase one left the back panel with a crossing and 2.4x
 *    full relaxation's energy, now retried with 8 paths), and the remaining
 *    energy within 10% of full relaxation's (IISERM's claim on a garment);
 *  - seam matching: on the bodice halves every pair of facing seam segments
 *    has equal 2D lengths (1e-9, measured on the pattern), the seams' sides
 *    too (pz_metrics_compute), for at most 5% more energy (measured 1%) than
 *    the panels flattened independently, whose facing segments differ by up
 *    to 4% and seams by 0.4% (the check has teeth); a dart slit into a
 *    hemisphere cap off its axis gets equal legs the same way (independently
 *    7.8% apart);
 *  - two panels (hemisphere halves): both flattened without flips, one
 *    record each, the energy map, each panel's E(Phi) and the total are those
 *    of the springs measured on the final pattern; a panel of two separate
 *    triangles is PZ_ERR_DATA with a one-line message and a cleared result.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "generate/generate.h"
#include "param/param.h"
#include "test_meshes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static pz_ctx ctx;

/* ------------------------------------------------------------------ helpers */

static pz_mesh *generate(pz_shape shape, int32_t faces, int open)
{
    pz_generate_options options = {.target_faces = faces, .open = open};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(shape, &options, &mesh, &ctx), ctx);
    return mesh;
}

/* A one-panel pattern of the whole mesh (consumed). */
static pz_pattern *one_panel(pz_mesh *mesh, const char *name)
{
    int32_t *panels = calloc((size_t)mesh->face_count, sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, NULL, name, &pattern, &ctx), ctx);
    free(panels);
    pz_mesh_free(&mesh);
    return pattern;
}

/* A two-panel pattern of `mesh` (kept): panel 1 where the face centroid's coordinate `axis` is negative. */
static pz_pattern *halves(const pz_mesh *mesh, int axis, const char *name)
{
    int32_t *panels = malloc((size_t)mesh->face_count * sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c = 0;
        for (int k = 0; k < 3; ++k)
            c += mesh->positions[3 * mesh->faces[3 * f + k] + axis];
        panels[f] = c < 0;
    }
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, NULL, NULL, name, &pattern, &ctx), ctx);
    free(panels);
    return pattern;
}

/* The faces of `mesh` whose centroid passes keep(); the source is freed. */
static pz_mesh *trim(pz_mesh *mesh, int (*keep)(const double centroid[3]))
{
    int32_t *ids = malloc((size_t)mesh->face_count * sizeof(int32_t)), count = 0;
    REQUIRE(ids, "out of memory");
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                c[d] += mesh->positions[3 * mesh->faces[3 * f + k] + d] / 3;
        if (keep(c))
            ids[count++] = f;
    }
    pz_mesh *out = NULL;
    REQUIRE_OK(pz_mesh_extract(mesh, ids, count, &out, NULL, NULL, &ctx), ctx);
    free(ids);
    pz_mesh_free(&mesh);
    return out;
}

static int cap25(const double c[3]) { return c[2] > 150 * cos(25 * TEST_PI / 180); }
static int cap60(const double c[3]) { return c[2] > 150 * cos(60 * TEST_PI / 180); }
static int saddle_disk(const double c[3]) { return c[0] * c[0] + c[1] * c[1] < 80 * 80; }
static int saddle_wide(const double c[3]) { return c[0] * c[0] + c[1] * c[1] < 150 * 150; }

static double *flatten(const pz_pattern *pattern, const pz_springmass_options *options, pz_springmass_result *result)
{
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    REQUIRE_OK(pz_param_springmass(pattern, options, uv, result, &ctx), ctx);
    return uv;
}

static pz_metrics *measure(const pz_pattern *pattern, const double *uv)
{
    pz_metrics *metrics = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &metrics, &ctx), ctx);
    return metrics;
}

/* ------------------------------------------------------------------ tests */

static void test_developable(pz_shape shape)
{
    pz_pattern *pattern = one_panel(generate(shape, 2000, 1), pz_shape_name(shape));
    pz_springmass_result result;
    double *uv = flatten(pattern, NULL, &result);
    pz_metrics *m = measure(pattern, uv);
    const pz_panel_metrics *pm = &m->panels[0];
    printf("%s: E_len %.3g E_ang %.3g E_area %.3g E_shape %.3g, stop %d after %d sweeps\n", pz_shape_name(shape),
           pm->e_len, pm->e_ang, pm->e_area, pm->e_shape, result.panels[0].stop, result.panels[0].iterations);
    CHECK(pm->e_len < 1e-6, "%s: E_len %g", pz_shape_name(shape), pm->e_len);
    CHECK(pm->e_ang < 1e-6, "%s: E_ang %g", pz_shape_name(shape), pm->e_ang);
    CHECK(pm->e_area < 0.01 && pm->e_shape < 0.01, "%s: E_area %g E_shape %g", pz_shape_name(shape), pm->e_area,
          pm->e_shape);
    CHECK(m->injective, "%s: %d flipped, %d crossings", pz_shape_name(shape), pm->flipped_triangles,
          pm->boundary_self_intersections);
    pz_metrics_free(&m);
    pz_springmass_result_clear(&result);
    free(uv);
    pz_pattern_free(&pattern);
}

static void test_doubly_curved(const char *name, pz_mesh *mesh)
{
    pz_pattern *pattern = one_panel(mesh, name);
    pz_springmass_result result;
    double *uv = flatten(pattern, NULL, &result);
    pz_metrics *m = measure(pattern, uv);
    const pz_panel_metrics *pm = &m->panels[0];
    printf("%s (%d faces): E_area %.4f%% E_shape %.4f%% (result %.4f%% %.4f%%), stop %d after %d sweeps\n", name,
           (int)pattern->mesh->face_count, 100 * pm->e_area, 100 * pm->e_shape, 100 * result.panels[0].e_area,
           100 * result.panels[0].e_shape, result.panels[0].stop, result.panels[0].iterations);
    CHECK(pm->e_area <= 0.01, "%s: E_area %g", name, pm->e_area);
    CHECK(pm->e_shape <= 0.01, "%s: E_shape %g", name, pm->e_shape);
    CHECK(fabs(pm->e_area - result.panels[0].e_area) < 1e-9, "%s: Eq. 4 disagrees with metrics", name);
    CHECK(m->injective, "%s: %d flipped, %d crossings", name, pm->flipped_triangles, pm->boundary_self_intersections);
    pz_metrics_free(&m);
    pz_springmass_result_clear(&result);
    free(uv);
    pz_pattern_free(&pattern);
}

/* Work of a run in node moves: every node relaxation, plus each global
 * iteration counted as one move per vertex (it touches every spring once and
 * solves once with the factored Laplacian; measured in bench_springmass, a
 * global iteration costs about as much as one sweep). */
static double work(const pz_springmass_result *r, int32_t nv)
{
    return (double)r->node_relaxations + (double)r->global_iterations * nv;
}

/* IISERM's claim: heap relaxation at least 5x faster than full relaxation on
 * a 5K-face doubly curved patch, remaining energy within 10% of full's. */
static void test_heap_versus_full(void)
{
    pz_pattern *pattern = one_panel(trim(generate(PZ_SHAPE_HEMISPHERE, 10000, 0), cap60), "hemisphere cap");
    int32_t nv = pattern->mesh->vertex_count;
    pz_springmass_options heap = {0}, full = {.relax = 1}, multi = {.heap_paths = 8};
    pz_springmass_result rh, rf, rm;
    double *uv_heap = flatten(pattern, &heap, &rh);
    double *uv_full = flatten(pattern, &full, &rf);
    double *uv_multi = flatten(pattern, &multi, &rm);
    printf("heap vs full (%d faces): work %.0f / %.0f / multi %.0f node moves (relaxations %lld / %lld / %lld, "
           "global iterations %lld / %lld / %lld), energy %.6g / %.6g / %.6g, time %.0f / %.0f / %.0f ms\n",
           (int)pattern->mesh->face_count, work(&rh, nv), work(&rf, nv), work(&rm, nv), rh.node_relaxations,
           rf.node_relaxations, rm.node_relaxations, rh.global_iterations, rf.global_iterations,
           rm.global_iterations, rh.final_energy, rf.final_energy, rm.final_energy, rh.phase_one_ms + rh.phase_two_ms,
           rf.phase_one_ms + rf.phase_two_ms, rm.phase_one_ms + rm.phase_two_ms);
    CHECK(pattern->mesh->face_count >= 4800 && pattern->mesh->face_count <= 5500, "patch has %d faces",
          (int)pattern->mesh->face_count);
    CHECK(5 * work(&rh, nv) <= work(&rf, nv), "heap %.0f vs full %.0f node moves", work(&rh, nv), work(&rf, nv));
    /* Both end with the same global release to the springs' minimum, which hides phase one: heap's phase one
     * leaves more energy than full's, and phase two takes both to the same end (within 0.1%). The claim
     * proper (heap within 10% of full) is checked below with the node sweeps alone in phase two. */
    CHECK(rh.phase_one_energy > rf.phase_one_energy, "phase one: heap left %g, full %g", rh.phase_one_energy,
          rf.phase_one_energy);
    CHECK(fabs(rh.final_energy - rf.final_energy) <= 1e-3 * rf.final_energy, "remaining energy heap %g full %g",
          rh.final_energy, rf.final_energy);
    CHECK(rm.phase_one_relaxations > rh.phase_one_relaxations, "multi-path %lld vs single %lld",
          rm.phase_one_relaxations, rh.phase_one_relaxations);
    /* the paper's node sweeps alone in phase two (no global release) still meet the claim */
    pz_springmass_options heap_local = {.local_release_only = 1}, full_local = {.relax = 1, .local_release_only = 1};
    pz_springmass_result rhl, rfl;
    double *uv_heap_local = flatten(pattern, &heap_local, &rhl);
    double *uv_full_local = flatten(pattern, &full_local, &rfl);
    printf("  local release only: work %lld / %lld node moves, energy %.6g / %.6g\n", rhl.node_relaxations,
           rfl.node_relaxations, rhl.final_energy, rfl.final_energy);
    CHECK(rhl.global_iterations == 0 && rfl.global_iterations == 0, "local_release_only ran a global release");
    CHECK(5 * rhl.node_relaxations <= rfl.node_relaxations, "local: heap %lld vs full %lld relaxations",
          rhl.node_relaxations, rfl.node_relaxations);
    CHECK(rhl.final_energy <= 1.1 * rfl.final_energy, "local: remaining energy heap %g full %g", rhl.final_energy,
          rfl.final_energy);
    CHECK(rh.final_energy < rhl.final_energy, "the global release left more energy: %g >= %g", rh.final_energy,
          rhl.final_energy);
    pz_metrics *m = measure(pattern, uv_heap);
    CHECK(m->injective, "heap: %d flipped", m->panels[0].flipped_triangles);
    pz_metrics_free(&m);
    pz_springmass_result_clear(&rh);
    pz_springmass_result_clear(&rf);
    pz_springmass_result_clear(&rm);
    pz_springmass_result_clear(&rhl);
    pz_springmass_result_clear(&rfl);
    free(uv_heap);
    free(uv_full);
    free(uv_multi);
    free(uv_heap_local);
    free(uv_full_local);
    pz_pattern_free(&pattern);
}

/* Area-weighted mean angle (degrees) between the warp's 3D image and the grain projected on each face. */
static double warp_grain_angle(const pz_mesh *mesh, const double *uv, const double grain[3])
{
    double sum = 0, weights = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *c = mesh->faces + 3 * f;
        double p3[3][3], p2[3][2];
        for (int k = 0; k < 3; ++k) {
            memcpy(p3[k], mesh->positions + 3 * c[k], sizeof p3[k]);
            memcpy(p2[k], uv + 2 * c[k], sizeof p2[k]);
        }
        double e1u = p2[1][0] - p2[0][0], e1v = p2[1][1] - p2[0][1], e2u = p2[2][0] - p2[0][0],
               e2v = p2[2][1] - p2[0][1], det = e1u * e2v - e2u * e1v, jv[3], n[3];
        double E1[3], E2[3];
        for (int d = 0; d < 3; ++d) {
            E1[d] = p3[1][d] - p3[0][d];
            E2[d] = p3[2][d] - p3[0][d];
            jv[d] = (E2[d] * e1u - E1[d] * e2u) / det;
        }
        n[0] = E1[1] * E2[2] - E1[2] * E2[1];
        n[1] = E1[2] * E2[0] - E1[0] * E2[2];
        n[2] = E1[0] * E2[1] - E1[1] * E2[0];
        double area = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        double gn = (grain[0] * n[0] + grain[1] * n[1] + grain[2] * n[2]) / (area * area);
        double g[3] = {grain[0] - gn * n[0], grain[1] - gn * n[1], grain[2] - gn * n[2]};
        double lg = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), lj = sqrt(jv[0] * jv[0] + jv[1] * jv[1] + jv[2] * jv[2]);
        double cosine = (g[0] * jv[0] + g[1] * jv[1] + g[2] * jv[2]) / (lg * lj);
        sum += area * acos(cosine > 1 ? 1 : cosine < -1 ? -1 : cosine) * 180 / TEST_PI;
        weights += area;
    }
    return sum / weights;
}

static void test_orthotropic(void)
{
    pz_pattern *pattern = one_panel(trim(generate(PZ_SHAPE_SADDLE, 4000, 0), saddle_disk), "saddle disk");
    int32_t nv = pattern->mesh->vertex_count;
    /* no accuracy stop: both run until the energy settles, so each reaches its own minimum */
    pz_springmass_options iso = {.grain_given = 1, .grain = {1, 0, 0}, .accuracy = 1e-9};
    pz_springmass_options ortho = iso, ortho_y = {.orthotropic = 1, .grain_given = 1, .grain = {0, 1, 0}, .accuracy = 1e-9};
    ortho.orthotropic = 1;
    double *uv_iso = flatten(pattern, &iso, NULL), *uv_ortho = flatten(pattern, &ortho, NULL);
    double *uv_y = flatten(pattern, &ortho_y, NULL);
    double moved = 0;
    for (int32_t i = 0; i < 2 * nv; ++i)
        moved = fmax(moved, fabs(uv_iso[i] - uv_ortho[i]));
    pz_metrics *mi = measure(pattern, uv_iso), *mo = measure(pattern, uv_ortho);
    double angle_x = warp_grain_angle(pattern->mesh, uv_ortho, ortho.grain);
    double angle_y = warp_grain_angle(pattern->mesh, uv_y, ortho_y.grain);
    double angle_x_on_y = warp_grain_angle(pattern->mesh, uv_y, ortho.grain);
    printf("orthotropic saddle: max uv change %.3g mm, orthotropic energy %.6g (isotropic springs %.6g), warp-grain "
           "angle %.2f (x) %.2f (y) deg, y pattern against x %.2f deg\n",
           moved, mo->panels[0].orthotropic_energy, mi->panels[0].orthotropic_energy, angle_x, angle_y, angle_x_on_y);
    CHECK(moved > 1e-3, "orthotropic left the pattern unchanged (%g mm)", moved);
    CHECK(mo->panels[0].orthotropic_energy < mi->panels[0].orthotropic_energy, "orthotropic energy %g >= %g",
          mo->panels[0].orthotropic_energy, mi->panels[0].orthotropic_energy);
    CHECK(angle_x < 5 && angle_y < 5, "warp off the grain: %g, %g degrees", angle_x, angle_y);
    CHECK(angle_x_on_y > 60, "the y-grain pattern's warp should be across x: %g degrees", angle_x_on_y);
    CHECK(mo->injective, "orthotropic: %d flipped", mo->panels[0].flipped_triangles);
    pz_metrics_free(&mi);
    pz_metrics_free(&mo);
    free(uv_iso);
    free(uv_ortho);
    free(uv_y);
    pz_pattern_free(&pattern);
}

/* A flat 300 x 300 mm sheet with a Gaussian bump centred at (210, 90). */
static void test_energy_map_bump(void)
{
    pz_mesh *mesh = test_grid(50, 50, TEST_GRID_FLAT, 0, &ctx);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *p = mesh->positions + 3 * v;
        p[0] *= 6;
        p[1] *= 6;
        double r2 = (p[0] - 210) * (p[0] - 210) + (p[1] - 90) * (p[1] - 90);
        p[2] = 25 * exp(-r2 / (2 * 25.0 * 25.0));
    }
    pz_pattern *pattern = one_panel(mesh, "bump");
    pz_springmass_result result;
    double *uv = flatten(pattern, NULL, &result);
    const double *top = pattern->mesh->positions + 3 * result.panels[0].max_energy_vertex;
    double distance = hypot(top[0] - 210, top[1] - 90);
    printf("bump: max energy %.4g at (%.0f, %.0f), %.1f mm from the bump centre\n",
           result.vertex_energy[result.panels[0].max_energy_vertex], top[0], top[1], distance);
    CHECK(distance < 60, "max-energy vertex %g mm from the bump", distance);
    pz_springmass_result_clear(&result);
    free(uv);
    pz_pattern_free(&pattern);
}

static double boundary_distance_along(const pz_pattern *pattern, const pz_springmass_panel *panel, int32_t i)
{
    /* distance to the cap's rim z = 0 on the hemisphere: its height */
    return pattern->mesh->positions[3 * panel->cut_vertices[i] + 2];
}

static void test_cutting_line_and_dart(void)
{
    pz_pattern *pattern = one_panel(generate(PZ_SHAPE_HEMISPHERE, 3000, 0), "hemisphere");
    pz_springmass_options options = {.trial_cut = 1};
    pz_springmass_result result;
    double *uv = flatten(pattern, &options, &result);
    const pz_springmass_panel *panel = &result.panels[0];
    REQUIRE(panel->cut_vertex_count >= 2, "cutting line of %d vertices", (int)panel->cut_vertex_count);
    double rim = boundary_distance_along(pattern, panel, 0);
    /* the line steps to larger graph distance from the rim; the height (the
     * true distance's proxy) may dip by less than an edge on the way */
    int rising = 1;
    for (int32_t i = 1; i < panel->cut_vertex_count; ++i)
        rising &= boundary_distance_along(pattern, panel, i) > boundary_distance_along(pattern, panel, i - 1) - 5;
    /* a crest line (wang2002 Sec. 6.3) follows the slowest descent: on the hemisphere the energy stays
     * above a tenth of the maximum up to the pole, so the line reaches it (a line taking the steepest
     * descent inward stopped at z 78) */
    rising &= boundary_distance_along(pattern, panel, panel->cut_vertex_count - 1) > 120;
    printf("hemisphere: cutting line of %d vertices from z %.1f to z %.1f; trial cut: kind %d, opening %.1f mm^2, "
           "energy %.4g -> %.4g\n",
           (int)panel->cut_vertex_count, rim, boundary_distance_along(pattern, panel, panel->cut_vertex_count - 1),
           panel->cut_kind, panel->cut_opening_mm2, panel->final_energy, panel->cut_energy);
    CHECK(rim < 1e-6, "cutting line starts at z %g, not on the rim", rim);
    CHECK(rising, "cutting line does not run inward");
    CHECK(panel->cut_kind == PZ_SEAM_KIND_DART, "hemisphere cut classified %d, want dart", panel->cut_kind);
    CHECK(panel->cut_energy < panel->final_energy, "the cut did not release energy: %g -> %g", panel->final_energy,
          panel->cut_energy);

    char dir[] = "/tmp/pz_springmass_XXXXXX", path[256];
    REQUIRE(mkdtemp(dir), "mkdtemp");
    snprintf(path, sizeof path, "%s/energy.svg", dir);
    REQUIRE_OK(pz_springmass_write_energy_svg(pattern, uv, &result, path, &ctx), ctx);
    FILE *file = fopen(path, "r");
    REQUIRE(file, "energy.svg missing");
    char line[512];
    int polygons = 0, polylines = 0;
    while (fgets(line, sizeof line, file)) {
        polygons += strncmp(line, "<polygon", 8) == 0;
        polylines += strncmp(line, "<polyline", 9) == 0;
    }
    fclose(file);
    CHECK(polygons == pattern->mesh->face_count && polylines == 1, "energy.svg: %d polygons, %d polylines", polygons,
          polylines);
    remove(path);
    rmdir(dir);
    pz_springmass_result_clear(&result);
    free(uv);
    pz_pattern_free(&pattern);
}

static void test_gusset(void)
{
    pz_pattern *pattern = one_panel(trim(generate(PZ_SHAPE_SADDLE, 3000, 0), saddle_wide), "saddle");
    pz_springmass_options options = {.trial_cut = 1};
    pz_springmass_result result;
    double *uv = flatten(pattern, &options, &result);
    const pz_springmass_panel *panel = &result.panels[0];
    printf("saddle: cutting line of %d vertices; trial cut: kind %d, opening %.1f mm^2\n",
           (int)panel->cut_vertex_count, panel->cut_kind, panel->cut_opening_mm2);
    CHECK(panel->cut_kind == PZ_SEAM_KIND_GUSSET, "saddle cut classified %d, want gusset", panel->cut_kind);
    pz_springmass_result_clear(&result);
    free(uv);
    pz_pattern_free(&pattern);
}

/* A nearly flat cap (8 degrees) opens by 0.014% of its area when cut: no seam ("none", the threshold is
 * 0.1%: docs/springmass.md); a 25-degree cap by 0.5%: a dart. */
static int cap8(const double c[3]) { return c[2] > 150 * cos(8 * TEST_PI / 180); }

static void test_negligible_opening(void)
{
    struct {
        const char *name;
        int (*keep)(const double c[3]);
        pz_seam_kind want;
    } cases[2] = {{"8-degree cap", cap8, PZ_SEAM_KIND_NONE}, {"25-degree cap", cap25, PZ_SEAM_KIND_DART}};
    for (int k = 0; k < 2; ++k) {
        pz_pattern *pattern = one_panel(trim(generate(PZ_SHAPE_HEMISPHERE, 12000, 0), cases[k].keep), cases[k].name);
        pz_springmass_options options = {.trial_cut = 1};
        pz_springmass_result result;
        double *uv = flatten(pattern, &options, &result);
        const pz_springmass_panel *panel = &result.panels[0];
        double area = pz_geom_total_area(pattern->mesh);
        printf("%s: trial cut opening %.3g mm^2 = %.3g%% of %.0f mm^2: kind %d\n", cases[k].name,
               panel->cut_opening_mm2, 100 * panel->cut_opening_mm2 / area, area, panel->cut_kind);
        CHECK(panel->cut_kind == cases[k].want, "%s: kind %d, want %d (opening %g mm^2)", cases[k].name,
              panel->cut_kind, cases[k].want, panel->cut_opening_mm2);
        CHECK(k == 1 || panel->cut_opening_mm2 != 0, "%s: no opening measured at all", cases[k].name);
        pz_springmass_result_clear(&result);
        free(uv);
        pz_pattern_free(&pattern);
    }
}

/*
 * The energies of the result measured here from the pattern alone: a spring
 * on every edge of the cut mesh, rest length its 3D length, energy
 * C/2 (|uv_a - uv_b| - rest)^2 at each end (wang2002 Eq. 1, C = 0.5, Sec. 5);
 * E(Phi) (Eq. 3) sums both ends of every spring. Each vertex of the energy
 * map, each panel's final_energy and the total must agree with these.
 */
static void check_spring_energies(const pz_pattern *pattern, const double *uv, const pz_springmass_result *result,
                                  const char *what)
{
    const double c = 0.5;
    const pz_mesh *mesh = pattern->mesh;
    pz_topology *topology = test_topology(mesh, &ctx);
    double *vertex = calloc((size_t)mesh->vertex_count, sizeof(double));
    double *panel = calloc((size_t)pattern->panel_count, sizeof(double));
    REQUIRE(vertex && panel, "out of memory");
    double total = 0;
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e], a = pz_he_from(topology, h), b = pz_he_to(topology, h);
        const double *pa = mesh->positions + 3 * a, *pb = mesh->positions + 3 * b;
        double rest = sqrt((pa[0] - pb[0]) * (pa[0] - pb[0]) + (pa[1] - pb[1]) * (pa[1] - pb[1]) +
                           (pa[2] - pb[2]) * (pa[2] - pb[2]));
        double stretch = hypot(uv[2 * a] - uv[2 * b], uv[2 * a + 1] - uv[2 * b + 1]) - rest;
        double end = 0.5 * c * stretch * stretch;
        vertex[a] += end, vertex[b] += end, total += 2 * end;
        panel[pattern->face_panel[pz_he_face(h)]] += 2 * end;
    }
    int32_t wrong = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (fabs(result->vertex_energy[v] - vertex[v]) > 1e-9 * (vertex[v] + total / mesh->vertex_count)) {
            if (++wrong <= 3)
                fprintf(stderr, "%s: vertex %d: energy map %.9g, springs %.9g\n", what, (int)v,
                        result->vertex_energy[v], vertex[v]);
        }
    CHECK(result->vertex_count == mesh->vertex_count && wrong == 0, "%s: %d of %d vertices off the springs' energy",
          what, (int)wrong, (int)mesh->vertex_count);
    for (int32_t p = 0; p < pattern->panel_count && p < result->panel_count; ++p)
        CHECK(fabs(result->panels[p].final_energy - panel[p]) <= 1e-9 * panel[p], "%s: panel %d: E %.9g, springs %.9g",
              what, (int)p, result->panels[p].final_energy, panel[p]);
    CHECK(fabs(result->final_energy - total) <= 1e-9 * total, "%s: E %.9g, springs %.9g", what, result->final_energy,
          total);
    printf("%s: E(Phi) %.6g, as the springs give\n", what, total);
    free(vertex);
    free(panel);
    pz_topology_free(&topology);
}

/* Two halves of the hemisphere as two panels: both flattened, each with its own record. */
static void test_two_panels(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_HEMISPHERE, 2000, 0);
    pz_pattern *pattern = halves(mesh, 0, "halves");
    pz_springmass_result result;
    double *uv = flatten(pattern, NULL, &result);
    int finite = 1;
    for (int32_t i = 0; i < 2 * pattern->mesh->vertex_count; ++i)
        finite &= isfinite(uv[i]);
    pz_metrics *m = measure(pattern, uv);
    CHECK(finite, "non-finite pattern coordinates");
    CHECK(result.panel_count == 2 && result.panels[0].panel == 0 && result.panels[1].panel == 1, "panel records");
    for (int p = 0; p < 2 && result.panel_count == 2; ++p) {
        CHECK(result.panels[p].cut_vertex_count >= 2, "panel %d: no cutting line", p);
        CHECK(m->panels[p].flipped_triangles == 0, "panel %d: %d flipped", p, m->panels[p].flipped_triangles);
        CHECK(fabs(result.panels[p].e_area - m->panels[p].e_area) < 1e-9, "panel %d: Eq. 4 disagrees", p);
    }
    check_spring_energies(pattern, uv, &result, "halves");
    pz_metrics_free(&m);
    pz_springmass_result_clear(&result);
    free(uv);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

/* Worst relative length difference of facing segments (side_a[i] side_a[i+1] against side_b[i]
 * side_b[i+1]) over every seam, measured on the pattern. */
static double worst_segment_mismatch(const pz_pattern *pattern, const double *uv)
{
    double worst = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        for (int32_t i = 0; i + 1 < seam->pair_count; ++i) {
            const double *a0 = uv + 2 * seam->side_a[i], *a1 = uv + 2 * seam->side_a[i + 1];
            const double *b0 = uv + 2 * seam->side_b[i], *b1 = uv + 2 * seam->side_b[i + 1];
            double la = hypot(a1[0] - a0[0], a1[1] - a0[1]), lb = hypot(b1[0] - b0[0], b1[1] - b0[1]);
            worst = fmax(worst, fabs(la - lb) / fmax(la, lb));
        }
    }
    return worst;
}

/* The bodice cut into front and back (two seams). Heap relaxation's phase
 * one left the back in a basin with a crossing outline (energy 823 against
 * full relaxation's 341) until panels ending folded or crossed were
 * flattened again with 8 heap paths: the result must be injective and within
 * 10% of full relaxation's energy. With seam matching (the default) every
 * facing pair of seam segments has equal lengths; flattened independently
 * they differ (the check has teeth), and matching costs little energy. */
static void test_bodice(void)
{
    pz_mesh *mesh = generate(PZ_SHAPE_BODICE, 4000, 0);
    pz_pattern *pattern = halves(mesh, 1, "bodice");
    pz_springmass_options alone = {.independent_panels = 1}, full = {.relax = 1};
    pz_springmass_result result, independent, reference;
    double *uv = flatten(pattern, NULL, &result);
    double *uv_alone = flatten(pattern, &alone, &independent);
    double *uv_full = flatten(pattern, &full, &reference);
    pz_metrics *m = measure(pattern, uv), *ma = measure(pattern, uv_alone);
    for (int32_t p = 0; p < m->panel_count; ++p) {
        printf("bodice panel %d (heap): %d flipped, %d boundary crossings, E_area %.4f (independent %.4f)\n", (int)p,
               m->panels[p].flipped_triangles, m->panels[p].boundary_self_intersections, m->panels[p].e_area,
               ma->panels[p].e_area);
        CHECK(m->panels[p].flipped_triangles == 0 && m->panels[p].boundary_self_intersections == 0,
              "bodice panel %d: %d flipped, %d crossings", (int)p, m->panels[p].flipped_triangles,
              m->panels[p].boundary_self_intersections);
    }
    double matched = worst_segment_mismatch(pattern, uv), unmatched = worst_segment_mismatch(pattern, uv_alone);
    printf("bodice: energy heap %.6g (independent %.6g), full %.6g; %d panels retried; facing segments %.3g apart "
           "(independent %.3g), seams %.3g (independent %.3g, result %.3g), %d pairs matched\n",
           result.final_energy, independent.final_energy, reference.final_energy, (int)result.retried_panels, matched,
           unmatched, m->max_seam_mismatch_rel, ma->max_seam_mismatch_rel, result.max_seam_mismatch,
           (int)result.matched_pairs);
    CHECK(result.final_energy <= 1.1 * reference.final_energy, "heap %g vs full %g", result.final_energy,
          reference.final_energy);
    CHECK(independent.final_energy <= 1.1 * reference.final_energy, "independent heap %g vs full %g",
          independent.final_energy, reference.final_energy);
    CHECK(matched < 1e-9 && m->max_seam_mismatch_rel < 1e-9, "matched seams %g apart (segments %g)",
          m->max_seam_mismatch_rel, matched);
    CHECK(fabs(result.max_seam_mismatch - m->max_seam_mismatch_rel) < 1e-9, "result says %g, metrics %g",
          result.max_seam_mismatch, m->max_seam_mismatch_rel);
    CHECK(ma->max_seam_mismatch_rel > 1e-3 && unmatched > 1e-2, "independent seams only %g apart (segments %g)",
          ma->max_seam_mismatch_rel, unmatched);
    CHECK(result.matched_pairs >= 80 && result.unmatched_panels == 0, "%d pairs matched, %d panels not",
          (int)result.matched_pairs, (int)result.unmatched_panels);
    CHECK(result.final_energy <= 1.05 * independent.final_energy, "matching cost energy %g -> %g",
          independent.final_energy, result.final_energy);
    pz_metrics_free(&m);
    pz_metrics_free(&ma);
    pz_springmass_result_clear(&result);
    pz_springmass_result_clear(&independent);
    pz_springmass_result_clear(&reference);
    free(uv);
    free(uv_alone);
    free(uv_full);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

/* Edge flags (over pz_topology_build(mesh) edges) of a slit from the boundary vertex nearest `from` that
 * has an inner neighbour, each step to the inner neighbour nearest `toward`, `steps` edges long. */
static uint8_t *slit(const pz_mesh *mesh, const double from[3], const double toward[3], int steps)
{
    pz_topology *t = test_topology(mesh, &ctx);
    uint8_t *flags = calloc((size_t)t->edge_count + 1, 1);
    REQUIRE(flags, "out of memory");
    int32_t v = -1;
    double best = INFINITY;
    for (int32_t u = 0; u < mesh->vertex_count; ++u) {
        const double *p = mesh->positions + 3 * u;
        double d = hypot(hypot(p[0] - from[0], p[1] - from[1]), p[2] - from[2]);
        int32_t ring[64], n = pz_topology_vertex_ring(t, u, ring, 64), inner = 0;
        for (int32_t k = 0; k < n && k < 64; ++k)
            inner += !t->vertex_on_boundary[ring[k]];
        if (t->vertex_on_boundary[u] && inner > 0 && d < best) {
            best = d;
            v = u;
        }
    }
    for (int step = 0; step < steps; ++step) {
        int32_t ring[64], n = pz_topology_vertex_ring(t, v, ring, 64), next = -1;
        best = INFINITY;
        for (int32_t k = 0; k < n && k < 64; ++k) {
            const double *p = mesh->positions + 3 * ring[k];
            double d = hypot(hypot(p[0] - toward[0], p[1] - toward[1]), p[2] - toward[2]);
            if (!t->vertex_on_boundary[ring[k]] && d < best) {
                best = d;
                next = ring[k];
            }
        }
        REQUIRE(next >= 0, "slit: no way on from vertex %d", (int)v);
        for (int32_t e = 0; e < t->edge_count; ++e) {
            int32_t h = t->edge_halfedge[2 * e], a = pz_he_from(t, h), b = pz_he_to(t, h);
            if ((a == v && b == next) || (a == next && b == v))
                flags[e] = 1;
        }
        v = next;
    }
    pz_topology_free(&t);
    return flags;
}

/* A dart: a slit from the rim of a hemisphere cap toward a point off its axis (so the two legs are not
 * mirror images); with seam matching its legs come out equally long. */
static void test_dart(void)
{
    pz_mesh *mesh = trim(generate(PZ_SHAPE_HEMISPHERE, 6000, 0), cap60);
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double from[3] = {hi[0], 0, lo[2]}, toward[3] = {0.2 * hi[0], 0.5 * hi[1], hi[2]};
    uint8_t *cuts = slit(mesh, from, toward, 12);
    int32_t *panels = calloc((size_t)mesh->face_count, sizeof(int32_t));
    REQUIRE(panels, "out of memory");
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, panels, cuts, NULL, "dart", &pattern, &ctx), ctx);
    REQUIRE(pattern->dart_count == 1 && pattern->panel_count == 1, "%d darts", pattern->dart_count);
    pz_springmass_options alone = {.independent_panels = 1};
    pz_springmass_result result, independent;
    double *uv = flatten(pattern, NULL, &result), *uv_alone = flatten(pattern, &alone, &independent);
    pz_metrics *m = measure(pattern, uv), *ma = measure(pattern, uv_alone);
    printf("dart (%d pairs): legs %.2f / %.2f mm, %.3g apart (independent %.3g); energy %.6g (independent %.6g), "
           "%d flipped\n",
           (int)pattern->darts[0].pair_count, m->darts[0].leg_a_mm, m->darts[0].leg_b_mm, m->darts[0].mismatch_rel,
           ma->darts[0].mismatch_rel, result.final_energy, independent.final_energy, m->panels[0].flipped_triangles);
    CHECK(m->darts[0].mismatch_rel < 1e-9, "dart legs %g apart", m->darts[0].mismatch_rel);
    CHECK(ma->darts[0].mismatch_rel > 1e-4, "independent dart legs only %g apart", ma->darts[0].mismatch_rel);
    CHECK(m->injective, "dart: %d flipped, %d crossings", m->panels[0].flipped_triangles,
          m->panels[0].boundary_self_intersections);
    pz_metrics_free(&m);
    pz_metrics_free(&ma);
    pz_springmass_result_clear(&result);
    pz_springmass_result_clear(&independent);
    free(uv);
    free(uv_alone);
    free(cuts);
    free(panels);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

/* A panel of two separate triangles cannot be reached from one seed: PZ_ERR_DATA, nothing leaked. */
static void test_disconnected_panel(void)
{
    static const double positions[] = {0, 0, 0, 10, 0, 0, 0, 10, 0, 50, 0, 0, 60, 0, 0, 50, 10, 0};
    static const int32_t faces[] = {0, 1, 2, 3, 4, 5};
    pz_pattern pattern = {0};
    int32_t face_panel[2] = {0, 0}, origin[6] = {0, 1, 2, 3, 4, 5};
    pattern.mesh = test_mesh_from(6, positions, 2, faces, &ctx);
    pattern.panel_count = 1;
    pattern.face_panel = face_panel;
    pattern.vertex_origin = origin;
    double uv[12];
    pz_springmass_result result;
    pz_status status = pz_param_springmass(&pattern, NULL, uv, &result, &ctx);
    CHECK(status == PZ_ERR_DATA, "status %d", (int)status);
    CHECK(strstr(ctx.error, "springmass") && !strchr(ctx.error, '\n'), "message: %s", ctx.error);
    CHECK(result.vertex_energy == NULL && result.panels == NULL, "result not cleared");
    pz_mesh_free(&pattern.mesh);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_developable(PZ_SHAPE_CYLINDER);
    test_developable(PZ_SHAPE_CONE);
    test_doubly_curved("hemisphere 25-degree cap", trim(generate(PZ_SHAPE_HEMISPHERE, 11000, 0), cap25));
    test_doubly_curved("saddle disk", trim(generate(PZ_SHAPE_SADDLE, 4000, 0), saddle_disk));
    test_heap_versus_full();
    test_orthotropic();
    test_energy_map_bump();
    test_cutting_line_and_dart();
    test_gusset();
    test_negligible_opening();
    test_two_panels();
    test_bodice();
    test_dart();
    test_disconnected_panel();
    return test_finish();
}
