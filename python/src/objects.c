/*
 * python/src/objects.c -- the objects the functions return. Mesh, Field and
 * Prepared are plain records (their attributes in an instance dict, set once
 * here, numpy arrays copied out of the library's structs, so they outlive
 * them); Result also owns the library's pz_result, which write() turns into
 * pattern files.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <string.h>

typedef struct record_object {
    PyObject_HEAD
    PyObject *dict;
} record_object;

typedef struct result_object {
    PyObject_HEAD
    PyObject *dict;
    pz_result *result;
    int writing;    /* a write() is running on another thread: a second one waits its turn in Python */
} result_object;

int pzpy_set(PyObject *object, const char *name, PyObject *value)
{
    if (!value)
        return -1;
    int status = PyObject_SetAttrString(object, name, value);
    Py_DECREF(value);
    return status;
}

/* ---------------------------------------------------------------- JSON */

PyObject *pzpy_from_json(const cJSON *item)
{
    if (!item || cJSON_IsNull(item))
        Py_RETURN_NONE;
    if (cJSON_IsBool(item))
        return PyBool_FromLong(cJSON_IsTrue(item));
    if (cJSON_IsString(item))
        return PyUnicode_DecodeUTF8(item->valuestring, (Py_ssize_t)strlen(item->valuestring), "replace");
    if (cJSON_IsNumber(item)) {
        double value = item->valuedouble;
        if (value == (double)(long long)value && value >= -9e15 && value <= 9e15)
            return PyLong_FromLongLong((long long)value);
        return PyFloat_FromDouble(value);
    }
    int is_array = cJSON_IsArray(item);
    PyObject *container = is_array ? PyList_New(0) : PyDict_New();
    for (const cJSON *child = item->child; container && child; child = child->next) {
        PyObject *value = pzpy_from_json(child);
        int status = !value ? -1
                     : is_array ? PyList_Append(container, value)
                                : PyDict_SetItemString(container, child->string ? child->string : "", value);
        Py_XDECREF(value);
        if (status < 0)
            Py_CLEAR(container);
    }
    return container;
}

PyObject *pzpy_names(char *const *names, int32_t count)
{
    PyObject *list = PyList_New(count);
    for (int32_t i = 0; list && i < count; ++i) {
        const char *name = names ? names[i] : NULL;
        PyObject *item = name ? PyUnicode_DecodeUTF8(name, (Py_ssize_t)strlen(name), "replace") : Py_NewRef(Py_None);
        if (!item)
            Py_CLEAR(list);
        else
            PyList_SET_ITEM(list, i, item);
    }
    return list;
}

/* ---------------------------------------------------------------- records */

static void record_dealloc(PyObject *self)
{
    Py_XDECREF(((record_object *)self)->dict);
    Py_TYPE(self)->tp_free(self);
}

/* "<panelize.Mesh: vertices (1234, 3), faces (2400, 3), units 'mm', ...>": each attribute, arrays by shape. */
static PyObject *record_repr(PyObject *self)
{
    PyObject *dict = ((record_object *)self)->dict;
    PyObject *parts = PyList_New(0);
    Py_ssize_t position = 0;
    PyObject *key, *value;
    while (parts && dict && PyDict_Next(dict, &position, &key, &value)) {
        if (PyList_Size(parts) >= 8)
            break;
        PyObject *shape = PyArray_Check(value) ? PyObject_GetAttrString(value, "shape") : NULL;
        PyObject *part = shape ? PyUnicode_FromFormat("%U %R", key, shape)
                         : PyList_Check(value) || PyDict_Check(value)
                             ? PyUnicode_FromFormat("%U (%zd)", key, PyObject_Length(value))
                             : PyUnicode_FromFormat("%U=%R", key, value);
        Py_XDECREF(shape);
        if (!part || PyList_Append(parts, part) < 0)
            Py_CLEAR(parts);
        Py_XDECREF(part);
    }
    if (!parts)
        return NULL;
    PyObject *separator = PyUnicode_FromString(", ");
    PyObject *joined = separator ? PyUnicode_Join(separator, parts) : NULL;
    PyObject *text = joined ? PyUnicode_FromFormat("<%s: %U>", Py_TYPE(self)->tp_name, joined) : NULL;
    Py_XDECREF(separator);
    Py_XDECREF(joined);
    Py_DECREF(parts);
    return text;
}

#define RECORD_TYPE(variable, name, doc)                                                                           \
    PyTypeObject variable = {                                                                                      \
        PyVarObject_HEAD_INIT(NULL, 0).tp_name = name,                                                             \
        .tp_basicsize = sizeof(record_object),                                                                     \
        .tp_dealloc = record_dealloc,                                                                              \
        .tp_repr = record_repr,                                                                                    \
        .tp_flags = Py_TPFLAGS_DEFAULT,                                                                            \
        .tp_doc = doc,                                                                                             \
        .tp_dictoffset = offsetof(record_object, dict),                                                            \
        .tp_new = NULL,                                                                                            \
    }

