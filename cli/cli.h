/*
 * cli/cli.h -- internal header of the panelize command line.
 *
 * The CLI is a table of commands (main.c). Each command names the options it
 * accepts; main.c parses the command line once into a pz_cli_args (both
 * `--opt value` and `--opt=value`, positional arguments anywhere, `--` ends
 * the options) and hands it to the command's run function, which returns a
 * pz_status. main.c turns that status into the exit code and prints the one
 * error line `panelize: <ctx.error>`; commands never print errors themselves.
 *
 * Output rules every command keeps (docs/cli.md): results on stdout (text, or
 * one JSON object with --json), progress and timings on stderr through
 * pz_note (silenced by --quiet), files only through pz_mesh_write or
 * pz_output_open/commit so that a failed run leaves nothing behind.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_CLI_H
#define PZ_CLI_H

#include "io/io.h"
#include "pipeline/pipeline.h"

#include <cjson/cJSON.h>

/*
 * Options a command may accept (a 64-bit set per command). Bits 0..8 are
 * flags or options parsed by main.c; from PZ_CLI_VALUE_FIRST_BIT on, the raw
 * text is kept for the command to parse (pz_cli_value).
 */
#define PZ_CLI_OPT_QUIET (UINT64_C(1) << 0) /* --quiet */
#define PZ_CLI_OPT_JSON (UINT64_C(1) << 1) /* --json */
#define PZ_CLI_OPT_UNITS (UINT64_C(1) << 2) /* --units mm|cm|m|auto */
#define PZ_CLI_OPT_REPAIR (UINT64_C(1) << 3) /* --repair */
#define PZ_CLI_OPT_POSE (UINT64_C(1) << 4) /* --pose FILE (repeatable) */
#define PZ_CLI_OPT_OUTPUT (UINT64_C(1) << 5) /* -o FILE / --output FILE */
#define PZ_CLI_OPT_FACES (UINT64_C(1) << 6) /* --faces N */
#define PZ_CLI_OPT_POSES (UINT64_C(1) << 7) /* --poses K */
#define PZ_CLI_OPT_OPEN (UINT64_C(1) << 8) /* --open */
#define PZ_CLI_OPT_PANELS (UINT64_C(1) << 9) /* --panels FILE|uv */
#define PZ_CLI_OPT_SEAMS (UINT64_C(1) << 10) /* --seams FILE (repeatable) */
#define PZ_CLI_OPT_DARTS (UINT64_C(1) << 11) /* --darts FILE (repeatable) */
#define PZ_CLI_OPT_GRAIN (UINT64_C(1) << 12) /* --grain X,Y,Z */
#define PZ_CLI_OPT_BACKEND (UINT64_C(1) << 13) /* --backend NAME */
#define PZ_CLI_OPT_ITERATIONS (UINT64_C(1) << 14) /* --iterations N */
#define PZ_CLI_OPT_WEIGHTS (UINT64_C(1) << 15) /* --weights S,R,D,M */
#define PZ_CLI_OPT_FABRIC (UINT64_C(1) << 16) /* --fabric KSU,KSV,KR */
#define PZ_CLI_OPT_SKETCH (UINT64_C(1) << 17) /* --sketch FILE */
#define PZ_CLI_OPT_SCALES (UINT64_C(1) << 18) /* --scales K */
#define PZ_CLI_OPT_SMOOTHNESS (UINT64_C(1) << 19) /* --smoothness W */
#define PZ_CLI_OPT_EDGE (UINT64_C(1) << 20) /* --edge MM (prepare) */
#define PZ_CLI_OPT_WELD (UINT64_C(1) << 21) /* --weld MM (prepare) */
#define PZ_CLI_OPT_KEEP (UINT64_C(1) << 22) /* --keep largest|all (prepare) */
#define PZ_CLI_OPT_SCHEME (UINT64_C(1) << 23) /* --scheme global|progressive (flatten, wirewarp) */
#define PZ_CLI_OPT_RELAX (UINT64_C(1) << 24) /* --relax heap|full (flatten, springmass) */
#define PZ_CLI_OPT_FEATURES (UINT64_C(1) << 25) /* --features FILE (flatten, wirewarp) */
#define PZ_CLI_OPT_MAX_CORNERS (UINT64_C(1) << 26) /* --max-corners C (run) */
#define PZ_CLI_OPT_MAX_STRAIN (UINT64_C(1) << 27) /* --max-strain S (run) */
#define PZ_CLI_OPT_SYMMETRY (UINT64_C(1) << 28) /* --symmetry auto|off|x|y|z|PLANE (run) */
#define PZ_CLI_OPT_PREPARE (UINT64_C(1) << 29) /* --prepare auto|off (run) */
#define PZ_CLI_OPT_SEAM_ALLOWANCE (UINT64_C(1) << 30) /* --seam-allowance MM (flatten, run) */
#define PZ_CLI_OPT_HEM_ALLOWANCE (UINT64_C(1) << 31) /* --hem-allowance MM */
#define PZ_CLI_OPT_ALLOWANCES (UINT64_C(1) << 32) /* --allowances FILE: per-seam allowance overrides */
#define PZ_CLI_OPT_NOTCH_SPACING (UINT64_C(1) << 33) /* --notch-spacing MM */
#define PZ_CLI_OPT_PAPER (UINT64_C(1) << 34) /* --paper a4|letter */
#define PZ_CLI_OPT_FABRIC_WIDTH (UINT64_C(1) << 35) /* --fabric-width MM */
#define PZ_CLI_OPT_GAP (UINT64_C(1) << 36) /* --gap MM */
#define PZ_CLI_OPT_DXF_STRICT (UINT64_C(1) << 37) /* --dxf-strict (a flag: stored as the value "1") */
#define PZ_CLI_OPT_TRUING (UINT64_C(1) << 38) /* --truing on|off (run) */
#define PZ_CLI_OPT_SIZE (UINT64_C(1) << 39) /* --size NAME: the size printed on every piece */
#define PZ_CLI_OPT_OUTPUTS (UINT64_C(1) << 40) /* --outputs LIST: the files to write (flatten, run) */
#define PZ_CLI_OPT_MAX_SEAM_MISMATCH (UINT64_C(1) << 41) /* --max-seam-mismatch R (run) */
#define PZ_CLI_OPT_MIN_PIECE_WIDTH (UINT64_C(1) << 42) /* --min-piece-width MM (run) */
#define PZ_CLI_OPT_MIN_PIECE_AREA (UINT64_C(1) << 43) /* --min-piece-area R (run) */
#define PZ_CLI_OPT_MIN_DART_INTAKE (UINT64_C(1) << 44) /* --min-dart-intake MM (run) */
#define PZ_CLI_OPT_STRICT (UINT64_C(1) << 45) /* --strict (run; a flag: stored as the value "1") */
#define PZ_CLI_OPT_FOLD (UINT64_C(1) << 46) /* --fold (run; a flag: stored as the value "1") */
#define PZ_CLI_OPT_MAX_PIECES (UINT64_C(1) << 47) /* --max-pieces N (run) */
#define PZ_CLI_OPT_JOBS (UINT64_C(1) << 48) /* --jobs N (batch) */
#define PZ_CLI_OPT_SHARD (UINT64_C(1) << 49) /* --shard I/N (batch) */
#define PZ_CLI_OPT_RESUME (UINT64_C(1) << 50) /* --resume (batch; a flag) */
#define PZ_CLI_OPT_TIMEOUT (UINT64_C(1) << 51) /* --timeout S (batch) */
#define PZ_CLI_OPT_MERGE (UINT64_C(1) << 52) /* --merge (batch; a flag) */
#define PZ_CLI_OPT_PORT (UINT64_C(1) << 53) /* --port N (studio) */
#define PZ_CLI_OPT_LISTEN (UINT64_C(1) << 54) /* --listen ADDR (studio) */
#define PZ_CLI_OPT_ROOT (UINT64_C(1) << 55) /* --root DIR (studio) */
#define PZ_CLI_OPT_GRAIN_HINTS (UINT64_C(1) << 56) /* --grain-hints FILE (flatten, run) */
#define PZ_CLI_OPT_CONSOLIDATE (UINT64_C(1) << 57) /* --consolidate on|off (run) */
#define PZ_CLI_OPT_MIRROR_SKETCH (UINT64_C(1) << 58) /* --mirror-sketch (run; a flag: stored as the value "1") */

