/*
 * tests/export/test_run_patterns.c -- the patterns `panelize run` makes of
 * every garment in ../shared/data/garments, through the export's checks and
 * through real readers (skipped, exit 77, without the shared data).
 *
 * For each garment, `panelize run GARMENT -o DIR` (the whole pipeline, its
 * default options: 10 mm allowances, 100 mm notch spacing, 1500 mm fabric,
 * 5 mm gap) must succeed; then
 *  - the pieces: DIR/garment.obj read back (panels from its `g panel_K`
 *    groups, seams and darts found again, uv = its vt), pz_pieces_build with
 *    the same options, the run's mirror map and names (report.json's
 *    panels[].mirror_panel and name, so the "Cut 2 mirrored" pairs and the
 *    DXF's block names are the run's): on
 *    every piece the cut line lies at the allowance outside the sew line
 *    (within 0.1 mm) and never crosses itself, every notch pair sits at equal
 *    arc length within 0.5 mm (measured from the notches' positions; end
 *    notches at the seam's ends), and every seam's labels are on the drawn
 *    pieces that stand for its sides (piece_checks.h);
 *  - the marker of those pieces: no overlap (closer than the gap), inside
 *    the fabric width, rotations 0/180, pairs as pairs (marker_checks.h);
 *  - the run's own files, by real readers: pattern.dxf by ezdxf (audit
 *    clean; every block one of our pieces, a closed cut and sew polyline of
 *    our vertex count and perimeter: check_dxf.py --subset, since the run
 *    leaves out the second piece of a mirrored pair), garment.glb by the
 *    Khronos validator (zero errors), pattern.svg and marker.svg by
 *    rsvg-convert, both PDFs by pdfinfo and pdftoppm, report.html by an XML
 *    parser. A reader that is not installed skips its check (the
 *    test exits 77), except with CI=true, where it fails.
 * One line per garment (pieces, notches, marker, seconds of the run).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "export_fixtures.h"
#include "marker_checks.h"
#include "piece_checks.h"
#include "readers.h"

static pz_ctx ctx;
static int32_t hidden_seams_seen;   /* seams reaching a hidden mirrored piece, over every garment */

typedef struct readers {
    int ezdxf, validator, rsvg, poppler, python;
    const char *source, *validator_dir;
} readers;

static void check_files(const readers *r, const char *dir, const pz_pieces *pieces, const char *name)
{
    char command[4000], log[1200], expected[1200], what[200];
    snprintf(log, sizeof log, "%s/reader.log", dir);
    if (r->ezdxf) {
        snprintf(expected, sizeof expected, "%s/expected.txt", dir);
        piece_checks_write_dxf_expected(pieces, expected);
        snprintf(command, sizeof command, "/usr/bin/python3 '%s/tests/export/check_dxf.py' --subset '%s/pattern.dxf' '%s'",
                 r->source, dir, expected);
        snprintf(what, sizeof what, "%s: pattern.dxf by ezdxf", name);
        reader_passes(command, log, what);
    }
    if (r->validator) {
        snprintf(command, sizeof command, "node '%s/tests/export/validate_glb.js' '%s' '%s/garment.glb'", r->source,
                 r->validator_dir, dir);
        snprintf(what, sizeof what, "%s: garment.glb by the Khronos validator", name);
        reader_passes(command, log, what);
    }
    if (r->rsvg) {
        snprintf(command, sizeof command,
                 "rsvg-convert -w 400 -o '%s/pattern.png' '%s/pattern.svg' && "
                 "rsvg-convert -w 400 -o '%s/marker.png' '%s/marker.svg'",
                 dir, dir, dir, dir);
        snprintf(what, sizeof what, "%s: pattern.svg and marker.svg by rsvg-convert", name);
        reader_passes(command, log, what);
    }
    if (r->poppler) {
        /* The sheet whole at 2 dpi (it can be metres wide: past 5000 mm it is cut into several 1:1 pages,
         * each within the PDF's 14400 pt page limit, export/pdf.c), the tiled PDF's cover and first tiles at 20. */
        snprintf(command, sizeof command,
                 "pdfinfo '%s/pattern.pdf' | awk '/^Pages:/ {p = $2} /^Page size:/ {w = $3; h = $5} "
                 "END {exit !(p >= 1 && w <= 14400 && h <= 14400)}' && pdftoppm -r 2 '%s/pattern.pdf' '%s/sheet' && "
                 "pdfinfo '%s/pattern-tiled.pdf' | grep -q '^Pages: *[0-9]' && "
                 "pdftoppm -r 20 -f 1 -l 3 '%s/pattern-tiled.pdf' '%s/tile'",
                 dir, dir, dir, dir, dir, dir);
        snprintf(what, sizeof what, "%s: pattern.pdf and pattern-tiled.pdf by pdfinfo and pdftoppm", name);
        reader_passes(command, log, what);
    }
    if (r->python) {
        snprintf(command, sizeof command,
                 "/usr/bin/python3 -c 'import sys, xml.etree.ElementTree as e; e.parse(sys.argv[1])' '%s/report.html'",
                 dir);
        snprintf(what, sizeof what, "%s: report.html is well-formed", name);
        reader_passes(command, log, what);
    }
}

