/*
 * tests/export/test_html.c -- report.html (pz_export_write_report_html) for a
 * bodice in 4 panels with a report shaped like report.json's:
 *  - one <html>, one strain <svg> with its legend, one colour-bin path per
 *    strain level used (the faces' strains land in the right bins: the
 *    number of triangles per fill colour matches a recount);
 *  - every panel listed in the panels table (its name and one row each),
 *    every seam one row, summary, marker and timings tables present;
 *  - self-contained: no "http", no src= or href= attributes, no <script>;
 *  - well-formed XML (parsed by /usr/bin/python3's ElementTree when there),
 *    text escaped, non-UTF-8 bytes replaced;
 *  - a stream that cannot be written gives PZ_ERR_CREATE.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "fixture_export_b.h"
#include "readers.h"

#include <stdio.h>
#include <unistd.h>

static pz_ctx ctx;

static int count_of(const char *text, const char *needle)
{
    int count = 0;
    for (const char *at = text; (at = strstr(at, needle)); at += strlen(needle))
        ++count;
    return count;
}

/* A report with the shape of report.json (panels, seams, summary, timings) from the metrics. */
static cJSON *make_report(const pz_metrics *metrics, const pz_marker *marker)
{
    cJSON *root = cJSON_CreateObject();
    cJSON *panels = cJSON_AddArrayToObject(root, "panels");
    for (int32_t p = 0; p < metrics->panel_count; ++p) {
        cJSON *panel = cJSON_CreateObject();
        char name[32];
        snprintf(name, sizeof name, "panel_%d", (int)p);
        cJSON_AddNumberToObject(panel, "id", p);
        cJSON_AddStringToObject(panel, "name", name);
        cJSON_AddNumberToObject(panel, "faces", metrics->panels[p].face_count);
        cJSON *warp = cJSON_AddObjectToObject(panel, "strain_warp");
        cJSON_AddNumberToObject(warp, "max", metrics->panels[p].strain_warp.max);
        cJSON_AddNumberToObject(warp, "p95", metrics->panels[p].strain_warp.p95);
        cJSON_AddNumberToObject(warp, "mean", metrics->panels[p].strain_warp.mean);
        cJSON_AddItemToArray(panels, panel);
    }
    cJSON *seams = cJSON_AddArrayToObject(root, "seams");
    for (int32_t s = 0; s < metrics->seam_count; ++s) {
        cJSON *seam = cJSON_CreateObject();
        int pair[2] = {metrics->seams[s].panel_a, metrics->seams[s].panel_b};
        cJSON_AddNumberToObject(seam, "id", s);
        cJSON_AddItemToObject(seam, "panels", cJSON_CreateIntArray(pair, 2));
        cJSON_AddNumberToObject(seam, "mismatch_rel", metrics->seams[s].mismatch_rel);
        cJSON_AddItemToArray(seams, seam);
    }
    cJSON *summary = cJSON_AddObjectToObject(root, "summary");
    cJSON_AddNumberToObject(summary, "panel_count", metrics->panel_count);
    cJSON_AddBoolToObject(summary, "injective", metrics->injective);
    cJSON_AddStringToObject(summary, "note", "a <b> & \"c\"");
    cJSON_AddStringToObject(summary, "latin1", "d\xe9" "coup\xe9"); /* not UTF-8: shown with '?' */
    cJSON *timings = cJSON_AddObjectToObject(root, "timings_ms");
    cJSON_AddNumberToObject(timings, "flatten", 12.5);
    cJSON_AddNumberToObject(timings, "total", 40.25);
    cJSON_AddItemToObject(root, "marker", pz_marker_report_json(marker));
    return root;
}

static char *write_html(const pz_export_inputs *inputs, const char *path)
{
    FILE *file = fopen(path, "w");
    REQUIRE(file, "cannot write %s", path);
    REQUIRE_OK(pz_export_write_report_html(file, inputs, "report.html", &ctx), ctx);
    long size = ftell(file);
    REQUIRE(fclose(file) == 0, "close");
    char *text = malloc((size_t)size + 1);
    file = fopen(path, "r");
    REQUIRE(text && file && fread(text, 1, (size_t)size, file) == (size_t)size, "read back");
    fclose(file);
    text[size] = 0;
    return text;
}

/* Number of 'M' commands (triangles) in the d of the path filled with `colour`. */
static int triangles_of_colour(const char *html, const char *colour)
{
    char needle[64];
    snprintf(needle, sizeof needle, "<path fill=\"%s\" stroke=\"%s\" stroke-width=\"0.2\" d=\"", colour, colour);
    const char *at = strstr(html, needle);
    if (!at)
        return 0;
    at += strlen(needle);
    int count = 0;
    for (; *at && *at != '"'; ++at)
        count += *at == 'M';
    return count;
}

