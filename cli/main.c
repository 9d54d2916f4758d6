/*
 * cli/main.c -- `panelize COMMAND ...`: the command table, the option
 * parser and the helpers the commands share.
 *
 * Parsing is hand-written and table driven: every option is listed once in
 * `option_table` with whether it takes a value; each command says which ones
 * it accepts. Values come as `--opt value` or `--opt=value`, positional
 * arguments may stand anywhere, `--` makes every later argument positional.
 * Any problem (unknown command or option, a missing value, a bad number) is
 * PZ_ERR_USAGE: exit 64 with one line `panelize: COMMAND: problem`.
 *
 * The process prints exactly one line on stderr when it fails: the context's
 * message, which names the file or the option at fault. Exit codes come from
 * pz_status_exit_code (0, 64, 65, 66, 70, 73: docs/cli.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "cli/cli.h"
#include "io/io.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Largest --faces and --poses accepted: beyond these a typo would only exhaust memory. */
#define PZ_CLI_MAX_FACES 10000000
#define PZ_CLI_MAX_POSES 64

static const pz_cli_command command_table[] = {
    {"info", "describe a mesh: counts, topology, validity, units, size, area",
     pz_cli_info_usage, PZ_CLI_OPT_COMMON | PZ_CLI_OPT_UNITS | PZ_CLI_OPT_POSE, pz_cli_info},
    {"check", "validate a mesh as every later command will (exit 65 when invalid)",
     pz_cli_check_usage, PZ_CLI_OPT_COMMON | PZ_CLI_OPT_UNITS | PZ_CLI_OPT_POSE | PZ_CLI_OPT_REPAIR,
     pz_cli_check},
    {"generate", "write a synthetic garment or test surface",
     pz_cli_generate_usage,
     PZ_CLI_OPT_COMMON | PZ_CLI_OPT_OUTPUT | PZ_CLI_OPT_FACES | PZ_CLI_OPT_POSES | PZ_CLI_OPT_OPEN,
     pz_cli_generate},
    {"flatten", "flatten every panel of a garment into a sewing pattern",
     pz_cli_flatten_usage,
     PZ_CLI_OPT_COMMON | PZ_CLI_OPT_UNITS | PZ_CLI_OPT_POSE | PZ_CLI_OPT_REPAIR | PZ_CLI_OPT_OUTPUT |
         PZ_CLI_OPT_PANELS | PZ_CLI_OPT_SEAMS | PZ_CLI_OPT_DARTS | PZ_CLI_OPT_GRAIN | PZ_CLI_OPT_BACKEND |
         PZ_CLI_OPT_ITERATIONS | PZ_CLI_OPT_WEIGHTS | PZ_CLI_OPT_FABRIC | PZ_CLI_OPT_SCHEME |
         PZ_CLI_OPT_RELAX | PZ_CLI_OPT_FEATURES | PZ_CLI_OPT_GRAIN_HINTS | PZ_CLI_OPT_EXPORT,
     pz_cli_flatten},
    {"run", "the whole pipeline: garment in, panels, darts and a sewable pattern out",
     pz_cli_run_usage, PZ_CLI_OPT_RUN, pz_cli_run},
    {"batch", "run many garments: folders, manifests, shards, resume, a summary",
     pz_cli_batch_usage, PZ_CLI_OPT_BATCH, pz_cli_batch},
    {"studio", "a local web page: sketch seams on the 3D garment, see the pattern update",
     pz_cli_studio_usage, PZ_CLI_OPT_COMMON | PZ_CLI_OPT_PORT | PZ_CLI_OPT_LISTEN | PZ_CLI_OPT_ROOT, pz_cli_studio},
    {"field", "compute the curvature-aligned cross-field that guides the seams",
     pz_cli_field_usage,
     PZ_CLI_OPT_COMMON | PZ_CLI_OPT_UNITS | PZ_CLI_OPT_POSE | PZ_CLI_OPT_REPAIR | PZ_CLI_OPT_OUTPUT |
         PZ_CLI_OPT_SKETCH | PZ_CLI_OPT_SCALES | PZ_CLI_OPT_SMOOTHNESS,
     pz_cli_field},
    {"prepare", "repair, weld, decimate and remesh a scan or an export into a clean garment mesh",
     pz_cli_prepare_usage,
     PZ_CLI_OPT_COMMON | PZ_CLI_OPT_UNITS | PZ_CLI_OPT_POSE | PZ_CLI_OPT_REPAIR | PZ_CLI_OPT_OUTPUT |
         PZ_CLI_OPT_FACES | PZ_CLI_OPT_EDGE | PZ_CLI_OPT_WELD | PZ_CLI_OPT_KEEP,
     pz_cli_prepare},
};
static const size_t command_table_count = sizeof command_table / sizeof command_table[0];

