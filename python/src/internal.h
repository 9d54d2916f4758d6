/*
 * python/src/internal.h -- the C extension panelize._panelize: what its files
 * share. The module is a thin caller of the library's public API
 * (pipeline/pipeline.h and the stage headers), as the command line is:
 *
 *   module.c   the module, its exception classes, and turning a failed
 *              pz_status into the matching panelize.Error subclass;
 *   arrays.c   numpy arrays in (checked: shape, dtype, indices) and out;
 *   work.c     running a library call on its own thread with the GIL
 *              released, while the caller's thread delivers progress to the
 *              Python callable and turns Ctrl-C into the library's cancel flag;
 *   options.c  keyword arguments into the library's options structs (the
 *              CLI's option names, its defaults, pz_run_options_check's ranges);
 *   calls.c    load, run, flatten, generate; calls_field.c: field, prepare;
 *   objects.c  the Mesh, Field, Prepared and Result types.
 *
 * Every function returning a PyObject * returns a new reference, or NULL with
 * a Python exception set. Functions returning int: 0 success, -1 with an
 * exception set.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_PYTHON_INTERNAL_H
#define PZ_PYTHON_INTERNAL_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL pz_python_numpy_api
#ifndef PZ_PYTHON_MODULE_C
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include "io/io.h"
#include "generate/generate.h"
#include "pipeline/pipeline.h"

/* ---------------------------------------------------------------- module.c: errors */

/** Raises the panelize.Error subclass of `status` with ctx->error as its message. Returns NULL. */
PyObject *pzpy_raise(pz_status status, const pz_ctx *ctx);

/** Raises panelize.UsageError with a formatted message (a bad keyword value found here). Returns NULL. */
PyObject *pzpy_usage_error(const char *fmt, ...);

/* ---------------------------------------------------------------- arrays.c */

/** A new (rows x cols) float64 array copied from `values` (may be NULL when rows is 0). */
PyObject *pzpy_doubles(const double *values, npy_intp rows, npy_intp cols);
/** A new int32 array: 1-D of `rows` when cols is 0, else rows x cols. */
PyObject *pzpy_ints(const int32_t *values, npy_intp rows, npy_intp cols);

/**
 * A pz_mesh (millimetres not applied: unit_scale 1) from numpy arrays:
 * vertices (n x 3, real numbers), faces (m x 3, integers, each in 0..n-1),
 * and optional poses (a sequence of n x 3 arrays or a k x n x 3 array),
 * labels (m integers >= 0), uv (k x 2) with uv_faces (m x 3 in 0..k-1).
 * Wrong types: TypeError; wrong shapes: ValueError, both naming the
 * argument; bad content (no faces, indices out of range): panelize.DataError.
 */
int pzpy_mesh_from_arrays(PyObject *vertices, PyObject *faces, PyObject *poses, PyObject *labels, PyObject *uv,
                          PyObject *uv_faces, pz_mesh **out);

/** The per-face int32 array `name` (face_count entries): a new int32 copy via *out (the caller frees). */
int pzpy_face_ints(PyObject *object, const char *name, int32_t face_count, int32_t **out);

/** Sketch curves from a sequence of k x 3 arrays (millimetres); *out NULL when the sequence is empty. */
int pzpy_sketch_from_curves(PyObject *curves, double scale, pz_sketch **out);

/* ---------------------------------------------------------------- work.c */

/** A library call to run off the GIL: `run` does the work (on another thread), with `ctx`. */
typedef struct pzpy_job {
    pz_status (*run)(struct pzpy_job *job, pz_ctx *ctx);
    void *data;
} pzpy_job;

/**
 * Runs job->run on a new thread with the GIL released and waits for it. The
 * waiting thread wakes every 20 ms: it calls `progress` (may be None) with
 * (stage, fraction, message) for each new report, polls Ctrl-C
 * (PyErr_CheckSignals) and `cancel` (None, or an object with is_set(), such
 * as threading.Event); either sets the library's cancel flag. Returns the
 * job's status; when a Python exception stopped it (KeyboardInterrupt, or
 * the progress callable raised), returns PZ_ERR_CANCELLED with that
 * exception set and *python_error = 1.
 */
pz_status pzpy_run_job(pzpy_job *job, pz_ctx *ctx, PyObject *progress, PyObject *cancel, int *python_error);

/* ---------------------------------------------------------------- options.c */

/** Keeps the bytes objects whose buffers the options point into alive until pzpy_keep_clear. */
typedef struct pzpy_keep {
    PyObject *list;
} pzpy_keep;
void pzpy_keep_clear(pzpy_keep *keep);

/** `path` (str or os.PathLike, or None) as a file-system path: *out stays NULL for None. */
int pzpy_path(PyObject *object, const char *name, pzpy_keep *keep, const char **out);

/** units=None|"auto"|"mm"|"cm"|"m". */
int pzpy_units(PyObject *object, pz_units *out);
/** repair=False|True: every repair of --repair. */
int pzpy_repair(PyObject *object, unsigned *out);