static void test_bodice(void)
{
    fixture_pattern fixture;
    fixture_pattern_build(&fixture, 3000, 4);
    fixture_pattern_export(&fixture);
    cJSON *report = make_report(fixture.metrics, fixture.marker);
    pz_export_inputs inputs = fixture.inputs;
    inputs.report = report;
    char dir[] = "/tmp/pz_html_XXXXXX";
    REQUIRE(mkdtemp(dir), "mkdtemp");
    char path[256], command[600];
    snprintf(path, sizeof path, "%s/report.html", dir);
    char *html = write_html(&inputs, path);

    CHECK(count_of(html, "<html") == 1 && count_of(html, "</html>") == 1, "one html element");
    CHECK(count_of(html, "<svg") == 1 && strstr(html, "(compression)") && strstr(html, "(tension)"),
          "strain svg and legend");
    CHECK(!strstr(html, "http") && !strstr(html, "src=") && !strstr(html, "href=") && !strstr(html, "<script"),
          "not self-contained");
    for (int32_t p = 0; p < fixture.pattern->panel_count; ++p) {
        char name[48];
        snprintf(name, sizeof name, "<td>panel_%d</td>", (int)p);
        CHECK(strstr(html, name) != NULL, "panel %d not in the table", (int)p);
    }
    const char *panels = strstr(html, "<table id=\"panels\">"), *seams = strstr(html, "<table id=\"seams\">");
    REQUIRE(panels && seams, "panels or seams table missing");
    const char *panels_end = strstr(panels, "</table>"), *seams_end = strstr(seams, "</table>");
    int panel_rows = 0, seam_rows = 0;
    for (const char *at = panels; (at = strstr(at, "<tr><td>")) && at < panels_end; ++at)
        ++panel_rows;
    for (const char *at = seams; (at = strstr(at, "<tr><td>")) && at < seams_end; ++at)
        ++seam_rows;
    CHECK(panel_rows == fixture.pattern->panel_count, "%d panel rows", panel_rows);
    CHECK(seam_rows == fixture.metrics->seam_count, "%d seam rows", seam_rows);
    CHECK(strstr(html, "<th>strain_warp p95</th>") != NULL, "nested columns");
    CHECK(strstr(html, "id=\"summary\"") && strstr(html, "id=\"timings\"") && strstr(html, "id=\"marker\""),
          "summary, timings or marker table missing");
    CHECK(strstr(html, "a &lt;b&gt; &amp; &quot;c&quot;") != NULL, "text not escaped");
    CHECK(strstr(html, "d?coup?") != NULL, "Latin-1 text not replaced");

    /* Every face is drawn once, in its strain's colour: white (the middle bin) holds the near-zero ones. */
    int drawn = 0;
    for (const char *at = html; (at = strstr(at, "stroke-width=\"0.2\" d=\"")); ++at) {
        for (at += 22; *at != '"'; ++at)
            drawn += *at == 'M';
    }
    CHECK(drawn == fixture.pattern->mesh->face_count, "%d triangles drawn of %d", drawn,
          (int)fixture.pattern->mesh->face_count);
    double scale = 0.01;
    for (int32_t f = 0; f < fixture.metrics->face_count; ++f)
        scale = fmax(scale, fmax(fabs(fixture.metrics->strain_warp[f]), fabs(fixture.metrics->strain_weft[f])));
    int near_zero = 0;
    for (int32_t f = 0; f < fixture.metrics->face_count; ++f) {
        double w = fixture.metrics->strain_warp[f], t = fixture.metrics->strain_weft[f];
        near_zero += fabs(fabs(w) >= fabs(t) ? w : t) < scale / 32.0;
    }
    CHECK(triangles_of_colour(html, "#ffffff") == near_zero, "white triangles %d, near-zero faces %d",
          triangles_of_colour(html, "#ffffff"), near_zero);
    printf("report.html: %zu bytes, %d triangles, strain scale %.3f\n", strlen(html), drawn, scale);

    if (reader_available("command -v /usr/bin/python3", "/usr/bin/python3")) {
        snprintf(command, sizeof command,
                 "/usr/bin/python3 -c 'import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])' %s", path);
        CHECK(system(command) == 0, "report.html is not well-formed XML");
    }
    free(html);

    FILE *full = fopen("/dev/full", "w");
    if (full) {
        setvbuf(full, NULL, _IONBF, 0);
        CHECK(pz_export_write_report_html(full, &inputs, "full.html", &ctx) == PZ_ERR_CREATE, "%s", ctx.error);
        fclose(full);
    }
    snprintf(command, sizeof command, "rm -rf %s", dir);
    CHECK(system(command) == 0, "cleanup");
    cJSON_Delete(report);
    fixture_pattern_free(&fixture);
}

int main(void)
{
    test_bodice();
    return test_finish();
}