typedef struct option_spec {
    const char *long_name;  /* without the leading "--" */
    char short_name;        /* 0 when there is none */
    uint64_t flag;          /* PZ_CLI_OPT_* bit */
    int takes_value;
} option_spec;

static const option_spec option_table[] = {
    {"quiet", 'q', PZ_CLI_OPT_QUIET, 0},
    {"json", 0, PZ_CLI_OPT_JSON, 0},
    {"units", 0, PZ_CLI_OPT_UNITS, 1},
    {"repair", 0, PZ_CLI_OPT_REPAIR, 0},
    {"pose", 0, PZ_CLI_OPT_POSE, 1},
    {"output", 'o', PZ_CLI_OPT_OUTPUT, 1},
    {"faces", 0, PZ_CLI_OPT_FACES, 1},
    {"poses", 0, PZ_CLI_OPT_POSES, 1},
    {"open", 0, PZ_CLI_OPT_OPEN, 0},
    {"panels", 0, PZ_CLI_OPT_PANELS, 1},
    {"seams", 0, PZ_CLI_OPT_SEAMS, 1},
    {"darts", 0, PZ_CLI_OPT_DARTS, 1},
    {"grain", 0, PZ_CLI_OPT_GRAIN, 1},
    {"backend", 0, PZ_CLI_OPT_BACKEND, 1},
    {"iterations", 0, PZ_CLI_OPT_ITERATIONS, 1},
    {"weights", 0, PZ_CLI_OPT_WEIGHTS, 1},
    {"fabric", 0, PZ_CLI_OPT_FABRIC, 1},
    {"sketch", 0, PZ_CLI_OPT_SKETCH, 1},
    {"scales", 0, PZ_CLI_OPT_SCALES, 1},
    {"smoothness", 0, PZ_CLI_OPT_SMOOTHNESS, 1},
    {"edge", 0, PZ_CLI_OPT_EDGE, 1},
    {"weld", 0, PZ_CLI_OPT_WELD, 1},
    {"keep", 0, PZ_CLI_OPT_KEEP, 1},
    {"scheme", 0, PZ_CLI_OPT_SCHEME, 1},
    {"relax", 0, PZ_CLI_OPT_RELAX, 1},
    {"features", 0, PZ_CLI_OPT_FEATURES, 1},
    {"max-corners", 0, PZ_CLI_OPT_MAX_CORNERS, 1},
    {"max-strain", 0, PZ_CLI_OPT_MAX_STRAIN, 1},
    {"symmetry", 0, PZ_CLI_OPT_SYMMETRY, 1},
    {"prepare", 0, PZ_CLI_OPT_PREPARE, 1},
    {"seam-allowance", 0, PZ_CLI_OPT_SEAM_ALLOWANCE, 1},
    {"hem-allowance", 0, PZ_CLI_OPT_HEM_ALLOWANCE, 1},
    {"allowances", 0, PZ_CLI_OPT_ALLOWANCES, 1},
    {"notch-spacing", 0, PZ_CLI_OPT_NOTCH_SPACING, 1},
    {"paper", 0, PZ_CLI_OPT_PAPER, 1},
    {"fabric-width", 0, PZ_CLI_OPT_FABRIC_WIDTH, 1},
    {"gap", 0, PZ_CLI_OPT_GAP, 1},
    {"dxf-strict", 0, PZ_CLI_OPT_DXF_STRICT, 0},
    {"truing", 0, PZ_CLI_OPT_TRUING, 1},
    {"size", 0, PZ_CLI_OPT_SIZE, 1},
    {"outputs", 0, PZ_CLI_OPT_OUTPUTS, 1},
    {"max-seam-mismatch", 0, PZ_CLI_OPT_MAX_SEAM_MISMATCH, 1},
    {"min-piece-width", 0, PZ_CLI_OPT_MIN_PIECE_WIDTH, 1},
    {"min-piece-area", 0, PZ_CLI_OPT_MIN_PIECE_AREA, 1},
    {"min-dart-intake", 0, PZ_CLI_OPT_MIN_DART_INTAKE, 1},
    {"strict", 0, PZ_CLI_OPT_STRICT, 0},
    {"fold", 0, PZ_CLI_OPT_FOLD, 0},
    {"max-pieces", 0, PZ_CLI_OPT_MAX_PIECES, 1},
    {"jobs", 'j', PZ_CLI_OPT_JOBS, 1},
    {"shard", 0, PZ_CLI_OPT_SHARD, 1},
    {"resume", 0, PZ_CLI_OPT_RESUME, 0},
    {"timeout", 0, PZ_CLI_OPT_TIMEOUT, 1},
    {"merge", 0, PZ_CLI_OPT_MERGE, 0},
    {"port", 0, PZ_CLI_OPT_PORT, 1},
    {"listen", 0, PZ_CLI_OPT_LISTEN, 1},
    {"root", 0, PZ_CLI_OPT_ROOT, 1},
    {"grain-hints", 0, PZ_CLI_OPT_GRAIN_HINTS, 1},
    {"consolidate", 0, PZ_CLI_OPT_CONSOLIDATE, 1},
    {"mirror-sketch", 0, PZ_CLI_OPT_MIRROR_SKETCH, 0},
};
static const size_t option_table_count = sizeof option_table / sizeof option_table[0];