/* `batch`: the batch ran, but one garment or more failed (summary.csv says which and why): exit 1. */
#define PZ_CLI_BATCH_FAILED ((pz_status)1)
#define PZ_CLI_EXIT_BATCH_FAILED 1

/* A command's outcome besides the pz_status codes (main.c maps it to its exit code, docs/cli.md): `run
 * --strict` wrote its files but the pattern misses its goals. */
#define PZ_CLI_GOALS_NOT_MET ((pz_status)3)
#define PZ_CLI_EXIT_GOALS_NOT_MET 3

/** Index of a raw-text option in pz_cli_args.values (bit position - PZ_CLI_VALUE_FIRST_BIT). */
#define PZ_CLI_VALUE_FIRST_BIT 9
#define PZ_CLI_VALUE_COUNT 50 /* up to bit 58 (--mirror-sketch) */
static inline int pz_cli_value_index(uint64_t flag)
{
    int bit = 0;
    while (!(flag & (UINT64_C(1) << bit)))
        ++bit;
    return bit - PZ_CLI_VALUE_FIRST_BIT;
}

/** The pattern-file options of `flatten` and `run` (export/export.h). */
#define PZ_CLI_OPT_EXPORT                                                                                   \
    (PZ_CLI_OPT_SEAM_ALLOWANCE | PZ_CLI_OPT_HEM_ALLOWANCE | PZ_CLI_OPT_ALLOWANCES | PZ_CLI_OPT_NOTCH_SPACING | \
     PZ_CLI_OPT_PAPER | PZ_CLI_OPT_FABRIC_WIDTH | PZ_CLI_OPT_GAP | PZ_CLI_OPT_DXF_STRICT | PZ_CLI_OPT_SIZE |      \
     PZ_CLI_OPT_OUTPUTS)

