/*
 * pipeline/write.c -- pz_result_write: the files of a result, all or nothing.
 *
 * Every file is written, complete and synced, into a hidden folder beside
 * the target, which is swapped in whole when all are written (folder.c): a
 * reader sees the earlier set or the new one, never a mix, and a failed or
 * cancelled write leaves the earlier set as it was. Order: garment.obj, the export table's files
 * but report.html (export/), layout.obj, energy.svg, report.json (built then,
 * so it can carry the write timing of the files before it), report.html
 * (which shows report.json).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "pipeline/internal.h"

#include <errno.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---------------------------------------------------------------- output names */

/* The short names of pz_outputs_parse and the files they stand for. */
static const struct {
    const char *word;
    const char *file;
    unsigned bit;
} output_names[] = {
    {"obj", "garment.obj", PZ_OUTPUT_GARMENT_OBJ},     {"svg", "pattern.svg", PZ_OUTPUT_SVG},
    {"pdf", "pattern.pdf", PZ_OUTPUT_PDF},             {"tiled", "pattern-tiled.pdf", PZ_OUTPUT_TILED_PDF},
    {"dxf", "pattern.dxf", PZ_OUTPUT_DXF},             {"marker", "marker.svg", PZ_OUTPUT_MARKER},
    {"glb", "garment.glb", PZ_OUTPUT_GLB},             {"json", "report.json", PZ_OUTPUT_REPORT_JSON},
    {"html", "report.html", PZ_OUTPUT_REPORT_HTML},    {"layout", "layout.obj", PZ_OUTPUT_LAYOUT_OBJ},
    {"energy", "energy.svg", PZ_OUTPUT_ENERGY_SVG},
};
#define OUTPUT_NAME_COUNT ((int)(sizeof output_names / sizeof output_names[0]))

pz_status pz_outputs_parse(const char *list, unsigned *outputs, pz_ctx *ctx)
{
    *outputs = 0;
    if (!list || !*list)
        return pz_error(ctx, PZ_ERR_USAGE, "--outputs: empty list (names: obj, svg, pdf, tiled, dxf, marker, glb, "
                        "json, html, layout, energy, all)");
    const char *word = list;
    while (*word) {
        size_t length = strcspn(word, ",");
        int found = length == 3 && strncmp(word, "all", 3) == 0;
        if (found)
            *outputs |= PZ_OUTPUT_ALL;
        for (int i = 0; !found && i < OUTPUT_NAME_COUNT; ++i)
            if (strlen(output_names[i].word) == length && strncmp(word, output_names[i].word, length) == 0)
                *outputs |= output_names[i].bit, found = 1;
        if (!found)
            return pz_error(ctx, PZ_ERR_USAGE, "--outputs: '%.*s' is not one of obj, svg, pdf, tiled, dxf, marker, "
                            "glb, json, html, layout, energy, all", (int)length, word);
        word += length;
        if (*word == ',')
            ++word;
    }
    return PZ_OK;
}

/* The bit of a file name, 0 when it has none. */
static unsigned output_bit(const char *file)
{
    for (int i = 0; i < OUTPUT_NAME_COUNT; ++i)
        if (strcmp(output_names[i].file, file) == 0)
            return output_names[i].bit;
    return 0;
}

/* ---------------------------------------------------------------- garment.obj, layout.obj */

/* The shortest %.Ng (15..17 digits) that reads back as exactly `value`. */
static void format_exact(char *buffer, size_t size, double value)
{
    for (int digits = 15; digits <= 17; ++digits) {
        snprintf(buffer, size, "%.*g", digits, value);
        if (strtod(buffer, NULL) == value)
            return;
    }
}