/* The run's mirror map: report.json's panels[p].mirror_panel (panel_count values, -1 where none), or NULL when the
 * run found no symmetry; and the pieces' names (panels[p].name: the DXF's blocks are named after them), into
 * names (panel_count strings, freed with free_names). */
static int32_t *report_panel_mirror(const char *dir, int32_t panel_count, const char *what, char ***names)
{
    char path[700];
    snprintf(path, sizeof path, "%s/report.json", dir);
    FILE *file = fopen(path, "rb");
    REQUIRE(file, "%s: no %s", what, path);
    fseek(file, 0, SEEK_END);
    long size = ftell(file);
    rewind(file);
    char *text = malloc((size_t)size + 1);
    REQUIRE(text && fread(text, 1, (size_t)size, file) == (size_t)size, "%s: cannot read %s", what, path);
    fclose(file);
    text[size] = '\0';
    cJSON *root = cJSON_Parse(text);
    free(text);
    REQUIRE(root, "%s: %s is not JSON", what, path);
    cJSON *panels = cJSON_GetObjectItem(root, "panels");
    REQUIRE(cJSON_GetArraySize(panels) == panel_count, "%s: report.json has %d panels, garment.obj %d", what,
            cJSON_GetArraySize(panels), (int)panel_count);
    int32_t *mirror = malloc(((size_t)panel_count + 1) * sizeof(int32_t)), found = 0;
    *names = calloc((size_t)panel_count + 1, sizeof(char *));
    REQUIRE(mirror && *names, "out of memory");
    for (int32_t p = 0; p < panel_count; ++p) {
        cJSON *value = cJSON_GetObjectItem(cJSON_GetArrayItem(panels, p), "mirror_panel");
        mirror[p] = cJSON_IsNumber(value) ? value->valueint : -1;
        found += mirror[p] >= 0;
        cJSON *name = cJSON_GetObjectItem(cJSON_GetArrayItem(panels, p), "name");
        REQUIRE(cJSON_IsString(name) && ((*names)[p] = strdup(name->valuestring)), "%s: panel %d has no name", what,
                (int)p);
    }
    cJSON_Delete(root);
    if (found == 0) {
        free(mirror);
        return NULL;
    }
    return mirror;
}