static const char global_usage_head[] =
    "usage: panelize COMMAND [OPTIONS] [ARGS]\n"
    "       panelize COMMAND --help\n"
    "       panelize --version\n"
    "\n"
    "Turns 3D garment meshes into sewable 2D patterns.\n"
    "\n"
    "commands:\n";

static const char global_usage_tail[] =
    "\n"
    "options common to every command:\n"
    "  --quiet        no progress or timings on stderr\n"
    "  --json         machine-readable output on stdout\n"
    "\n"
    "exit codes: 0 ok, 3 goals not met (run --strict), 64 usage, 65 bad or invalid\n"
    "mesh data, 66 cannot open an input, 70 internal error, 73 cannot create an\n"
    "output, 130 interrupted (Ctrl-C). On failure exactly one\n"
    "line `panelize: FILE: problem` is printed on stderr. See docs/cli.md.\n";

static void print_global_usage(FILE *stream)
{
    fputs(global_usage_head, stream);
    for (size_t i = 0; i < command_table_count; ++i)
        fprintf(stream, "  %-10s %s\n", command_table[i].name, command_table[i].summary);
    fputs(global_usage_tail, stream);
}

static const pz_cli_command *find_command(const char *name)
{
    for (size_t i = 0; i < command_table_count; ++i)
        if (strcmp(command_table[i].name, name) == 0)
            return &command_table[i];
    return NULL;
}

/* ---------------------------------------------------------------- parsing */

/* Finds "--name" (name_length chars, no '=') or "-c"; NULL when unknown. */
static const option_spec *find_option(const char *name, size_t name_length, char short_name)
{
    for (size_t i = 0; i < option_table_count; ++i) {
        const option_spec *spec = &option_table[i];
        if (short_name ? spec->short_name == short_name
                       : strlen(spec->long_name) == name_length && strncmp(spec->long_name, name, name_length) == 0)
            return spec;
    }
    return NULL;
}

