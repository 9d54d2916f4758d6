/*
 * export/stream_status.h -- private to export/: how a writer reports a stream
 * that failed (a full disk, an I/O error): PZ_ERR_CREATE naming the file and
 * the system's reason, taken when the failure is seen (errno, else EIO).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_STREAM_STATUS_H
#define PZ_EXPORT_STREAM_STATUS_H

#include "mesh/mesh.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

/* PZ_OK when nothing failed on `file`; else PZ_ERR_CREATE "NAME: cannot write: REASON". error: an errno
 * recorded earlier (0: none, then the current errno or EIO). */
static inline pz_status pz_export_stream_status(FILE *file, int error, const char *name, pz_ctx *ctx)
{
    if (!error && !ferror(file))
        return PZ_OK;
    if (!error)
        error = errno ? errno : EIO;
    return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot write: %s", name, strerror(error));
}

#endif /* PZ_EXPORT_STREAM_STATUS_H */