RECORD_TYPE(pzpy_mesh_type, "panelize.Mesh",
            "A garment mesh, as panelize.load returns it. Attributes: vertices (n x 3 float64, millimetres), "
            "faces (m x 3 int32), poses (k x n x 3 float64, mm; k may be 0), labels (m int32, or None), "
            "label_names (list), uv (u x 2 float64, or None), uv_faces (m x 3 int32 into uv, or None), units "
            "(the file's units: 'mm', 'cm' or 'm'), unit_scale (mm per file unit). Pass it to run, flatten, "
            "field or prepare in place of the arrays.");
RECORD_TYPE(pzpy_field_type, "panelize.Field",
            "The cross-field of panelize.field. Attributes: directions (m x 3: one unit arm of each face's "
            "cross), normals (m x 3), curvature_directions (m x 3), anisotropy (m), constraint (m uint8: 0 free, "
            "1 boundary, 2 sketch), singular_vertices (k int32), singular_indices (k, in turns), vertices and "
            "faces (the mesh used, mm), report (dict: the command line's report.json).");
RECORD_TYPE(pzpy_prepared_type, "panelize.Prepared",
            "The mesh panelize.prepare made: mesh (a panelize.Mesh, mm), seams (list of int32 vertex polylines "
            "welding found, closed ones end where they start), report (dict: the steps and counts of `panelize "
            "prepare --json`).");

PyObject *pzpy_mesh_object(const pz_mesh *mesh, pz_units units)
{
    PyObject *self = PyType_GenericAlloc(&pzpy_mesh_type, 0);
    if (!self)
        return NULL;
    int failed = pzpy_set(self, "vertices", pzpy_doubles(mesh->positions, mesh->vertex_count, 3)) < 0 ||
                 pzpy_set(self, "faces", pzpy_ints(mesh->faces, mesh->face_count, 3)) < 0;
    npy_intp shape[3] = {mesh->pose_count, mesh->vertex_count, 3};
    PyObject *poses = failed ? NULL : PyArray_SimpleNew(3, shape, NPY_FLOAT64);
    if (poses && mesh->pose_count)
        memcpy(PyArray_DATA((PyArrayObject *)poses), mesh->poses,
               (size_t)mesh->pose_count * (size_t)mesh->vertex_count * 3 * sizeof(double));
    failed = failed || pzpy_set(self, "poses", poses) < 0;
    failed = failed || pzpy_set(self, "labels", mesh->face_labels ? pzpy_ints(mesh->face_labels, mesh->face_count, 0)
                                                                  : Py_NewRef(Py_None)) < 0;
    failed = failed || pzpy_set(self, "label_names", pzpy_names(mesh->label_names, mesh->label_count)) < 0;
    int has_uv = mesh->uv_count > 0 && mesh->uvs && mesh->corner_uvs;
    failed = failed || pzpy_set(self, "uv", has_uv ? pzpy_doubles(mesh->uvs, mesh->uv_count, 2) : Py_NewRef(Py_None)) < 0;
    failed = failed || pzpy_set(self, "uv_faces", has_uv ? pzpy_ints(mesh->corner_uvs, mesh->face_count, 3)
                                                         : Py_NewRef(Py_None)) < 0;
    failed = failed || pzpy_set(self, "units", PyUnicode_FromString(pz_units_str(units))) < 0;
    failed = failed || pzpy_set(self, "unit_scale", PyFloat_FromDouble(mesh->unit_scale)) < 0;
    if (failed)
        Py_CLEAR(self);
    return self;
}

/* ---------------------------------------------------------------- Result */

static void result_dealloc(PyObject *self)
{
    result_object *object = (result_object *)self;
    Py_XDECREF(object->dict);
    pz_result_free(&object->result);
    Py_TYPE(self)->tp_free(self);
}

typedef struct write_job {
    pz_result *result;
    const char *folder;
    unsigned outputs;
} write_job;

static pz_status run_write(pzpy_job *job, pz_ctx *ctx)
{
    write_job *write = job->data;
    return pz_result_write(write->result, write->folder, write->outputs, NULL, ctx);
}

