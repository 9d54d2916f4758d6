/*
 * python/src/arrays.c -- numpy arrays in and out. Every array from Python is
 * hostile until checked: its type (real numbers for coordinates, integers for
 * indices: TypeError naming the argument), its shape (ValueError naming it),
 * its size (int32 counts), and its indices (each in range: panelize.DataError,
 * the category a file with the same problem gets). NaN coordinates pass on to
 * the library, which repairs or refuses them as it does a file's.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <string.h>

static PyObject *data_error(const char *fmt, ...)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    va_list arguments;
    va_start(arguments, fmt);
    vsnprintf(ctx.error, sizeof ctx.error, fmt, arguments);
    va_end(arguments);
    return pzpy_raise(PZ_ERR_DATA, &ctx);
}

/* A new array of `type` (items of `size` bytes): 1-D of `rows` when cols is 0, else rows x cols, copied. */
static PyObject *new_copy(const void *values, npy_intp rows, npy_intp cols, int type, size_t size)
{
    npy_intp shape[2] = {rows, cols};
    PyObject *array = PyArray_SimpleNew(cols ? 2 : 1, shape, type);
    if (array && rows * (cols ? cols : 1) > 0)
        memcpy(PyArray_DATA((PyArrayObject *)array), values, (size_t)(rows * (cols ? cols : 1)) * size);
    return array;
}

PyObject *pzpy_doubles(const double *values, npy_intp rows, npy_intp cols)
{
    return new_copy(values, rows, cols, NPY_FLOAT64, sizeof(double));
}

PyObject *pzpy_ints(const int32_t *values, npy_intp rows, npy_intp cols)
{
    return new_copy(values, rows, cols, NPY_INT32, sizeof(int32_t));
}

/*
 * `object` as a C-contiguous array of `type` (NPY_FLOAT64 or NPY_INT64) with
 * `ndim` dimensions, the last `columns` wide (0: any). Only real numbers
 * (integers too, for float64) or integers are accepted.
 */
static PyArrayObject *as_array(PyObject *object, const char *name, int type, int ndim, npy_intp columns)
{
    PyArrayObject *given = (PyArrayObject *)PyArray_FROM_O(object);
    if (!given) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: expected an array of %s, got %.80s", name,
                     type == NPY_FLOAT64 ? "numbers" : "integers", Py_TYPE(object)->tp_name);
        return NULL;
    }
    int kind = PyArray_DESCR(given)->kind;
    int accepted = type == NPY_FLOAT64 ? (kind == 'f' || kind == 'i' || kind == 'u') : (kind == 'i' || kind == 'u');
    if (!accepted && PyArray_SIZE(given) > 0) {
        PyErr_Format(PyExc_TypeError, "%s: expected %s, got an array of dtype %S", name,
                     type == NPY_FLOAT64 ? "real numbers (float64)" : "integers (int32 or int64)",
                     (PyObject *)PyArray_DESCR(given));
        Py_DECREF(given);
        return NULL;
    }
    int shape_ok = PyArray_NDIM(given) == ndim && (!columns || PyArray_DIM(given, ndim - 1) == columns);
    if (!shape_ok) {
        PyObject *shape = PyObject_GetAttrString((PyObject *)given, "shape");
        if (columns)
            PyErr_Format(PyExc_ValueError, "%s: expected shape (%s%" NPY_INTP_FMT "), got %S", name,
                         ndim == 3 ? "k, n, " : "n, ", columns, shape ? shape : Py_None);
        else
            PyErr_Format(PyExc_ValueError, "%s: expected a %d-dimensional array, got shape %S", name, ndim,
                         shape ? shape : Py_None);
        Py_XDECREF(shape);
        Py_DECREF(given);
        return NULL;
    }
    if (PyArray_SIZE(given) > INT32_MAX / 4) {
        PyErr_Format(PyExc_ValueError, "%s: %" NPY_INTP_FMT " values are more than panelize takes", name,
                     PyArray_SIZE(given));
        Py_DECREF(given);
        return NULL;
    }
    PyArrayObject *array = (PyArrayObject *)PyArray_FROM_OTF((PyObject *)given, type,
                                                             NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED |
                                                                 NPY_ARRAY_FORCECAST);
    Py_DECREF(given);
    return array;
}