/* A whole decimal integer in [minimum, maximum]; anything else is a usage error naming the option. */
static pz_status parse_count(const char *command, const char *option, const char *text, long minimum,
                             long maximum, int32_t *out, pz_ctx *ctx)
{
    char *end = NULL;
    errno = 0;
    long value = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: %s: '%s' is not a whole number", command, option, text);
    if (value < minimum || value > maximum)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: %s: %ld is out of range (%ld .. %ld)", command, option, value,
                        minimum, maximum);
    *out = (int32_t)value;
    return PZ_OK;
}

/* Stores one option (with its value, if it takes one) into args. */
static pz_status apply_option(pz_cli_args *args, const option_spec *spec, const char *value, pz_ctx *ctx)
{
    const char *command = args->command;
    switch (spec->flag) {
    case PZ_CLI_OPT_QUIET: args->quiet = 1; return PZ_OK;
    case PZ_CLI_OPT_JSON: args->json = 1; return PZ_OK;
    case PZ_CLI_OPT_REPAIR:
        args->repair_flags = PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES | PZ_REPAIR_ORIENT;
        return PZ_OK;
    case PZ_CLI_OPT_OPEN: args->open = 1; return PZ_OK;
    case PZ_CLI_OPT_POSE: args->pose_paths[args->pose_path_count++] = value; return PZ_OK;
    case PZ_CLI_OPT_OUTPUT:
        if (args->output_path)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: -o given twice", command);
        if (!*value)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: -o: empty file name", command);
        args->output_path = value;
        return PZ_OK;
    case PZ_CLI_OPT_UNITS:
        if (pz_units_parse(value, &args->units, ctx) != PZ_OK)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: --units: '%s' is not one of mm, cm, m, auto", command, value);
        return PZ_OK;
    case PZ_CLI_OPT_FACES:
        return parse_count(command, "--faces", value, 1, PZ_CLI_MAX_FACES, &args->target_faces, ctx);
    case PZ_CLI_OPT_POSES:
        return parse_count(command, "--poses", value, 0, PZ_CLI_MAX_POSES, &args->pose_count, ctx);
    case PZ_CLI_OPT_SEAMS: args->seam_paths[args->seam_path_count++] = value; return PZ_OK;
    case PZ_CLI_OPT_DARTS: args->dart_paths[args->dart_path_count++] = value; return PZ_OK;
    }
    if (spec->flag >= (UINT64_C(1) << PZ_CLI_VALUE_FIRST_BIT)) {
        /* Value options: the command parses the text; given twice is a mistake worth naming. */
        const char **slot = &args->values[pz_cli_value_index(spec->flag)];
        if (*slot)
            return pz_error(ctx, PZ_ERR_USAGE, "%s: --%s given twice", command, spec->long_name);
        *slot = value ? value : "1"; /* a flag among them (--dxf-strict) reads as "1" */
        return PZ_OK;
    }
    return pz_error(ctx, PZ_ERR_INTERNAL, "%s: option table and parser disagree", command);
}

/*
 * Parses one option argument argv[*index] ("--name", "--name=value", "-c");
 * advances *index past a separate value.
 */
static pz_status parse_option(pz_cli_args *args, uint64_t accepted, int argc, char **argv, int *index,
                              pz_ctx *ctx)
{
    const char *arg = argv[*index];
    const option_spec *spec;
    const char *inline_value = NULL;
    if (arg[1] == '-') {
        const char *name = arg + 2;
        const char *equals = strchr(name, '=');
        size_t name_length = equals ? (size_t)(equals - name) : strlen(name);
        spec = find_option(name, name_length, 0);
        if (equals)
            inline_value = equals + 1;
    } else {
        spec = arg[2] == '\0' ? find_option(NULL, 0, arg[1]) : NULL;
    }
    if (!spec || !(spec->flag & accepted))
        return pz_error(ctx, PZ_ERR_USAGE, "%s: unknown option %s (see panelize %s --help)", args->command, arg,
                        args->command);
    const char *value = NULL;
    if (spec->takes_value) {
        if (inline_value) {
            value = inline_value;
        } else if (*index + 1 < argc) {
            value = argv[++*index];
        } else {
            return pz_error(ctx, PZ_ERR_USAGE, "%s: %s needs a value", args->command, arg);
        }
    } else if (inline_value) {
        return pz_error(ctx, PZ_ERR_USAGE, "%s: --%s takes no value", args->command, spec->long_name);
    }
    return apply_option(args, spec, value, ctx);
}

