/*
 * python/src/options.c -- keyword arguments into the library's options
 * structs. The names are the command line's (--max-strain is max_strain=),
 * a value of None keeps the library's default (pz_run_options_default and the
 * stages' _default functions: the only place the defaults live), and the
 * ranges are the library's own (pz_run_options_check, pz_field_options_check,
 * pz_prepare_options_check), so a value the CLI refuses is refused here with
 * the same words. What stays here is only turning Python values into C ones:
 * a string where a number belongs is a TypeError, an unknown word a
 * UsageError listing the words.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <string.h>

void pzpy_keep_clear(pzpy_keep *keep)
{
    Py_CLEAR(keep->list);
}

/* Holds a reference to `object` until pzpy_keep_clear. */
static int keep_alive(pzpy_keep *keep, PyObject *object)
{
    if (!keep->list && !(keep->list = PyList_New(0)))
        return -1;
    return PyList_Append(keep->list, object);
}

PyObject *pzpy_pop(PyObject *kwargs, const char *name, pzpy_keep *keep)
{
    PyObject *value = kwargs ? PyDict_GetItemString(kwargs, name) : NULL;
    if (!value)
        return Py_None;
    if (keep_alive(keep, value) < 0 || PyDict_DelItemString(kwargs, name) < 0)
        return NULL;
    return value;
}

int pzpy_no_more_keywords(PyObject *kwargs, const char *function)
{
    Py_ssize_t position = 0;
    PyObject *key, *value;
    if (kwargs && PyDict_Next(kwargs, &position, &key, &value)) {
        PyErr_Format(PyExc_TypeError, "%s() got an unexpected keyword argument %R", function, key);
        return -1;
    }
    return 0;
}

/* ---------------------------------------------------------------- values */

/* A real number (not a bool, not a string) into *out; None leaves it. */
static int number(PyObject *object, const char *name, double *out)
{
    if (object == Py_None)
        return 0;
    if (PyBool_Check(object) || PyUnicode_Check(object) || PyBytes_Check(object) || !PyNumber_Check(object)) {
        PyErr_Format(PyExc_TypeError, "%s: expected a number, got %.80s", name, Py_TYPE(object)->tp_name);
        return -1;
    }
    double value = PyFloat_AsDouble(object);
    if (value == -1.0 && PyErr_Occurred()) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: expected a real number, got %.80s", name, Py_TYPE(object)->tp_name);
        return -1;
    }
    *out = value;
    return 0;
}

/* A whole number (an int, or a float or numpy scalar with no fraction) into *out; the range is the library's. */
static int whole(PyObject *object, const char *name, double *out)
{
    double value = *out;
    if (number(object, name, &value) < 0)
        return -1;
    if (object != Py_None && !isfinite(value)) {
        pzpy_usage_error("%s: %g is not a whole number", name, value);
        return -1;
    }
    if (object != Py_None && value != floor(value)) {
        PyErr_Format(PyExc_TypeError, "%s: expected a whole number, got %R", name, object);
        return -1;
    }
    *out = value;
    return 0;
}

/* `count` numbers from a sequence into out; None leaves them and *given. */
static int numbers(PyObject *object, const char *name, int count, double *out, int *given)
{
    if (object == Py_None)
        return 0;
    PyObject *items = PyUnicode_Check(object) ? NULL : PySequence_Fast(object, "");
    if (!items || PySequence_Fast_GET_SIZE(items) != count) {
        PyErr_Clear();
        PyErr_Format(PyExc_ValueError, "%s: expected a sequence of %d numbers", name, count);
        Py_XDECREF(items);
        return -1;
    }
    int status = 0;
    for (int i = 0; i < count && status == 0; ++i)
        status = number(PySequence_Fast_GET_ITEM(items, i), name, &out[i]);
    Py_DECREF(items);
    if (status == 0 && given)
        *given = 1;
    return status;
}

/* A whole number as an int for the library's range check: beyond int's reach it becomes INT_MAX or
 * INT_MIN, which every whole-number option refuses, naming it. */
