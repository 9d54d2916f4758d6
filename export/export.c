/*
 * export/export.c -- export options, the per-seam allowance file, and the
 * table of the files `flatten` and `run` write.
 *
 * Allowance file (--allowances FILE, docs/export.md): one seam per line,
 * `PANEL_A PANEL_B MM` (panel ids, either order; every seam joining the two
 * panels, or a panel and itself, gets MM), `#` starts a comment, blank lines
 * are skipped. A later line for the same pair wins.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "export/export.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void pz_export_options_default(pz_export_options *options)
{
    memset(options, 0, sizeof *options);
    options->seam_allowance_mm = 10;
    options->hem_allowance_mm = -1;   /* follows the seam allowance */
    options->notch_spacing_mm = 100;
    options->notch_depth_mm = 5;
    options->paper = "a4";
    options->fabric_width_mm = 1500;
    options->gap_mm = 5;
}

/* The next whitespace-separated token of a line (NUL-terminated in place); 0 at the end. */
static int next_token(char **cursor, char **token)
{
    char *c = *cursor;
    while (*c && isspace((unsigned char)*c))
        ++c;
    if (!*c)
        return 0;
    *token = c;
    while (*c && !isspace((unsigned char)*c))
        ++c;
    if (*c)
        *c++ = '\0';
    *cursor = c;
    return 1;
}

static int parse_panel(const char *token, int32_t panel_count, int32_t *panel)
{
    char *end = NULL;
    errno = 0;
    long value = strtol(token, &end, 10);
    if (end == token || *end || errno == ERANGE || value < 0 || value >= panel_count)
        return 0;
    *panel = (int32_t)value;
    return 1;
}

/* Applies one `A B MM` line; PZ_ERR_DATA naming path and line otherwise. */
static pz_status apply_line(char *line, const char *path, int32_t number, const pz_pattern *pattern,
                            double *allowances, pz_ctx *ctx)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    char *cursor = line, *tokens[4] = {NULL, NULL, NULL, NULL};
    int count = 0;
    while (count < 4 && next_token(&cursor, &tokens[count]))
        ++count;
    if (count == 0)
        return PZ_OK;
    if (count != 3)
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: expected `PANEL_A PANEL_B MM`", path, (int)number);
    int32_t a, b;
    if (!parse_panel(tokens[0], pattern->panel_count, &a) || !parse_panel(tokens[1], pattern->panel_count, &b))
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: panel ids must be whole numbers below %d", path, (int)number,
                        (int)pattern->panel_count);
    char *end = NULL;
    errno = 0;
    double mm = strtod(tokens[2], &end);
    if (end == tokens[2] || *end || errno == ERANGE || !isfinite(mm))
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: '%s' is not a number (mm)", path, (int)number, tokens[2]);
    if (mm < 0)
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: negative allowance %g mm", path, (int)number, mm);
    int found = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        if ((seam->panel_a == a && seam->panel_b == b) || (seam->panel_a == b && seam->panel_b == a)) {
            allowances[s] = mm;
            found = 1;
        }
    }
    if (!found)
        return pz_error(ctx, PZ_ERR_DATA, "%s: line %d: no seam joins panels %d and %d", path, (int)number, (int)a,
                        (int)b);
    return PZ_OK;
}

pz_status pz_export_read_allowances(const char *path, const pz_pattern *pattern, double **out, pz_ctx *ctx)
{
    *out = NULL;
    FILE *file = NULL;
    pz_status opened = pz_input_open(path, &file, ctx);
    if (opened != PZ_OK)
        return opened;
    double *allowances = malloc((size_t)pattern->seam_count * sizeof(double) + 1);
    if (!allowances) {
        fclose(file);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", path);
    }
    for (int32_t s = 0; s < pattern->seam_count; ++s)
        allowances[s] = -1;
    char *line = NULL;
    size_t capacity = 0;
    int32_t number = 0;
    pz_status status = PZ_OK;
    while (status == PZ_OK && getline(&line, &capacity, file) >= 0)
        status = apply_line(line, path, ++number, pattern, allowances, ctx);
    if (status == PZ_OK && ferror(file))
        status = pz_error(ctx, PZ_ERR_OPEN, "%s: cannot read: %s", path, strerror(errno));
    free(line);
    fclose(file);
    if (status != PZ_OK) {
        free(allowances);
        return status;
    }
    *out = allowances;
    return PZ_OK;
}

/* Only writers that work are listed: the command writes exactly these. */
const pz_export_file pz_export_files[] = {
    {"pattern.svg", pz_export_write_svg, 0},
    {"pattern.dxf", pz_export_write_dxf, 0},
    {"pattern.pdf", pz_export_write_pdf, 1},
    {"pattern-tiled.pdf", pz_export_write_pdf_tiled, 1},
    {"marker.svg", pz_export_write_marker_svg, 0},
    {"garment.glb", pz_export_write_glb, 1},
    {"report.html", pz_export_write_report_html, 0},
};
const int pz_export_file_count = (int)(sizeof pz_export_files / sizeof pz_export_files[0]);