/* outputs: "svg,dxf", ("svg", "dxf") or None (every file) into the library's bit set. */
static int parse_outputs(PyObject *outputs, unsigned *bits)
{
    *bits = PZ_OUTPUT_ALL;
    if (outputs == Py_None)
        return 0;
    PyObject *list = NULL;
    if (PyUnicode_Check(outputs))
        list = Py_NewRef(outputs);
    else {
        PyObject *separator = PyUnicode_FromString(",");
        PyObject *items = separator ? PySequence_Fast(outputs, "outputs: expected a sequence of names") : NULL;
        for (Py_ssize_t i = 0; items && i < PySequence_Fast_GET_SIZE(items); ++i)
            if (!PyUnicode_Check(PySequence_Fast_GET_ITEM(items, i))) {
                PyErr_SetString(PyExc_TypeError, "outputs: expected names (str) such as \"svg\", \"dxf\"");
                Py_CLEAR(items);
            }
        list = items ? PyUnicode_Join(separator, items) : NULL;
        Py_XDECREF(items);
        Py_XDECREF(separator);
    }
    const char *text = list ? PyUnicode_AsUTF8(list) : NULL;
    int status = -1;
    if (text) {
        pz_ctx ctx;
        pz_ctx_init(&ctx);
        pz_status parsed = pz_outputs_parse(text, bits, &ctx);
        status = parsed == PZ_OK ? 0 : (pzpy_raise(parsed, &ctx), -1);
    }
    Py_XDECREF(list);
    return status;
}

static PyObject *result_write(PyObject *self, PyObject *args, PyObject *kwargs)
{
    static char *keywords[] = {"folder", "outputs", "progress", "cancel", NULL};
    PyObject *folder = NULL, *outputs = Py_None, *progress = Py_None, *cancel = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|O$OO:write", keywords, &folder, &outputs, &progress, &cancel))
        return NULL;
    result_object *object = (result_object *)self;
    pzpy_keep keep = {NULL};
    write_job data = {object->result, NULL, 0};
    if (pzpy_path(folder, "folder", &keep, &data.folder) < 0 || parse_outputs(outputs, &data.outputs) < 0) {
        pzpy_keep_clear(&keep);
        return NULL;
    }
    if (object->writing) {
        pzpy_keep_clear(&keep);
        PyErr_SetString(PyExc_RuntimeError, "write: this result is being written by another thread");
        return NULL;
    }
    object->writing = 1;
    pzpy_job job = {run_write, &data};
    int status = pzpy_run_job_or_raise(&job, progress, cancel);
    object->writing = 0;
    pzpy_keep_clear(&keep);
    if (status < 0)
        return NULL;
    Py_RETURN_NONE;
}

static PyMethodDef result_methods[] = {
    {"write", (PyCFunction)(void (*)(void))result_write, METH_VARARGS | METH_KEYWORDS,
     "write(folder, outputs=None, *, progress=None, cancel=None)\n--\n\n"
     "Writes the pattern files into `folder`, all or nothing, as `panelize run -o folder` does: the files are "
     "made in a hidden folder beside it and replace `folder` whole only once every one is complete (an earlier "
     "panelize output there is replaced; a folder of other files is refused with CreateError, nothing changed). "
     "`outputs`: None (every file) or names from obj, svg, pdf, tiled, dxf, marker, glb, json, html, layout, "
     "energy, all (a sequence, or one comma-separated string). Raises CreateError (73) when the folder cannot "
     "be written, UsageError for an unknown name. The GIL is released while writing."},
    {NULL, NULL, 0, NULL}};

PyTypeObject pzpy_result_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "panelize.Result",
    .tp_basicsize = sizeof(result_object),
    .tp_dealloc = result_dealloc,
    .tp_repr = record_repr,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The pattern of panelize.run or panelize.flatten. Attributes (lengths in millimetres):\n"
              "  vertices (n x 3 float64), faces (m x 3 int32): the garment as flattened (prepared, seams trued);\n"
              "  face_panel (m int32): each face's panel, 0 .. panel_count - 1; panel_count; panel_names (list);\n"
              "  pattern (m x 3 x 2 float64): each face corner's position on the pattern (the pieces laid out\n"
              "    side by side, the grain along +y);\n"
              "  pattern_uv (k x 2), pattern_faces (m x 3 into pattern_uv), pattern_vertex (k int32: the garment\n"
              "    vertex of each pattern vertex): the same, indexed (for matplotlib's triplot);\n"
              "  seams: list of dicts {panels: (a, b), vertices_a, vertices_b (int32 garment vertices sewn together,\n"
              "    in order), pattern_a, pattern_b (k x 2 positions on the two pieces)};\n"
              "  darts: list of dicts {panel, tip (garment vertex), pattern_tip (2), vertices_a, vertices_b,\n"
              "    pattern_a, pattern_b (the two legs)};\n"
              "  curves (list of k x 3 float64 polylines on the garment: the seams and darts; run only),\n"
              "    curve_is_dart (bool array);\n"
              "  goals_met (bool; None for flatten), worst_strain, units (the input's), report (dict: report.json).\n"
              "write(folder, outputs) writes the pattern files.",
    .tp_dictoffset = offsetof(result_object, dict),
    .tp_methods = result_methods,
};

PyObject *pzpy_result_object(pz_result **result)
{
    result_object *self = (result_object *)PyType_GenericAlloc(&pzpy_result_type, 0);
    if (!self)
        return NULL;
    self->result = *result;
    *result = NULL;
    return (PyObject *)self;
}

const pz_result *pzpy_result_of(PyObject *result)
{
    return ((result_object *)result)->result;
}