static int as_int(double value)
{
    return value > 1e9 ? INT_MAX : value < -1e9 ? INT_MIN : (int)value; /* the caller passes finite values */
}

/* True/False (or the CLI's words "on"/"off") into *out; None leaves it. */
static int flag(PyObject *object, const char *name, int *out)
{
    if (object == Py_None)
        return 0;
    if (PyBool_Check(object)) {
        *out = object == Py_True;
        return 0;
    }
    const char *text = PyUnicode_Check(object) ? PyUnicode_AsUTF8(object) : NULL;
    if (text && (strcmp(text, "on") == 0 || strcmp(text, "off") == 0)) {
        *out = strcmp(text, "on") == 0;
        return 0;
    }
    PyErr_Clear();
    PyErr_Format(PyExc_TypeError, "%s: expected True or False (or \"on\"/\"off\"), got %R", name, object);
    return -1;
}

/* One of `count` words into *index; a string that is none of them is a UsageError listing them. */
static int word(PyObject *object, const char *name, const char *const *words, int count, int *index)
{
    const char *text = PyUnicode_Check(object) ? PyUnicode_AsUTF8(object) : NULL;
    if (!text) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: expected a string, got %.80s", name, Py_TYPE(object)->tp_name);
        return -1;
    }
    char list[160] = "";
    size_t used = 0;
    for (int i = 0; i < count; ++i) {
        if (strcmp(text, words[i]) == 0) {
            *index = i;
            return 0;
        }
        if (used < sizeof list)
            used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", i == 0 ? "" : i + 1 < count ? ", " : " or ",
                                     words[i]);
    }
    pzpy_usage_error("%s: '%s' is not %s", name, text, list);
    return -1;
}

int pzpy_path(PyObject *object, const char *name, pzpy_keep *keep, const char **out)
{
    if (object == Py_None)
        return 0;
    PyObject *bytes = NULL;
    if (!PyUnicode_FSConverter(object, &bytes)) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: expected a path (str or os.PathLike), got %.80s", name,
                     Py_TYPE(object)->tp_name);
        return -1;
    }
    int status = keep_alive(keep, bytes);
    Py_DECREF(bytes);
    if (status < 0)
        return -1;
    *out = PyBytes_AS_STRING(bytes);
    if (!**out) {
        pzpy_usage_error("%s: empty file name", name);
        return -1;
    }
    return 0;
}

/* A string kept alive by the popped kwargs (pzpy_pop keeps it). */
static int text(PyObject *object, const char *name, const char **out)
{
    if (object == Py_None)
        return 0;
    const char *value = PyUnicode_Check(object) ? PyUnicode_AsUTF8(object) : NULL;
    if (!value) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: expected a string, got %.80s", name, Py_TYPE(object)->tp_name);
        return -1;
    }
    *out = value;
    return 0;
}

int pzpy_units(PyObject *object, pz_units *out)
{
    static const char *const names[] = {"auto", "mm", "cm", "m"};
    static const pz_units units[] = {PZ_UNITS_AUTO, PZ_UNITS_MM, PZ_UNITS_CM, PZ_UNITS_M};
    int index = 0;
    if (object != Py_None && word(object, "units", names, 4, &index) < 0)
        return -1;
    *out = object == Py_None ? PZ_UNITS_AUTO : units[index];
    return 0;
}

int pzpy_repair(PyObject *object, unsigned *out)
{
    int repair = 0;
    if (flag(object, "repair", &repair) < 0)
        return -1;
    *out = repair ? PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES | PZ_REPAIR_ORIENT : 0;
    return 0;
}

/* 0 when the library's check passed, else -1 with its UsageError raised. */
static int checked(pz_status status, const pz_ctx *ctx)
{
    return status == PZ_OK ? 0 : (pzpy_raise(status, ctx), -1);
}

/* ---------------------------------------------------------------- run and flatten */

