/*
 * studio/studio.h -- `panelize studio`: a local web server over pz_run
 * (docs/studio.md).
 *
 * The server (libmicrohttpd) serves the single-page app from its assets
 * folder and a small JSON API: load a garment (a path under the allowed
 * folder, or an upload), run it with the designer's options and sketched
 * strokes, follow the run's progress, cancel it, fetch the result (the
 * garment with a panel per face, seams, the flattened pattern with its
 * strain, the verdict) and its pattern files (SVG, PDF, DXF, GLB, ...).
 *
 *   pz_studio_options options;
 *   pz_studio_options_default(&options);
 *   options.port = 0;                         (any free port)
 *   pz_studio *studio = NULL;
 *   if (pz_studio_start(&options, &studio, &ctx) == PZ_OK) {
 *       printf("%s\n", pz_studio_url(studio));
 *       ... until the process is told to stop ...
 *   }
 *   pz_studio_stop(&studio);
 *
 * Each garment runs one pz_run at a time in a thread of its own: a new run
 * cancels the running one (through pz_ctx.cancel) and starts once it has
 * stopped. Every request is checked before any work: a bad one is a 4xx
 * answer {"error": "message"}, never a crash. By default the server listens
 * on 127.0.0.1 only and answers only requests whose Host names this machine.
 *
 * Not part of libpanelize: its own static library, linked into the panelize
 * command (cli/cmd_studio.c). POSIX threads.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_STUDIO_H
#define PZ_STUDIO_H

#include "core/core.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The largest upload accepted by default (a garment file): 64 MiB. */
#define PZ_STUDIO_DEFAULT_MAX_UPLOAD (64u << 20)
/** The most garments kept loaded at once: loading another drops the least recently used. */
#define PZ_STUDIO_MAX_GARMENTS 8

typedef struct pz_studio_options {
    const char *listen;          /* the address to listen on; NULL (default): 127.0.0.1 (this machine only) */
    int port;                    /* 0: any free port (pz_studio_url says which); default 8008 */
    const char *root;            /* the allowed folder: garments are read and files written under it only;
                                    NULL: the current directory */
    const char *assets;          /* the web app's folder; NULL: found beside the executable
                                    (share/panelize/studio) or in $PZ_STUDIO_ASSETS */
    size_t max_upload;           /* the largest upload (bytes) and request body; default PZ_STUDIO_DEFAULT_MAX_UPLOAD */
    const char *garment;         /* a garment to load at start (under root), or NULL */
} pz_studio_options;

void pz_studio_options_default(pz_studio_options *options);

typedef struct pz_studio pz_studio;

/**
 * Starts the server in threads of its own and returns. PZ_ERR_USAGE for a
 * bad listen address or port, PZ_ERR_OPEN for a root or assets folder that
 * cannot be read or a garment that cannot be loaded, PZ_ERR_CREATE when the
 * address cannot be bound. *out is freed with pz_studio_stop.
 */
pz_status pz_studio_start(const pz_studio_options *options, pz_studio **out, pz_ctx *ctx);

/** "http://ADDRESS:PORT/": the page's address (owned by the studio). */
const char *pz_studio_url(const pz_studio *studio);

/** Stops the server: cancels and waits for every run, frees everything; accepts NULL; sets *studio = NULL. */
void pz_studio_stop(pz_studio **studio);

#ifdef __cplusplus
}
#endif

#endif /* PZ_STUDIO_H */