/* Integers of `array` (int64) into int32 `out`, each in 0..limit-1 (limit < 0: any non-negative). */
static int copy_indices(PyArrayObject *array, const char *name, const char *what, int64_t limit, int32_t *out)
{
    const int64_t *values = PyArray_DATA(array);
    npy_intp count = PyArray_SIZE(array);
    for (npy_intp i = 0; i < count; ++i) {
        if (values[i] < 0 || (limit >= 0 && values[i] >= limit) || values[i] > INT32_MAX) {
            if (limit >= 0)
                data_error("%s: entry %" NPY_INTP_FMT " is %lld, not a %s in 0..%lld", name, i, (long long)values[i],
                           what, (long long)limit - 1);
            else
                data_error("%s: entry %" NPY_INTP_FMT " is %lld, not a %s >= 0", name, i, (long long)values[i], what);
            return -1;
        }
        out[i] = (int32_t)values[i];
    }
    return 0;
}

/* poses: None, a sequence of n x 3 arrays, or a k x n x 3 array, added to mesh. */
static int add_poses(PyObject *poses, pz_mesh *mesh)
{
    if (poses == Py_None)
        return 0;
    PyObject *items = PySequence_Fast(poses, "poses: expected a sequence of (n, 3) arrays or a (k, n, 3) array");
    if (!items)
        return -1;
    int status = 0;
    for (Py_ssize_t p = 0; p < PySequence_Fast_GET_SIZE(items) && status == 0; ++p) {
        char name[32];
        snprintf(name, sizeof name, "poses[%zd]", p);
        PyArrayObject *pose = as_array(PySequence_Fast_GET_ITEM(items, p), name, NPY_FLOAT64, 2, 3);
        if (!pose)
            status = -1;
        else if (PyArray_DIM(pose, 0) != mesh->vertex_count) {
            PyErr_Format(PyExc_ValueError, "%s: %" NPY_INTP_FMT " vertices, the mesh has %d", name,
                         PyArray_DIM(pose, 0), (int)mesh->vertex_count);
            status = -1;
        } else {
            pz_ctx ctx;
            pz_ctx_init(&ctx);
            pz_status added = pz_mesh_add_pose(mesh, PyArray_DATA(pose), &ctx);
            if (added != PZ_OK) {
                pzpy_raise(added, &ctx);
                status = -1;
            }
        }
        Py_XDECREF(pose);
    }
    Py_DECREF(items);
    return status;
}

/* labels (one per face, >= 0) and uv (k x 2) with uv_faces (m x 3), when given. */
static int add_labels_and_uv(PyObject *labels, PyObject *uv, PyObject *uv_faces, pz_mesh *mesh)
{
    if (labels != Py_None) {
        if (pzpy_face_ints(labels, "labels", mesh->face_count, &mesh->face_labels) < 0)
            return -1;
        for (int32_t f = 0; f < mesh->face_count; ++f)
            if (mesh->face_labels[f] >= mesh->label_count)
                mesh->label_count = mesh->face_labels[f] + 1;
    }
    if ((uv == Py_None) != (uv_faces == Py_None)) {
        PyErr_SetString(PyExc_ValueError, "uv and uv_faces: give both or neither");
        return -1;
    }
    if (uv == Py_None)
        return 0;
    PyArrayObject *coordinates = as_array(uv, "uv", NPY_FLOAT64, 2, 2);
    PyArrayObject *corners = coordinates ? as_array(uv_faces, "uv_faces", NPY_INT64, 2, 3) : NULL;
    int status = coordinates && corners ? 0 : -1;
    if (status == 0 && PyArray_DIM(corners, 0) != mesh->face_count) {
        PyErr_Format(PyExc_ValueError, "uv_faces: %" NPY_INTP_FMT " rows, the mesh has %d faces",
                     PyArray_DIM(corners, 0), (int)mesh->face_count);
        status = -1;
    }
    if (status == 0) {
        mesh->uv_count = (int32_t)PyArray_DIM(coordinates, 0);
        mesh->uvs = malloc(((size_t)mesh->uv_count + 1) * 2 * sizeof(double));
        mesh->corner_uvs = malloc(((size_t)mesh->face_count + 1) * 3 * sizeof(int32_t));
        if (!mesh->uvs || !mesh->corner_uvs) {
            PyErr_NoMemory();
            status = -1;
        } else {
            memcpy(mesh->uvs, PyArray_DATA(coordinates), (size_t)mesh->uv_count * 2 * sizeof(double));
            status = copy_indices(corners, "uv_faces", "uv index", mesh->uv_count, mesh->corner_uvs);
        }
    }
    Py_XDECREF(coordinates);
    Py_XDECREF(corners);
    return status;
}

