/*
 * batch/batch.h -- many garments, one call each, in worker processes
 * (docs/batch.md).
 *
 *   pz_batch_list_read: the garments of the inputs (files, folders searched
 *                       for meshes, manifests), each with its output folder
 *                       name, in one stable order (sorted by that name).
 *   pz_batch_run:       runs the garments of one shard, `jobs` at a time,
 *                       each in its own forked worker (a crash or a time-out
 *                       kills that garment only), writes each garment's
 *                       folder (pz_result_write) and its marker `batch.json`
 *                       last, then summary.csv and summary.jsonl.
 *   pz_batch_merge:     the shards' summaries joined into one.
 *   pz_batch_run_garment: the work of one garment (read, pz_run, write),
 *                       which a worker calls; usable on its own.
 *
 * The batch runner is a caller of pz_run like the command line: the options
 * of each garment come from the caller (the command line parses its own and
 * the manifest's), through the `work` callback run in the worker.
 *
 * Ownership: a list is the caller's (pz_batch_list_free); pz_batch_run and
 * pz_batch_merge own nothing they are given. POSIX only (fork, waitpid).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_BATCH_H
#define PZ_BATCH_H

#include "core/core.h"
#include "pipeline/pipeline.h"

#ifdef __cplusplus
extern "C" {
#endif

/** One garment of a batch. Every string is owned by the list. */
typedef struct pz_batch_garment {
    char *name;          /* its folder under OUTROOT: unique in the list, of [A-Za-z0-9._-], not starting with '.' */
    char *path;          /* the mesh file (a manifest's relative paths made relative to the current folder) */
    char *source;        /* where it was named, for messages: the file, FOLDER/..., or MANIFEST:LINE */
    char **args;         /* a manifest line's options after the path (file values resolved), or NULL */
    int arg_count;
    int32_t order;       /* its place in the stable order (0-based): garment i belongs to shard i mod N */
} pz_batch_garment;

/** Garments in their stable order (sorted by name, byte by byte). */
typedef struct pz_batch_list {
    pz_batch_garment *garments;
    int32_t count;
} pz_batch_list;

/**
 * The garments of `inputs`: a mesh file (.obj .ply .off .glb .gltf, any
 * case), a folder (searched through its sub-folders for such files; hidden
 * entries skipped, symbolic links to folders not followed), or a manifest
 * (.txt or .list: one garment per line, `PATH [OPTION]...`, docs/batch.md).
 * A garment's name is its path below the folder (or its file's base name)
 * without the extension, '/' written '-', other characters outside
 * [A-Za-z0-9._-] written '_'. Two garments of one name, a missing input, a
 * bad manifest line or no garment at all is an error naming the input
 * (PZ_ERR_USAGE, PZ_ERR_OPEN or PZ_ERR_DATA) and *out is NULL. On success the
 * caller frees *out with pz_batch_list_free.
 */
pz_status pz_batch_list_read(const char *const *inputs, int input_count, pz_batch_list **out, pz_ctx *ctx);

/** Frees a list; accepts NULL and *list == NULL; sets *list = NULL. */
void pz_batch_list_free(pz_batch_list **list);

/**
 * "I/N": shard I (0-based, 0 .. N-1, as Slurm's --array=0-(N-1) numbers its
 * tasks) of N, N in 1 .. 100000. PZ_ERR_USAGE naming the text otherwise.
 */
pz_status pz_batch_shard_parse(const char *text, int32_t *index, int32_t *count, pz_ctx *ctx);

/** What one garment's work reports (the worker fills it; the runner sends it to the batch). */
typedef struct pz_batch_outcome {
    pz_status status;        /* PZ_OK: the folder is written */
    int goals_judged;        /* 1 when goals_met says something */
    int goals_met;
    int32_t pieces;          /* the pattern's pieces (panels) */
    int32_t darts;
    double worst_strain;     /* worst |warp| or |weft| strain over panels and poses; -1 unknown */
    char message[1024];      /* the error (one line) when status is not PZ_OK */
} pz_batch_outcome;

/**
 * The work of one garment, run inside its worker process: write the result
 * of `garment` into `folder` and fill `outcome` (status, figures; the message
 * is taken from ctx->error). `threads` is the OpenMP threads it may use (the
 * runner has set them already). Returns the garment's status.
 */
typedef pz_status (*pz_batch_work_fn)(const pz_batch_garment *garment, const char *folder, int threads,
                                      pz_batch_outcome *outcome, void *user, pz_ctx *ctx);

typedef struct pz_batch_options {
    const char *outroot;     /* the garments' folders and the summaries go here (created when missing) */
    int jobs;                /* garments at once; 0 = 1 */
    int threads;             /* OpenMP threads per garment; 0 = the usable cores / jobs (at least 1) */
    double timeout_s;        /* a garment running longer is killed and recorded as "timeout"; 0 = none */
    int resume;              /* 1: a garment whose folder holds its marker (batch.json, status ok) is not run again */
    int strict;              /* 1: a pattern that misses its goals is a failure (category "goals") */
    int32_t shard_index;     /* run garments with order % shard_count == shard_index */
    int32_t shard_count;     /* 0: no sharding (summary.csv); N >= 1: shard I of N (summary-I-of-N.csv) */
    int progress;            /* 1: one updating line on stderr (a terminal); 0: a note per garment (ctx->quiet: none) */
    pz_batch_work_fn work;   /* required */
    void *user;              /* passed to work */
} pz_batch_options;

/** The counts of one batch (or of a merge). */
typedef struct pz_batch_totals {
    int32_t garments;        /* in this shard */
    int32_t ok;              /* written (including resumed) */
    int32_t resumed;         /* of them, skipped because their folder was complete */
    int32_t failed;          /* failed, crashed or timed out */
    int32_t pending;         /* not run: the batch was interrupted */
    double seconds;          /* the batch's wall time */
    char summary_csv[4096];  /* the summary written */
} pz_batch_totals;

/**
 * Runs the garments of `list` in the chosen shard (docs/batch.md): each in a
 * forked worker with `threads` threads, at most `jobs` at once, killed after
 * timeout_s. A garment that fails is recorded and the others go on. Writes
 * summary.csv and summary.jsonl (or summary-I-of-N.*) into outroot atomically,
 * one row per garment of the shard in the stable order. SIGINT or SIGTERM
 * stops the workers, records the unfinished garments as "pending" and
 * returns PZ_ERR_CANCELLED. Returns PZ_OK when the batch itself ran
 * (totals->failed says whether garments failed); PZ_ERR_CREATE when outroot
 * or a summary cannot be written.
 */
pz_status pz_batch_run(const pz_batch_list *list, const pz_batch_options *options, pz_batch_totals *totals,
                       pz_ctx *ctx);

/**
 * Joins the shards' summaries in outroot (summary-I-of-N.jsonl, every I of
 * one N present) into summary.csv and summary.jsonl, rows in the stable
 * order. A missing shard, summaries of different N or a row that does not
 * parse is an error naming the file (PZ_ERR_OPEN, PZ_ERR_DATA).
 */
pz_status pz_batch_merge(const char *outroot, pz_batch_totals *totals, pz_ctx *ctx);

/**
 * The work of one garment: reads `path` with its pose files, runs pz_run
 * with `options` and writes `outputs` (pz_output_file bits) into `folder`
 * (pz_result_write); fills outcome (its message from ctx->error on failure).
 * Returns the status.
 */
pz_status pz_batch_run_garment(const char *path, const char *const *pose_paths, int pose_count,
                               const pz_run_options *options, const char *folder, unsigned outputs,
                               pz_batch_outcome *outcome, pz_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* PZ_BATCH_H */