void pz_cli_args_clear(pz_cli_args *args)
{
    free(args->pose_paths);
    free(args->seam_paths);
    free(args->dart_paths);
    free(args->positionals);
    memset(args, 0, sizeof *args);
}

pz_status pz_cli_parse_args(const char *command_name, uint64_t accepted, int argc, char **argv, int first,
                            pz_cli_args *args, pz_ctx *ctx)
{
    memset(args, 0, sizeof *args);
    args->command = command_name;
    args->units = PZ_UNITS_AUTO;
    /* Every argument is at most one pose path or one positional: argc bounds both arrays. */
    args->pose_paths = calloc((size_t)argc + 1, sizeof *args->pose_paths);
    args->positionals = calloc((size_t)argc + 1, sizeof *args->positionals);
    args->seam_paths = calloc((size_t)argc + 1, sizeof *args->seam_paths);
    args->dart_paths = calloc((size_t)argc + 1, sizeof *args->dart_paths);
    if (!args->pose_paths || !args->positionals || !args->seam_paths || !args->dart_paths) {
        pz_cli_args_clear(args);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", command_name);
    }
    int options_ended = 0;
    for (int i = first; i < argc; ++i) {
        const char *arg = argv[i];
        if (!options_ended && strcmp(arg, "--") == 0) {
            options_ended = 1;
        } else if (!options_ended && arg[0] == '-' && arg[1] != '\0') {
            pz_status status = parse_option(args, accepted, argc, argv, &i, ctx);
            if (status != PZ_OK) {
                pz_cli_args_clear(args);
                return status;
            }
        } else {
            args->positionals[args->positional_count++] = arg;
        }
    }
    return PZ_OK;
}

/* True when `--help` or `-h` appears before any `--`. */
static int wants_help(int argc, char **argv, int first)
{
    for (int i = first; i < argc && strcmp(argv[i], "--") != 0; ++i)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return 1;
    return 0;
}

/* ---------------------------------------------------------------- shared helpers */

pz_status pz_cli_expect_positionals(const pz_cli_args *args, int count, const char *what, pz_ctx *ctx)
{
    if (args->positional_count == count)
        return PZ_OK;
    if (args->positional_count > count)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: unexpected argument '%s' (expected %s)", args->command,
                        args->positionals[count], what);
    return pz_error(ctx, PZ_ERR_USAGE, "%s: expected %s (see panelize %s --help)", args->command, what,
                    args->command);
}

void pz_cli_mesh_to_mm(const pz_cli_args *args, pz_mesh *mesh, pz_units *units_used, int *plausible)
{
    if (plausible)
        *plausible = pz_mesh_units_plausible(mesh, args->units);
    pz_mesh_to_mm(mesh, args->units, units_used);
}

void pz_cli_warn_units(const pz_cli_args *args, const char *path, const pz_mesh *mesh, pz_units used,
                       pz_ctx *ctx)
{
    if (args->units != PZ_UNITS_AUTO || pz_mesh_units_plausible(mesh, PZ_UNITS_MM))
        return;
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double extent = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    pz_note(ctx, "%s: warning: units guessed as %s, but then the largest extent (%.0f mm) is outside a "
            "garment's 200-3000 mm; give --units if that is wrong", path, pz_units_str(used), extent);
}