/* backend and its own options (scheme for wirewarp, relax for springmass, features for wirewarp). */
static int backend_options(PyObject *kwargs, pz_flatten_options *flatten, pzpy_keep *keep)
{
    static const char *const backends[] = {"textile", "lscm", "wirewarp", "springmass"};
    static const char *const schemes[] = {"global", "progressive"};
    static const char *const relaxations[] = {"heap", "full"};
    PyObject *backend = pzpy_pop(kwargs, "backend", keep), *scheme = pzpy_pop(kwargs, "scheme", keep);
    PyObject *relax = pzpy_pop(kwargs, "relax", keep), *features = pzpy_pop(kwargs, "features", keep);
    if (!backend || !scheme || !relax || !features)
        return -1;
    int index = 0;
    if (backend != Py_None) {
        if (word(backend, "backend", backends, 4, &index) < 0)
            return -1;
        flatten->backend = (pz_backend)index;
    }
    const char *name = pz_backend_name(flatten->backend);
    if (scheme != Py_None && flatten->backend != PZ_BACKEND_WIREWARP)
        return pzpy_usage_error("flatten: scheme works with backend=\"wirewarp\", not %s", name), -1;
    if (relax != Py_None && flatten->backend != PZ_BACKEND_SPRINGMASS)
        return pzpy_usage_error("flatten: relax works with backend=\"springmass\", not %s", name), -1;
    if (features != Py_None && flatten->backend != PZ_BACKEND_WIREWARP)
        return pzpy_usage_error("flatten: features works with backend=\"wirewarp\", not %s", name), -1;
    if (scheme != Py_None && word(scheme, "scheme", schemes, 2, &flatten->progressive) < 0)
        return -1;
    if (relax != Py_None && word(relax, "relax", relaxations, 2, &flatten->relax_full) < 0)
        return -1;
    return pzpy_path(features, "features", keep, &flatten->features_path);
}

static int flatten_options(PyObject *kwargs, pz_flatten_options *flatten, pzpy_keep *keep)
{
    if (backend_options(kwargs, flatten, keep) < 0)
        return -1;
    double iterations = flatten->iterations, fabric[3];
    PyObject *value;
    if (!(value = pzpy_pop(kwargs, "iterations", keep)) || whole(value, "iterations", &iterations) < 0)
        return -1;
    flatten->iterations = as_int(iterations);
    if (!(value = pzpy_pop(kwargs, "weights", keep)) || numbers(value, "weights", 4, flatten->weights, NULL) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "fabric", keep)) || numbers(value, "fabric", 3, fabric, &flatten->fabric_given) < 0)
        return -1;
    if (flatten->fabric_given)
        flatten->fabric = (pz_fabric){fabric[0], fabric[1], fabric[2]};
    if (!(value = pzpy_pop(kwargs, "grain", keep)))
        return -1;
    return numbers(value, "grain", 3, flatten->grain, &flatten->grain_given);
}

/* The pattern files' options (export/export.h). */
static int export_options(PyObject *kwargs, pz_run_options *run, pzpy_keep *keep)
{
    pz_export_options *output = &run->output;
    static const struct {
        const char *name;
        size_t offset;
    } lengths[] = {{"seam_allowance", offsetof(pz_export_options, seam_allowance_mm)},
                   {"hem_allowance", offsetof(pz_export_options, hem_allowance_mm)},
                   {"notch_spacing", offsetof(pz_export_options, notch_spacing_mm)},
                   {"fabric_width", offsetof(pz_export_options, fabric_width_mm)},
                   {"gap", offsetof(pz_export_options, gap_mm)}};
    PyObject *value;
    int hem_given = 0;
    for (size_t i = 0; i < sizeof lengths / sizeof lengths[0]; ++i) {
        if (!(value = pzpy_pop(kwargs, lengths[i].name, keep)) ||
            number(value, lengths[i].name, (double *)((char *)output + lengths[i].offset)) < 0)
            return -1;
        hem_given |= i == 1 && value != Py_None;
    }
    if (!hem_given) /* the CLI's rule: open edges get the seam allowance unless told otherwise */
        output->hem_allowance_mm = output->seam_allowance_mm;
    const char *paper = NULL;
    if (!(value = pzpy_pop(kwargs, "paper", keep)) || text(value, "paper", &paper) < 0)
        return -1;
    if (paper)
        output->paper = (paper[0] == 'a' || paper[0] == 'A') && (paper[1] == '4') && !paper[2] ? "a4"
                        : strcasecmp(paper, "letter") == 0                                     ? "letter"
                                                                                               : paper;
    if (!(value = pzpy_pop(kwargs, "dxf_strict", keep)) || flag(value, "dxf_strict", &output->dxf_strict) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "size", keep)) || text(value, "size", &output->size_name) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "allowances", keep)) || pzpy_path(value, "allowances", keep, &run->allowances_path) < 0)
        return -1;
    return 0;
}