pz_status pl_write_garment_obj(FILE *file, const pz_mesh *garment, const double *positions,
                               const pz_pattern *pattern, const double *uv, pz_ctx *ctx)
{
    (void)ctx; /* write errors surface in pz_output_commit */
    fprintf(file, "# panelize flatten: the garment's own vertices and faces; vt = the sewing pattern in mm;\n"
                  "# one group per panel (panel_K)\n");
    char x[32], y[32], z[32];
    for (int32_t v = 0; v < garment->vertex_count; ++v) {
        format_exact(x, sizeof x, positions[3 * v]);
        format_exact(y, sizeof y, positions[3 * v + 1]);
        format_exact(z, sizeof z, positions[3 * v + 2]);
        fprintf(file, "v %s %s %s\n", x, y, z);
    }
    const pz_mesh *cut = pattern->mesh;
    for (int32_t v = 0; v < cut->vertex_count; ++v)
        fprintf(file, "vt %.6f %.6f\n", uv[2 * v], uv[2 * v + 1]);
    int32_t current = -1;
    for (int32_t f = 0; f < garment->face_count; ++f) {
        if (pattern->face_panel[f] != current) {
            current = pattern->face_panel[f];
            fprintf(file, "g panel_%d\n", (int)current);
        }
        const int32_t *corners = &garment->faces[3 * f], *cut_corners = &cut->faces[3 * f];
        fprintf(file, "f %d/%d %d/%d %d/%d\n", (int)corners[0] + 1, (int)cut_corners[0] + 1, (int)corners[1] + 1,
                (int)cut_corners[1] + 1, (int)corners[2] + 1, (int)cut_corners[2] + 1);
    }
    return PZ_OK;
}

/* layout.obj: the garment's vertices used by the layout (in the input's units, like garment.obj), one
 * group and one polyline (`l`) per seam or dart. */
pz_status pl_write_layout_obj(const pz_result *result, FILE *file, pz_ctx *ctx)
{
    const pz_pattern *pattern = result->pattern;
    const pz_mesh *mesh = pattern->mesh;
    double scale = mesh->unit_scale > 0 ? mesh->unit_scale : 1.0;
    /* The cut mesh's vertex of each garment vertex (any copy has the garment's position). */
    int32_t garment_vertices = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (pattern->vertex_origin[v] + 1 > garment_vertices)
            garment_vertices = pattern->vertex_origin[v] + 1;
    int32_t *copy = malloc(((size_t)garment_vertices + 1) * sizeof(int32_t));
    if (!copy)
        return pz_error(ctx, PZ_ERR_NOMEM, "layout.obj: out of memory");
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        copy[pattern->vertex_origin[v]] = v;
    fprintf(file, "# panelize layout: %d seams, %d darts (polylines on the garment)\n", (int)pattern->seam_count,
            (int)pattern->dart_count);
    int32_t seam = 0, dart = 0;
    for (int32_t c = 0; c < result->layout_curve_count; ++c) {
        int32_t first = result->layout_offsets[c], last = result->layout_offsets[c + 1];
        if (result->layout_is_dart[c])
            fprintf(file, "g dart_%d\n", (int)dart++);
        else
            fprintf(file, "g seam_%d_panels_%d_%d\n", (int)seam, (int)pattern->seams[seam].panel_a,
                    (int)pattern->seams[seam].panel_b), ++seam;
        for (int32_t i = first; i < last; ++i) {
            const double *p = mesh->positions + 3 * (size_t)copy[result->layout_vertices[i]];
            fprintf(file, "v %.9g %.9g %.9g\n", p[0] / scale, p[1] / scale, p[2] / scale);
        }
        fputs("l", file);
        for (int32_t i = first; i < last; ++i)
            fprintf(file, " %d", (int)(i + 1));
        fputc('\n', file);
    }
    free(copy);
    if (ferror(file))
        return pz_error(ctx, PZ_ERR_CREATE, "layout.obj: write error");
    return PZ_OK;
}


/* ---------------------------------------------------------------- folders */

/* Directories created by this run, removed again when it fails. */
typedef struct created_dirs {
    char *paths[64];
    int count;
} created_dirs;

static void remove_created_dirs(created_dirs *dirs)
{
    while (dirs->count > 0) {
        --dirs->count;
        rmdir(dirs->paths[dirs->count]);
        free(dirs->paths[dirs->count]);
    }
}

static void forget_created_dirs(created_dirs *dirs)
{
    while (dirs->count > 0)
        free(dirs->paths[--dirs->count]);
}