int pzpy_mesh_from_arrays(PyObject *vertices, PyObject *faces, PyObject *poses, PyObject *labels, PyObject *uv,
                          PyObject *uv_faces, pz_mesh **out)
{
    *out = NULL;
    PyArrayObject *positions = as_array(vertices, "vertices", NPY_FLOAT64, 2, 3);
    PyArrayObject *corners = positions ? as_array(faces, "faces", NPY_INT64, 2, 3) : NULL;
    if (!corners) {
        Py_XDECREF(positions);
        return -1;
    }
    npy_intp vertex_count = PyArray_DIM(positions, 0), face_count = PyArray_DIM(corners, 0);
    pz_mesh *mesh = NULL;
    int status = 0;
    if (vertex_count == 0 || face_count == 0) {
        data_error("%s: the mesh has no %s", vertex_count == 0 ? "vertices" : "faces",
                   vertex_count == 0 ? "vertices" : "faces");
        status = -1;
    } else {
        pz_ctx ctx;
        pz_ctx_init(&ctx);
        pz_status created = pz_mesh_create((int32_t)vertex_count, (int32_t)face_count, &mesh, &ctx);
        if (created != PZ_OK) {
            pzpy_raise(created, &ctx);
            status = -1;
        }
    }
    if (status == 0) {
        memcpy(mesh->positions, PyArray_DATA(positions), (size_t)vertex_count * 3 * sizeof(double));
        status = copy_indices(corners, "faces", "vertex index", vertex_count, mesh->faces);
    }
    Py_DECREF(positions);
    Py_DECREF(corners);
    if (status == 0)
        status = add_poses(poses, mesh);
    if (status == 0)
        status = add_labels_and_uv(labels, uv, uv_faces, mesh);
    if (status < 0) {
        pz_mesh_free(&mesh);
        return -1;
    }
    *out = mesh;
    return 0;
}

int pzpy_face_ints(PyObject *object, const char *name, int32_t face_count, int32_t **out)
{
    *out = NULL;
    PyArrayObject *array = as_array(object, name, NPY_INT64, 1, 0);
    if (!array)
        return -1;
    int status = 0;
    if (PyArray_DIM(array, 0) != face_count) {
        PyErr_Format(PyExc_ValueError, "%s: %" NPY_INTP_FMT " entries, the mesh has %d faces", name,
                     PyArray_DIM(array, 0), (int)face_count);
        status = -1;
    } else if (!(*out = malloc(((size_t)face_count + 1) * sizeof(int32_t)))) {
        PyErr_NoMemory();
        status = -1;
    } else if ((status = copy_indices(array, name, "non-negative integer", -1, *out)) < 0) {
        free(*out);
        *out = NULL;
    }
    Py_DECREF(array);
    return status;
}

int pzpy_sketch_from_curves(PyObject *curves, double scale, pz_sketch **out)
{
    *out = NULL;
    PyObject *items = PySequence_Fast(curves, "sketches: expected a sequence of (k, 3) arrays");
    if (!items)
        return -1;
    Py_ssize_t count = PySequence_Fast_GET_SIZE(items);
    PyArrayObject **arrays = calloc((size_t)count + 1, sizeof *arrays);
    pz_sketch *sketch = calloc(1, sizeof *sketch);
    int status = arrays && sketch ? 0 : -1;
    if (status < 0)
        PyErr_NoMemory();
    size_t points = 0;
    for (Py_ssize_t i = 0; i < count && status == 0; ++i) {
        char name[32];
        snprintf(name, sizeof name, "sketches[%zd]", i);
        arrays[i] = as_array(PySequence_Fast_GET_ITEM(items, i), name, NPY_FLOAT64, 2, 3);
        if (!arrays[i])
            status = -1;
        else if (PyArray_DIM(arrays[i], 0) < 2) {
            data_error("%s: a curve needs at least 2 points", name);
            status = -1;
        } else
            points += (size_t)PyArray_DIM(arrays[i], 0);
    }
    if (status == 0 && count > 0) {
        sketch->curve_count = (int32_t)count;
        sketch->curve_offsets = malloc(((size_t)count + 1) * sizeof(int32_t));
        sketch->points = malloc((points + 1) * 3 * sizeof(double));
        if (!sketch->curve_offsets || !sketch->points) {
            PyErr_NoMemory();
            status = -1;
        }
        size_t at = 0;
        for (Py_ssize_t i = 0; i < count && status == 0; ++i) {
            sketch->curve_offsets[i] = (int32_t)at;
            const double *values = PyArray_DATA(arrays[i]);
            for (npy_intp k = 0; k < 3 * PyArray_DIM(arrays[i], 0); ++k)
                sketch->points[3 * at + (size_t)k] = values[k] * scale;
            at += (size_t)PyArray_DIM(arrays[i], 0);
        }
        if (status == 0)
            sketch->curve_offsets[count] = (int32_t)at;
    }
    for (Py_ssize_t i = 0; arrays && i < count; ++i)
        Py_XDECREF(arrays[i]);
    free(arrays);
    Py_DECREF(items);
    if (status < 0 || count == 0) {
        pz_sketch_free(&sketch);
        return status;
    }
    *out = sketch;
    return 0;
}