/* symmetry="auto"|"off"|"x"|"y"|"z", or a plane: (nx, ny, nz, d) or (px, py, pz, nx, ny, nz), in the garment's units. */
static int symmetry_option(PyObject *object, pz_segment_options *segment)
{
    static const char *const names[] = {"auto", "off", "x", "y", "z"};
    static const pz_symmetry_mode modes[] = {PZ_SYMMETRY_AUTO, PZ_SYMMETRY_OFF, PZ_SYMMETRY_X, PZ_SYMMETRY_Y,
                                             PZ_SYMMETRY_Z};
    if (object == Py_None)
        return 0;
    int index = 0;
    if (PyUnicode_Check(object)) {
        if (word(object, "symmetry", names, 5, &index) < 0)
            return -1;
        segment->symmetry = modes[index];
        return 0;
    }
    Py_ssize_t count = PySequence_Check(object) ? PySequence_Size(object) : -1;
    double values[6];
    if ((count != 4 && count != 6) || numbers(object, "symmetry", (int)count, values, NULL) < 0) {
        if (!PyErr_Occurred() || PyErr_ExceptionMatches(PyExc_ValueError)) {
            PyErr_Clear();
            pzpy_usage_error("symmetry: expected auto, off, x, y, z, a plane (nx, ny, nz, d) or a point and a normal "
                             "(px, py, pz, nx, ny, nz)");
        }
        return -1;
    }
    const double *n = count == 6 ? values + 3 : values;
    segment->symmetry = PZ_SYMMETRY_PLANE;
    memcpy(segment->symmetry_plane, n, 3 * sizeof(double));
    segment->symmetry_plane[3] = count == 4 ? values[3] : n[0] * values[0] + n[1] * values[1] + n[2] * values[2];
    return 0;
}

/* The goals and the segmentation's switches (run only). */
static int run_only_options(PyObject *kwargs, pz_run_options *options, pzpy_keep *keep)
{
    static const struct {
        const char *name;
        size_t offset;
    } goals[] = {{"max_strain", offsetof(pz_goal_options, max_strain)},
                 {"max_seam_mismatch", offsetof(pz_goal_options, max_seam_mismatch)},
                 {"min_piece_width", offsetof(pz_goal_options, min_piece_width_mm)},
                 {"min_piece_area", offsetof(pz_goal_options, min_piece_area)},
                 {"min_dart_intake", offsetof(pz_goal_options, min_dart_intake_mm)}};
    PyObject *value;
    for (size_t i = 0; i < sizeof goals / sizeof goals[0]; ++i)
        if (!(value = pzpy_pop(kwargs, goals[i].name, keep)) ||
            number(value, goals[i].name, (double *)((char *)&options->goals + goals[i].offset)) < 0)
            return -1;
    double corners = options->goals.max_corners;
    if (!(value = pzpy_pop(kwargs, "max_corners", keep)) || whole(value, "max_corners", &corners) < 0)
        return -1;
    options->goals.max_corners = as_int(corners);
    static const char *const prepare_modes[] = {"off", "auto"};
    if (!(value = pzpy_pop(kwargs, "prepare", keep)))
        return -1;
    if (value != Py_None && (PyBool_Check(value) ? (options->prepare = value == Py_True, 0)
                                                 : word(value, "prepare", prepare_modes, 2, &options->prepare)) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "symmetry", keep)) || symmetry_option(value, &options->segment) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "fold", keep)) || flag(value, "fold", &options->output.fold) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "darts", keep)) || flag(value, "darts", &options->segment.darts) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "truing", keep)) || flag(value, "truing", &options->truing) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "consolidate", keep)) || flag(value, "consolidate", &options->consolidate) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "mirror_sketch", keep)) ||
        flag(value, "mirror_sketch", &options->mirror_sketch) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "sketch", keep)) || pzpy_path(value, "sketch", keep, &options->sketch_path) < 0)
        return -1;
    return 0;
}