/* mkdir -p: every missing prefix of `dir`, remembering what it created. */
static pz_status make_directories(const char *dir, created_dirs *dirs, pz_ctx *ctx)
{
    char *path = strdup(dir);
    if (!path)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", dir);
    size_t length = strlen(path);
    pz_status status = PZ_OK;
    for (size_t end = 1; end <= length && status == PZ_OK; ++end) {
        if (end < length && path[end] != '/')
            continue;
        char saved = path[end];
        path[end] = '\0';
        struct stat info;
        if (stat(path, &info) == 0) {
            if (!S_ISDIR(info.st_mode))
                status = pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output directory: %s is not a directory",
                                  dir, path);
        } else if (mkdir(path, 0777) != 0) {
            status = pz_error(ctx, PZ_ERR_CREATE, "%s: cannot create the output directory: %s", dir, strerror(errno));
        } else if (dirs->count < (int)(sizeof dirs->paths / sizeof dirs->paths[0])) {
            if (!(dirs->paths[dirs->count] = strdup(path)))
                status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", dir);
            else
                ++dirs->count;
        }
        path[end] = saved;
    }
    free(path);
    return status;
}

/* ---------------------------------------------------------------- writing */

enum output_kind { OUT_GARMENT_OBJ, OUT_EXPORT, OUT_LAYOUT, OUT_REPORT, OUT_HTML };

typedef struct output_entry {
    const char *name;
    enum output_kind kind;
    int index;                /* OUT_EXPORT / OUT_HTML: pz_export_files index */
    int binary;
} output_entry;

#define MAX_OUTPUTS 32

/* Everything one write needs. */
typedef struct writer {
    pz_result *result;
    pz_export_inputs export_inputs;
    double write_start;
    cJSON *report_root;       /* built just before report.json is written */
    char *report_text;        /* report.json */
    output_entry outputs[MAX_OUTPUTS];
    int output_count;
} writer;

static void add_output(writer *w, unsigned wanted, const char *name, enum output_kind kind, int index, int binary)
{
    unsigned bit = output_bit(name);
    if ((bit == 0 || (wanted & bit)) && w->output_count < MAX_OUTPUTS)
        w->outputs[w->output_count++] = (output_entry){name, kind, index, binary};
}

static void list_outputs(writer *w, unsigned wanted)
{
    const pz_result *result = w->result;
    w->output_count = 0;
    add_output(w, wanted, "garment.obj", OUT_GARMENT_OBJ, 0, 1);
    for (int i = 0; i < pz_export_file_count; ++i)
        if (strcmp(pz_export_files[i].name, "report.html") != 0 &&
            (result->marker || result->pieces || strcmp(pz_export_files[i].name, "marker.svg") != 0))
            add_output(w, wanted, pz_export_files[i].name, OUT_EXPORT, i, pz_export_files[i].binary);
    if (result->from_run)
        add_output(w, wanted, "layout.obj", OUT_LAYOUT, 0, 1);
    add_output(w, wanted, "report.json", OUT_REPORT, 0, 1);
    for (int i = 0; i < pz_export_file_count; ++i)
        if (strcmp(pz_export_files[i].name, "report.html") == 0)
            add_output(w, wanted, pz_export_files[i].name, OUT_HTML, i, 1);
}

/* report.json's content (report.html shows it too). */
static pz_status build_report(writer *w, pz_ctx *ctx)
{
    if (w->report_root)
        return PZ_OK;
    w->result->timings.write = pz_elapsed_ms(w->write_start, pz_seconds());
    cJSON *root = pz_result_report(w->result);
    w->report_text = root ? cJSON_Print(root) : NULL;
    if (!w->report_text) {
        cJSON_Delete(root);
        return pz_error(ctx, PZ_ERR_NOMEM, "report.json: out of memory");
    }
    w->report_root = root;
    w->export_inputs.report = root;
    return PZ_OK;
}