/** The options of `run` (the command table in main.c; `batch` takes them too, but --pose, and --panels uv only). */
#define PZ_CLI_OPT_RUN                                                                                           \
    (PZ_CLI_OPT_COMMON | PZ_CLI_OPT_UNITS | PZ_CLI_OPT_POSE | PZ_CLI_OPT_REPAIR | PZ_CLI_OPT_OUTPUT |            \
     PZ_CLI_OPT_PANELS | PZ_CLI_OPT_DARTS | PZ_CLI_OPT_GRAIN | PZ_CLI_OPT_BACKEND | PZ_CLI_OPT_ITERATIONS |      \
     PZ_CLI_OPT_WEIGHTS | PZ_CLI_OPT_FABRIC | PZ_CLI_OPT_SCHEME | PZ_CLI_OPT_RELAX | PZ_CLI_OPT_FEATURES |       \
     PZ_CLI_OPT_SKETCH | PZ_CLI_OPT_MAX_CORNERS | PZ_CLI_OPT_MAX_STRAIN | PZ_CLI_OPT_SYMMETRY |                 \
     PZ_CLI_OPT_PREPARE | PZ_CLI_OPT_TRUING | PZ_CLI_OPT_MAX_SEAM_MISMATCH | PZ_CLI_OPT_MIN_PIECE_WIDTH |       \
     PZ_CLI_OPT_MIN_PIECE_AREA | PZ_CLI_OPT_MIN_DART_INTAKE | PZ_CLI_OPT_STRICT | PZ_CLI_OPT_FOLD |             \
     PZ_CLI_OPT_MAX_PIECES | PZ_CLI_OPT_GRAIN_HINTS | PZ_CLI_OPT_CONSOLIDATE | PZ_CLI_OPT_MIRROR_SKETCH |      \
     PZ_CLI_OPT_EXPORT)

/** The options of `batch`: run's (--panels uv only), but --pose (per garment: a manifest's), and its own. */
#define PZ_CLI_OPT_BATCH                                                                                         \
    ((PZ_CLI_OPT_RUN & ~PZ_CLI_OPT_POSE) | PZ_CLI_OPT_JOBS | PZ_CLI_OPT_SHARD |           \
     PZ_CLI_OPT_RESUME | PZ_CLI_OPT_TIMEOUT | PZ_CLI_OPT_MERGE)