static void check_garment(const readers *r, const char *data, const char *file)
{
    char garment[1024], dir[600], command[2400], obj[700];
    snprintf(garment, sizeof garment, "%s/garments/%s", data, file);
    snprintf(dir, sizeof dir, "%s/%s", test_temp_dir, file);
    snprintf(command, sizeof command, "'%s' run '%s' -o '%s' --quiet > '%s.log' 2>&1", getenv("PZ_BINARY"), garment,
             dir, dir);
    double start = pz_seconds();
    int status = reader_run(command);
    double seconds = pz_seconds() - start;
    CHECK(status == 0, "%s: panelize run exits %d (%s.log)", file, status, dir);
    if (status != 0)
        return;
    snprintf(obj, sizeof obj, "%s/garment.obj", dir);
    fixture f;
    REQUIRE(fixture_from_pattern_obj(&f, obj), "%s: the run's pattern cannot be read back", file);
    pz_export_options options;
    pz_export_options_default(&options);
    pz_pieces *pieces = NULL;
    char **names = NULL;
    int32_t *panel_mirror = report_panel_mirror(dir, f.pattern->panel_count, file, &names);
    REQUIRE_OK(pz_pieces_build(f.pattern, f.uv, &options, panel_mirror, (const char *const *)names, &pieces, &ctx),
               ctx);
    check_piece_cuts(f.pattern, pieces, file);
    notch_pair_stats pairs = check_notch_pairs(f.pattern, pieces, f.uv, options.notch_spacing_mm, file);
    int32_t hidden_seams = check_drawn_labels(f.pattern, pieces, file);
    hidden_seams_seen += hidden_seams;
    int32_t doubled = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        doubled += pieces->pieces[p].cut_quantity == 2;
    pz_marker *marker = NULL;
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    check_marker(pieces, marker, &options);
    int32_t notches = 0, cut_points = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        notches += pieces->pieces[p].notch_count;
        cut_points += pieces->pieces[p].cut_count;
    }
    printf("%-26s %3d pieces (%d cut twice), %3d seams (%d on a hidden piece), %d darts, %4d notches (pairs within "
           "%.1e mm, ends at the corners within %.1e mm, sides differ by up to %.2f mm), %5d cut points, marker "
           "%.0f mm %.1f %%, run %.1f s\n",
           file, (int)pieces->piece_count, (int)doubled, (int)f.pattern->seam_count, (int)hidden_seams,
           (int)f.pattern->dart_count, (int)notches, pairs.interior, pairs.end_corner, pairs.end_mismatch,
           (int)cut_points, marker->length_mm, 100 * marker->efficiency, seconds);
    check_files(r, dir, pieces, file);
    pz_marker_free(&marker);
    pz_pieces_free(&pieces);
    free(panel_mirror);
    for (int32_t p = 0; p < f.pattern->panel_count; ++p)
        free(names[p]);
    free(names);
    fixture_free(&f);
}

int main(void)
{
    ctx.quiet = 1;
    const char *data = test_shared_data();
    if (!data)
        test_skip("no shared data (PZ_SHARED_DATA)");
    REQUIRE(getenv("PZ_BINARY") && getenv("PZ_SOURCE_DIR"), "PZ_BINARY and PZ_SOURCE_DIR must be set (ctest does)");
    readers r = {0};
    r.source = getenv("PZ_SOURCE_DIR");
    char validator_dir[700], probe[800];
    snprintf(validator_dir, sizeof validator_dir, "%s/.tools/node_modules/gltf-validator", r.source);
    r.validator_dir = validator_dir;
    snprintf(probe, sizeof probe, "command -v node && test -d '%s'", validator_dir);
    r.ezdxf = reader_available("/usr/bin/python3 -c 'import ezdxf'", "ezdxf (/usr/bin/python3)");
    r.validator = reader_available(probe, "the Khronos glTF validator (node, .tools)");
    r.rsvg = reader_available("command -v rsvg-convert", "rsvg-convert");
    r.poppler = reader_available("command -v pdfinfo && command -v pdftoppm", "poppler (pdfinfo, pdftoppm)");
    r.python = reader_available("command -v /usr/bin/python3", "/usr/bin/python3");
    test_temp_dir_create("pz_run_patterns");
    for (size_t g = 0; g < sizeof fixture_garments / sizeof fixture_garments[0]; ++g)
        check_garment(&r, data, fixture_garments[g].file);
    /* The wetsuit's run keeps mirrored pairs: the labels of hidden pieces' seams must have been checked. */
    CHECK(hidden_seams_seen > 0, "no run made a \"Cut 2 mirrored\" pair: the mirrored-label check ran on nothing");
    if (!getenv("PZ_KEEP_OUTPUT"))
        test_remove_tree(test_temp_dir);
    else
        printf("output kept in %s\n", test_temp_dir);
    return test_finish();
}
