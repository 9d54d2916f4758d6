/*
 * cli/cmd_studio.c -- `panelize studio [GARMENT] [--port N] [--listen ADDR]
 * [--root DIR]`: starts the studio's web server (studio/studio.h), prints
 * its address, and serves until Ctrl-C or SIGTERM (then exit 0).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _XOPEN_SOURCE 700
#include "cli/cli.h"
#include "studio/studio.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char pz_cli_studio_usage[] =
    "usage: panelize studio [GARMENT] [--port N] [--listen ADDR] [--root DIR] [--quiet]\n"
    "\n"
    "Starts a local web page to work on a garment: orbit the 3D garment coloured\n"
    "by panel, draw seam strokes on it, set the goals, and see the pattern and\n"
    "its strain update; download the pattern files. Prints the page's address\n"
    "and serves until Ctrl-C. Nothing is fetched from the network.\n"
    "\n"
    "options:\n"
    "  GARMENT          a garment to open at start (under the allowed folder)\n"
    "  --port N         the port (default 8008; 0: any free port)\n"
    "  --listen ADDR    the address to listen on (default 127.0.0.1: this machine\n"
    "                   only; another address lets other machines in)\n"
    "  --root DIR       the allowed folder: garments are opened and pattern files\n"
    "                   written under it only (default: GARMENT's folder, or the\n"
    "                   current one)\n"
    "\n"
    "See docs/studio.md.\n";

pz_status pz_cli_studio(const pz_cli_args *args, pz_ctx *ctx)
{
    if (args->positional_count > 1)
        return pz_error(ctx, PZ_ERR_USAGE, "studio: expected at most one GARMENT, got %d", args->positional_count);
    pz_studio_options options;
    pz_studio_options_default(&options);
    const char *port = pz_cli_value(args, PZ_CLI_OPT_PORT);
    if (port) {
        char *end = NULL;
        errno = 0;
        long value = strtol(port, &end, 10);
        if (end == port || *end || errno || value < 0 || value > 65535)
            return pz_error(ctx, PZ_ERR_USAGE, "studio: --port: '%s' is not a port (0 .. 65535)", port);
        options.port = (int)value;
    }
    options.listen = pz_cli_value(args, PZ_CLI_OPT_LISTEN);
    options.root = pz_cli_value(args, PZ_CLI_OPT_ROOT);
    options.garment = args->positional_count ? args->positionals[0] : NULL;
    /* The garment by its real path (the server reads paths relative to the allowed folder); its own
     * folder is the allowed one unless --root says otherwise. */
    char *garment_path = NULL, *garment_folder = NULL;
    if (options.garment) {
        garment_path = realpath(options.garment, NULL);
        if (!garment_path)
            return pz_error(ctx, PZ_ERR_OPEN, "%s: cannot open: %s", options.garment, strerror(errno));
        options.garment = garment_path;
    }
    if (garment_path && !options.root) {
        garment_folder = strdup(garment_path);
        if (!garment_folder) {
            free(garment_path);
            return pz_error(ctx, PZ_ERR_NOMEM, "studio: out of memory");
        }
        *strrchr(garment_folder, '/') = '\0';
        options.root = garment_folder[0] ? garment_folder : "/";
    }
    /* The server's threads inherit a mask without SIGINT and SIGTERM: this thread waits for them. */
    sigset_t signals, old_mask;
    sigemptyset(&signals);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals, &old_mask);
    pz_studio *studio = NULL;
    pz_status status = pz_studio_start(&options, &studio, ctx);
    if (status == PZ_OK) {
        printf("panelize studio: %s\n", pz_studio_url(studio));
        fflush(stdout);
        pz_note(ctx, "studio: serving; Ctrl-C stops");
        int received = 0;
        sigwait(&signals, &received);
        pz_note(ctx, "studio: stopping");
    }
    pz_studio_stop(&studio);
    free(garment_folder);
    free(garment_path);
    pthread_sigmask(SIG_SETMASK, &old_mask, NULL);
    return status;
}