/* Writes one output; path (the file's full name) names it in errors. */
static pz_status write_file(writer *w, const output_entry *entry, const char *path, FILE *file, pz_ctx *ctx)
{
    const pz_result *result = w->result;
    switch (entry->kind) {
    case OUT_GARMENT_OBJ:
        return pl_write_garment_obj(file, result->garment, result->positions_out, result->pattern, result->uv, ctx);
    case OUT_EXPORT:
        return pz_export_files[entry->index].write(file, &w->export_inputs, path, ctx);
    case OUT_HTML: {
        pz_status status = build_report(w, ctx);
        return status != PZ_OK ? status : pz_export_files[entry->index].write(file, &w->export_inputs, path, ctx);
    }
    case OUT_LAYOUT:
        return pl_write_layout_obj(result, file, ctx);
    case OUT_REPORT: {
        pz_status status = build_report(w, ctx);
        if (status != PZ_OK)
            return status;
        fputs(w->report_text, file);
        fputc('\n', file);
        return PZ_OK;
    }
    }
    return pz_error(ctx, PZ_ERR_INTERNAL, "%s: unknown output", path);
}

static char *join_path(const char *dir, const char *name)
{
    size_t size = strlen(dir) + strlen(name) + 2;
    char *path = malloc(size);
    if (path)
        snprintf(path, size, "%s%s%s", dir, dir[0] && dir[strlen(dir) - 1] == '/' ? "" : "/", name);
    return path;
}

/* What the export writers read, borrowed from the result. */
static void fill_export_inputs(writer *w)
{
    const pz_result *result = w->result;
    pz_export_inputs *inputs = &w->export_inputs;
    inputs->garment = result->garment;
    inputs->positions = result->positions_out;
    inputs->pattern = result->pattern;
    inputs->uv = result->uv;
    inputs->metrics = result->metrics[0];
    inputs->pieces = result->pieces;
    inputs->marker = result->marker;
    inputs->options = &result->options.output;
    inputs->panel_names = (const char *const *)result->panel_names;
    inputs->layout_vertices = result->layout_vertices;
    inputs->layout_offsets = result->layout_offsets;
    inputs->layout_curve_count = result->layout_curve_count;
}

/* mkdir -p of the folder's parent (the folder itself is swapped in whole: folder.c). */
static pz_status make_parent(const char *folder, created_dirs *dirs, pz_ctx *ctx)
{
    char *parent = strdup(folder);
    if (!parent)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder);
    size_t length = strlen(parent);
    while (length > 1 && parent[length - 1] == '/')
        parent[--length] = '\0';
    char *slash = strrchr(parent, '/');
    pz_status status = PZ_OK;
    if (slash && slash != parent) {
        *slash = '\0';
        status = make_directories(parent, dirs, ctx);
    }
    free(parent);
    return status;
}

/* Whether an output draws on what pz_run may defer (pz_result_complete): the marker (marker.svg, garment.glb's
 * texture space) or the trade-off (the reports). */
static int needs_extras(const output_entry *entry)
{
    return entry->kind == OUT_REPORT || entry->kind == OUT_HTML || strcmp(entry->name, "marker.svg") == 0 ||
           strcmp(entry->name, "garment.glb") == 0;
}

/* Opens and writes the outputs with needs_extras() == `extras` (files[i], paths[i], shown[i]). */
static pz_status write_some(writer *w, int extras, pz_output *files, char **paths, char **shown, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    for (int i = 0; i < w->output_count && status == PZ_OK; ++i) {
        if (needs_extras(&w->outputs[i]) != extras)
            continue;
        /* Writers name the file by where it will be (messages); it is written where it is made. */
        if ((status = pz_output_open(&files[i], paths[i], "wb", ctx)) == PZ_OK)
            status = write_file(w, &w->outputs[i], shown[i], files[i].file, ctx);
        if (status == PZ_OK)
            status = pz_check_cancel(ctx, "write");
    }
    return status;
}

/*
 * What pz_run deferred (the marker, the trade-off: pz_result_complete) made beside the files that do not need
 * it, on a second thread when there is one (the wetsuit's marker is a second of one core; its pattern files
 * half of one), then the files that do. The result is the same either way.
 */
static pz_status write_files(writer *w, pz_output *files, char **paths, char **shown, pz_ctx *ctx)
{
    pz_ctx side = *ctx; /* the completion's own error line; no progress from a second thread */
    side.progress = NULL;
    pz_status completed = PZ_OK, status = PZ_OK;
    int threads = omp_get_max_threads() > 1 && !pl_result_completed(w->result) ? 2 : 1;
#pragma omp parallel sections num_threads(threads)
    {
#pragma omp section
        completed = pz_result_complete(w->result, &side);
#pragma omp section
        status = write_some(w, 0, files, paths, shown, ctx);
    }
    if (completed != PZ_OK && status == PZ_OK)
        status = pz_error(ctx, completed, "%s", side.error);
    if (status == PZ_OK) {
        fill_export_inputs(w); /* the marker made just now */
        status = write_some(w, 1, files, paths, shown, ctx);
    }
    return status;
}

