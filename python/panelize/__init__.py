# SPDX-License-Identifier: GPL-3.0-or-later
"""panelize: a 3D garment mesh in, a sewable 2D pattern out (numpy arrays in and out).

The functions are the command line's commands, with its option names as keyword
arguments (``--max-strain`` is ``max_strain=``), its defaults and its ranges:

    load(path)                 -> Mesh    (vertices in mm, faces, poses, labels, uv)
    run(vertices, faces, ...)  -> Result  (panels, pattern coordinates, seams, darts, report, write())
    flatten(vertices, faces, panels=...) -> Result  (the user's own panels)
    field(vertices, faces, ...) -> Field   (the cross-field)
    prepare(vertices, faces, ...) -> Prepared (welded, repaired, remeshed mesh)
    generate(shape, faces=...) -> Mesh    (synthetic garments)
    run_file(path, folder, ...) -> dict   (one garment, file to folder: for process pools and Dask)

A Mesh can stand in for (vertices, faces). Failures raise a subclass of
panelize.Error carrying the command line's category and exit code. The GIL is
released while the library works; Ctrl-C stops a call within a fraction of a
second. See docs/python.md.
"""

from ._panelize import (  # noqa: F401  (the C extension: python/src/)
    CancelledError,
    CreateError,
    DataError,
    Error,
    Field,
    GoalsNotMetError,
    InternalError,
    Mesh,
    OpenError,
    Prepared,
    Result,
    UsageError,
    __version__,
    field,
    flatten,
    generate,
    load,
    prepare,
    run,
)

__all__ = [
    "CancelledError", "CreateError", "DataError", "Error", "Field", "GoalsNotMetError", "InternalError", "Mesh",
    "OpenError", "Prepared", "Result", "UsageError", "field", "flatten", "generate", "load", "prepare", "run",
    "run_file",
]


def run_file(path, folder, outputs=None, poses=(), units=None, **options):
    """Runs one garment file into one pattern folder and returns a small summary dict.

    The per-garment function for pools of workers (concurrent.futures, Dask): it takes and
    returns only plain, picklable values, so it can run in another process or machine.
    ``path``: the garment file; ``folder``: its pattern folder (written all or nothing, as
    Result.write); ``outputs``: the files to write (None: every one); ``poses``: pose files;
    ``units`` and ``**options``: as in run(). A failure raises as run() does: a pool
    reports it through the future.

    Returns {"path", "folder", "panels", "darts", "goals_met", "worst_strain", "seconds"}.
    """
    import time

    start = time.monotonic()
    mesh = load(path, units=units, poses=poses)
    result = run(mesh, **options)
    result.write(folder, outputs=outputs)
    return {
        "path": str(path),
        "folder": str(folder),
        "panels": result.panel_count,
        "darts": len(result.darts),
        "goals_met": result.goals_met,
        "worst_strain": result.worst_strain,
        "seconds": round(time.monotonic() - start, 3),
    }