int pzpy_run_options(PyObject *kwargs, int run_only, pz_run_options *options, pzpy_keep *keep)
{
    pz_run_options_default(options);
    PyObject *value;
    if (!(value = pzpy_pop(kwargs, "units", keep)) || pzpy_units(value, &options->units) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "repair", keep)) || pzpy_repair(value, &options->repair_flags) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "name", keep)) || text(value, "name", &options->name) < 0)
        return -1;
    if (flatten_options(kwargs, &options->flatten, keep) < 0 || export_options(kwargs, options, keep) < 0)
        return -1;
    /* --grain-hints FILE: the warp along each stroke in its piece (run and flatten). */
    if (!(value = pzpy_pop(kwargs, "grain_hints", keep)) ||
        pzpy_path(value, "grain_hints", keep, &options->grain_hints_path) < 0)
        return -1;
    if (run_only && run_only_options(kwargs, options, keep) < 0)
        return -1;
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    return checked(pz_run_options_check(options, run_only ? "run" : "flatten", PZ_OPTION_KEYWORD, &ctx), &ctx);
}

/* ---------------------------------------------------------------- field and prepare */

int pzpy_field_options(PyObject *kwargs, pz_field_options *options)
{
    pzpy_keep keep = {NULL};
    pz_field_options_default(options);
    options->use_poses = 1;
    options->scale_count = PZ_FIELD_DEFAULT_SCALES;
    options->smoothness = PZ_FIELD_DEFAULT_SMOOTHNESS;
    double scales = options->scale_count;
    PyObject *value;
    int status = (value = pzpy_pop(kwargs, "scales", &keep)) && whole(value, "scales", &scales) == 0 &&
                         (value = pzpy_pop(kwargs, "smoothness", &keep)) &&
                         number(value, "smoothness", &options->smoothness) == 0
                     ? 0
                     : -1;
    pzpy_keep_clear(&keep);
    if (status < 0)
        return -1;
    options->scale_count = as_int(scales);
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    return checked(pz_field_options_check(options, "field", PZ_OPTION_KEYWORD, &ctx), &ctx);
}

int pzpy_prepare_options(PyObject *kwargs, pz_prepare_options *options, pzpy_keep *keep)
{
    pz_prepare_options_default(options);
    double faces = 0, weld = options->weld_distance;
    PyObject *value;
    if (!(value = pzpy_pop(kwargs, "faces", keep)) || whole(value, "faces", &faces) < 0)
        return -1;
    options->target_faces = as_int(faces);
    if (!(value = pzpy_pop(kwargs, "edge", keep)) || number(value, "edge", &options->target_edge) < 0)
        return -1;
    if (!(value = pzpy_pop(kwargs, "weld", keep)) || number(value, "weld", &weld) < 0)
        return -1;
    options->weld_distance = value != Py_None && weld == 0.0 ? -1.0 : weld; /* the CLI's --weld 0: no welding */
    static const char *const keeps[] = {"largest", "all"};
    int index = 0;
    if (!(value = pzpy_pop(kwargs, "keep", keep)) || (value != Py_None && word(value, "keep", keeps, 2, &index) < 0))
        return -1;
    options->keep = index ? PZ_PREPARE_KEEP_ALL : PZ_PREPARE_KEEP_LARGEST;
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    return checked(pz_prepare_options_check(options, "prepare", PZ_OPTION_KEYWORD, &ctx), &ctx);
}