/* Writes every listed file into `dir` (the hidden folder), each complete and synced. */
static pz_status write_all(writer *w, const char *dir, const char *folder, int energy_wanted, const char **names,
                           int *name_count, pz_ctx *ctx)
{
    const pz_result *result = w->result;
    int count = w->output_count, committed = 0;
    pz_output files[MAX_OUTPUTS];
    char *paths[MAX_OUTPUTS], *shown[MAX_OUTPUTS];
    memset(files, 0, sizeof files);
    memset(paths, 0, sizeof paths);
    memset(shown, 0, sizeof shown);
    pz_status status = PZ_OK;
    for (int i = 0; i < count && status == PZ_OK; ++i)
        if (!(paths[i] = join_path(dir, w->outputs[i].name)) || !(shown[i] = join_path(folder, w->outputs[i].name)))
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder);
    if (status == PZ_OK)
        status = write_files(w, files, paths, shown, ctx);
    for (; committed < count && status == PZ_OK; ++committed)
        if ((status = pz_output_commit(&files[committed], ctx)) == PZ_OK)
            names[(*name_count)++] = w->outputs[committed].name;
    /* energy.svg has its own atomic writer (param/). */
    char *energy_path = NULL;
    if (status == PZ_OK && energy_wanted) {
        if (!(energy_path = join_path(dir, "energy.svg")))
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", folder);
        else if ((status = pz_springmass_write_energy_svg(result->pattern, result->uv, &result->backend.springmass,
                                                          energy_path, ctx)) == PZ_OK)
            names[(*name_count)++] = "energy.svg";
    }
    /* Abort is a no-op on an output never opened or already committed (its fields are cleared). */
    for (int i = 0; i < count; ++i) {
        pz_output_abort(&files[i]);
        free(paths[i]);
        free(shown[i]);
    }
    free(energy_path);
    return status;
}

pz_status pz_result_write(pz_result *result, const char *folder, unsigned outputs, char **report_text, pz_ctx *ctx)
{
    if (report_text)
        *report_text = NULL;
    if (!result || !result->pattern || !folder || !*folder)
        return pz_error(ctx, PZ_ERR_USAGE, "write: no result or no folder");
    writer w;
    memset(&w, 0, sizeof w);
    w.result = result;
    w.write_start = pz_seconds();
    fill_export_inputs(&w);
    list_outputs(&w, outputs);
    int energy_wanted = result->options.flatten.backend == PZ_BACKEND_SPRINGMASS && (outputs & PZ_OUTPUT_ENERGY_SVG);
    const char *names[MAX_OUTPUTS + 1];
    int name_count = 0;
    created_dirs dirs = {0};
    pl_folder hidden;
    memset(&hidden, 0, sizeof hidden);
    hidden.lock_fd = -1;
    pz_status status = pz_output_folder_check(folder, ctx);
    if (status == PZ_OK)
        status = make_parent(folder, &dirs, ctx);
    if (status == PZ_OK)
        status = pl_folder_begin(folder, &hidden, ctx);
    if (status == PZ_OK)
        status = write_all(&w, hidden.hidden, folder, energy_wanted, names, &name_count, ctx);
    if (status == PZ_OK)
        status = pz_check_cancel(ctx, "write");
    if (status == PZ_OK)
        status = pl_folder_commit(&hidden, names, name_count, ctx);
    pl_folder_end(&hidden); /* removes the hidden folder unless it was swapped in */
    if (status != PZ_OK)
        remove_created_dirs(&dirs);
    forget_created_dirs(&dirs);
    if (status == PZ_OK && report_text) {
        *report_text = w.report_text;
        w.report_text = NULL;
    }
    free(w.report_text);
    cJSON_Delete(w.report_root);
    return status;
}