/** Options every command takes. */
#define PZ_CLI_OPT_COMMON (PZ_CLI_OPT_QUIET | PZ_CLI_OPT_JSON)

/** The parsed command line of one command. Strings point into argv. */
typedef struct pz_cli_args {
    const char *command;        /* the command's name, for messages */
    int quiet;                  /* --quiet */
    int json;                   /* --json */
    pz_units units;             /* --units; PZ_UNITS_AUTO = guess */
    unsigned repair_flags;      /* --repair: pz_repair_flags for pz_mesh_prepare */
    const char **pose_paths;    /* --pose files, in order (owned array) */
    int pose_path_count;
    const char *output_path;    /* -o, or NULL */
    int32_t target_faces;       /* --faces; 0 = the generator's default */
    int32_t pose_count;         /* --poses */
    int open;                   /* --open */
    const char *values[PZ_CLI_VALUE_COUNT]; /* raw text of --panels ... --smoothness, or NULL;
                                               read with pz_cli_value(args, PZ_CLI_OPT_X) */
    const char **seam_paths;    /* --seams files, in order (owned array) */
    int seam_path_count;
    const char **dart_paths;    /* --darts files, in order (owned array) */
    int dart_path_count;
    const char **positionals;   /* arguments that are not options (owned array) */
    int positional_count;
} pz_cli_args;

/** The raw text of a value option (PZ_CLI_OPT_PANELS ... PZ_CLI_OPT_SMOOTHNESS), or NULL when absent. */
static inline const char *pz_cli_value(const pz_cli_args *args, uint64_t flag)
{
    return args->values[pz_cli_value_index(flag)];
}

/** One command of the table in main.c. */
typedef struct pz_cli_command {
    const char *name;
    const char *summary;        /* one line for `panelize --help` */
    const char *usage;          /* full text for `panelize COMMAND --help` */
    uint64_t options;           /* accepted PZ_CLI_OPT_* bits */
    pz_status (*run)(const pz_cli_args *args, pz_ctx *ctx);
} pz_cli_command;

/* Commands (cmd_info.c, cmd_generate.c) and their help texts. */
pz_status pz_cli_info(const pz_cli_args *args, pz_ctx *ctx);
pz_status pz_cli_check(const pz_cli_args *args, pz_ctx *ctx);
pz_status pz_cli_generate(const pz_cli_args *args, pz_ctx *ctx);
pz_status pz_cli_flatten(const pz_cli_args *args, pz_ctx *ctx);   /* cmd_flatten.c */
pz_status pz_cli_field(const pz_cli_args *args, pz_ctx *ctx);     /* cmd_field.c */
pz_status pz_cli_prepare(const pz_cli_args *args, pz_ctx *ctx);   /* cmd_prepare.c */
pz_status pz_cli_run(const pz_cli_args *args, pz_ctx *ctx);       /* cmd_run.c */
pz_status pz_cli_batch(const pz_cli_args *args, pz_ctx *ctx);     /* cmd_batch.c */
pz_status pz_cli_studio(const pz_cli_args *args, pz_ctx *ctx);    /* cmd_studio.c */
extern const char pz_cli_studio_usage[];
extern const char pz_cli_batch_usage[];
extern const char pz_cli_run_usage[];
extern const char pz_cli_prepare_usage[];
extern const char pz_cli_flatten_usage[];
extern const char pz_cli_field_usage[];
extern const char pz_cli_info_usage[];
extern const char pz_cli_check_usage[];
extern const char pz_cli_generate_usage[];

/* ---------------------------------------------------------------- helpers (main.c) */

/**
 * Parses argv[first .. argc-1] as options of `command_name` accepting the
 * `accepted` PZ_CLI_OPT_* bits (the parser of every command; `batch` uses it
 * for a manifest line's options). On failure *args is cleared; on success the
 * caller frees it with pz_cli_args_clear. Strings point into argv.
 */
pz_status pz_cli_parse_args(const char *command_name, uint64_t accepted, int argc, char **argv, int first,
                            pz_cli_args *args, pz_ctx *ctx);
void pz_cli_args_clear(pz_cli_args *args);