/**
 * The keyword options of run (and flatten, run_only 0) into *options (filled
 * from pz_run_options_default first; None keeps a default), checked with
 * pz_run_options_check. `kwargs` is consumed: the names used are deleted, so
 * the caller can refuse what is left.
 */
int pzpy_run_options(PyObject *kwargs, int run_only, pz_run_options *options, pzpy_keep *keep);

/** field's keyword options (scales, smoothness), checked with pz_field_options_check. */
int pzpy_field_options(PyObject *kwargs, pz_field_options *options);
/** prepare's keyword options (faces, edge, weld, keep), checked with pz_prepare_options_check. */
int pzpy_prepare_options(PyObject *kwargs, pz_prepare_options *options, pzpy_keep *keep);

/** A TypeError naming the first keyword left in kwargs (an unknown option). 0 when none is left. */
int pzpy_no_more_keywords(PyObject *kwargs, const char *function);

/** Pops kwargs[name] (a borrowed reference kept alive by `keep`; Py_None when absent). */
PyObject *pzpy_pop(PyObject *kwargs, const char *name, pzpy_keep *keep);

/* ---------------------------------------------------------------- objects.c */

extern PyTypeObject pzpy_mesh_type, pzpy_field_type, pzpy_prepared_type, pzpy_result_type;

/** A panelize.Mesh holding copies of the mesh's arrays (vertices in mm), its units and labels' names. */
PyObject *pzpy_mesh_object(const pz_mesh *mesh, pz_units units);
/** A panelize.Result taking ownership of *result (set to NULL). */
PyObject *pzpy_result_object(pz_result **result);
/** The pz_result a panelize.Result owns (borrowed). */
const pz_result *pzpy_result_of(PyObject *result);
/** Raises panelize.GoalsNotMetError ("run: goals not met (strict): REASONS") carrying `result`. */
void pzpy_goals_error(PyObject *result, const char *reasons);
/** Sets attribute `name` of `object` to `value`, stealing the reference; -1 (and value released) on failure. */
int pzpy_set(PyObject *object, const char *name, PyObject *value);
/** A list of `count` str (None where names or names[i] is NULL). */
PyObject *pzpy_names(char *const *names, int32_t count);
/** A Python object from a cJSON tree (dict, list, str, int, float, bool, None). */
PyObject *pzpy_from_json(const cJSON *item);

/* ---------------------------------------------------------------- calls.c */

/* The mesh arguments of run, flatten, field and prepare: arrays, or a panelize.Mesh in place of them. */
typedef struct pzpy_garment {
    PyObject *vertices, *faces, *poses, *labels, *uv, *uv_faces;
    const char *name;       /* the Mesh's file, for messages (kept alive by `keep`) */
    int from_mesh;          /* a panelize.Mesh: millimetres already */
} pzpy_garment;

/** Reads the positional (vertices, faces) or Mesh, and the keywords poses, labels, uv, uv_faces (popped). */
int pzpy_garment_from_call(PyObject *args, PyObject *kwargs, const char *function, pzpy_garment *garment,
                           pzpy_keep *keep);
/** The pz_mesh of the garment arguments (pzpy_mesh_from_arrays). */
int pzpy_garment_mesh(const pzpy_garment *garment, pz_mesh **out);
/** units= as given (None when absent): a Mesh is in millimetres unless units= says otherwise. */
int pzpy_garment_units(const pzpy_garment *garment, PyObject *kwargs, pzpy_keep *keep, pz_units *out);
/** Pops progress= and cancel= (Py_None when absent). */
int pzpy_pop_control(PyObject *kwargs, pzpy_keep *keep, PyObject **progress, PyObject **cancel);
/** A copy of the call's kwargs (or an empty dict) that the option parsers consume. */
PyObject *pzpy_consumable(PyObject *kwargs);
/** Runs job with progress and cancel, quietly; 0 on PZ_OK, else -1 with the exception set. */
int pzpy_run_job_or_raise(pzpy_job *job, PyObject *progress, PyObject *cancel);

PyObject *pzpy_load(PyObject *self, PyObject *args, PyObject *kwargs);
PyObject *pzpy_run(PyObject *self, PyObject *args, PyObject *kwargs);
PyObject *pzpy_flatten(PyObject *self, PyObject *args, PyObject *kwargs);
PyObject *pzpy_field(PyObject *self, PyObject *args, PyObject *kwargs);
PyObject *pzpy_prepare(PyObject *self, PyObject *args, PyObject *kwargs);
PyObject *pzpy_generate(PyObject *self, PyObject *args, PyObject *kwargs);
extern const char pzpy_load_doc[], pzpy_run_doc[], pzpy_flatten_doc[], pzpy_field_doc[], pzpy_prepare_doc[],
    pzpy_generate_doc[];

#endif /* PZ_PYTHON_INTERNAL_H */