pz_status pz_cli_load_valid_mesh(const pz_cli_args *args, const char *path, pz_mesh **out,
                                 pz_units *units_used, pz_ctx *ctx)
{
    *out = NULL;
    pz_mesh *mesh = NULL;
    pz_status status = pz_mesh_read_with_poses(path, args->pose_paths, args->pose_path_count, &mesh, ctx);
    if (status != PZ_OK)
        return status;
    pz_units used = PZ_UNITS_AUTO;
    pz_cli_mesh_to_mm(args, mesh, &used, NULL);
    status = pz_mesh_check_units(mesh, used, args->units == PZ_UNITS_AUTO, path, ctx);
    if (status == PZ_OK)
        status = pz_mesh_prepare_quietly_first(&mesh, path, args->repair_flags, ctx);
    if (status != PZ_OK) {
        pz_mesh_free(&mesh);
        return status;
    }
    if (units_used)
        *units_used = used;
    *out = mesh;
    return PZ_OK;
}

cJSON *pz_cli_json_vec3(const double values[3], int decimals)
{
    double rounded[3];
    for (int k = 0; k < 3; ++k)
        rounded[k] = pz_round(values[k], decimals);
    return cJSON_CreateDoubleArray(rounded, 3);
}

pz_status pz_cli_print_json(cJSON *root, int build_failed, pz_ctx *ctx)
{
    char *text = (root && !build_failed) ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    if (!text)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory writing JSON");
    fputs(text, stdout);
    fputc('\n', stdout);
    free(text);
    return PZ_OK;
}

/* ---------------------------------------------------------------- main */

/* Runs one command; returns the process exit code. */
static int run_command(const pz_cli_command *command, int argc, char **argv, pz_ctx *ctx)
{
    if (wants_help(argc, argv, 2)) {
        fputs(command->usage, stdout);
        return 0;
    }
    pz_cli_args args;
    pz_status status = pz_cli_parse_args(command->name, command->options, argc, argv, 2, &args, ctx);
    if (status == PZ_OK) {
        ctx->quiet = args.quiet;
        status = command->run(&args, ctx);
        pz_cli_args_clear(&args);
    }
    if (status != PZ_OK) {
        if (!ctx->error[0])
            pz_error(ctx, status, "%s: %s", command->name, pz_status_str(status));
        fprintf(stderr, "panelize: %s\n", ctx->error);
    }
    /* A result that could not reach stdout (a full disk, a closed pipe) is a failed run. */
    if (fflush(stdout) != 0 && (status == PZ_OK || status == PZ_CLI_GOALS_NOT_MET || status == PZ_CLI_BATCH_FAILED)) {
        fprintf(stderr, "panelize: %s: cannot write to standard output\n", command->name);
        return pz_status_exit_code(PZ_ERR_CREATE);
    }
    if (status == PZ_CLI_BATCH_FAILED)
        return PZ_CLI_EXIT_BATCH_FAILED;
    return status == PZ_CLI_GOALS_NOT_MET ? PZ_CLI_EXIT_GOALS_NOT_MET : pz_status_exit_code(status);
}

int main(int argc, char **argv)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    if (argc < 2) {
        print_global_usage(stderr);
        return pz_status_exit_code(PZ_ERR_USAGE);
    }
    const char *first = argv[1];
    if (strcmp(first, "--help") == 0 || strcmp(first, "-h") == 0 || strcmp(first, "help") == 0) {
        const pz_cli_command *command = argc > 2 ? find_command(argv[2]) : NULL;
        if (command)
            fputs(command->usage, stdout);
        else
            print_global_usage(stdout);
        return 0;
    }
    if (strcmp(first, "--version") == 0) {
        printf("panelize %s\n", PZ_VERSION_STRING);
        return 0;
    }
    const pz_cli_command *command = find_command(first);
    if (!command) {
        fprintf(stderr, "panelize: %s: unknown %s (see panelize --help)\n", first,
                first[0] == '-' ? "option" : "command");
        return pz_status_exit_code(PZ_ERR_USAGE);
    }
    return run_command(command, argc, argv, &ctx);
}