/**
 * Requires exactly `count` positional arguments; otherwise PZ_ERR_USAGE
 * "COMMAND: expected WHAT".
 */
pz_status pz_cli_expect_positionals(const pz_cli_args *args, int count, const char *what, pz_ctx *ctx);

/**
 * Loads the mesh a command works on: reads `path` with the --pose files,
 * converts to millimetres (--units, or guessed; *units_used may be NULL) and
 * makes it valid through pz_mesh_prepare with the --repair flags. Fails with
 * PZ_ERR_INVALID_MESH (exit 65) naming the file when the mesh stays invalid.
 * Every command that needs a valid mesh goes through here.
 */
pz_status pz_cli_load_valid_mesh(const pz_cli_args *args, const char *path, pz_mesh **out,
                                 pz_units *units_used, pz_ctx *ctx);

/**
 * Converts a freshly read mesh to millimetres with --units, or a guess.
 * *plausible (may be NULL) says whether the size then fits a garment.
 */
void pz_cli_mesh_to_mm(const pz_cli_args *args, pz_mesh *mesh, pz_units *units_used, int *plausible);

/**
 * Warns on stderr when the units were guessed and the mesh (already in mm)
 * fits no garment. Call it once the command has succeeded: a failed run
 * prints exactly one line, its error.
 */
void pz_cli_warn_units(const pz_cli_args *args, const char *path, const pz_mesh *mesh, pz_units used,
                       pz_ctx *ctx);

/* ---------------------------------------------------------------- flatten and run (cli/options.c) */

/**
 * The options `flatten` and `run` share, from args into *options (set to the
 * library's defaults first): --units, --repair, --backend and its options,
 * --iterations, --weights, --fabric, --grain, the pattern-file options, -o
 * and the positional MESH. PZ_ERR_USAGE naming the option otherwise; checked
 * before any file is read.
 */
pz_status pz_cli_pipeline_options(const pz_cli_args *args, pz_run_options *options, pz_ctx *ctx);

/**
 * The positional MESH with its --pose files, or several panel files joined
 * (pz_mesh_join); file_vertex_offset (positional_count + 1, may be NULL)
 * receives where each file's vertices start. The mesh is in its files' units.
 */
pz_status pz_cli_read_meshes(const pz_cli_args *args, pz_mesh **mesh, int32_t *file_vertex_offset, pz_ctx *ctx);

/**
 * Every option of `run` from args into *options (pz_cli_pipeline_options,
 * then the goals, symmetry, darts, preparation, truing, sketch), messages
 * naming `run`. PZ_ERR_USAGE naming the option; no file is read.
 */
pz_status pz_cli_run_options(const pz_cli_args *args, pz_run_options *options, pz_ctx *ctx);

/** The files to write: --outputs, or all. */
pz_status pz_cli_outputs(const pz_cli_args *args, unsigned *outputs, pz_ctx *ctx);

/**
 * Writes the result's files into -o (all or nothing), then prints report.json
 * (--json) or the summary on stdout and the timings note on stderr.
 * read_ms: the time the command spent reading its inputs.
 */
pz_status pz_cli_write_result(const pz_cli_args *args, pz_result *result, double read_ms, pz_ctx *ctx);

/**
 * Progress on a terminal and Ctrl-C: when stderr is a terminal and --quiet is
 * not given, ctx->progress draws one updating line; SIGINT and SIGTERM set the
 * context's cancel flag so the library stops at its next check (exit 130).
 * pz_cli_progress_end clears the line and restores the signal handlers.
 */
void pz_cli_progress_begin(const pz_cli_args *args, pz_ctx *ctx);
void pz_cli_progress_end(pz_ctx *ctx);


/** A JSON array of 3 numbers, or NULL when out of memory. */
cJSON *pz_cli_json_vec3(const double values[3], int decimals);

/**
 * Prints `root` on stdout as one JSON document followed by a newline, and
 * deletes it. `build_failed` (some cJSON_Add* returned NULL) or a failed print
 * is PZ_ERR_NOMEM.
 */
pz_status pz_cli_print_json(cJSON *root, int build_failed, pz_ctx *ctx);

#endif /* PZ_CLI_H */
