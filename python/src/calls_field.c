/*
 * python/src/calls_field.c -- panelize.field and panelize.prepare: the
 * cross-field and the preparation alone, as `panelize field` and
 * `panelize prepare` run them (the mesh converted to millimetres, validated
 * with the --repair switches, the sketch read and checked), their figures
 * returned as numpy arrays and a dict instead of files.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <string.h>

/* ---------------------------------------------------------------- field */

typedef struct field_job {
    pz_mesh *mesh;
    pz_units units, used;
    unsigned repair_flags;
    const char *name;
    const char *sketch_path;
    pz_sketch *sketch;       /* from sketches= or the file */
    pz_field_options options;
    pz_topology *topology;
    pz_field *field;
} field_job;

static pz_status run_field(pzpy_job *job, pz_ctx *ctx)
{
    field_job *data = job->data;
    pz_mesh_to_mm(data->mesh, data->units, &data->used);
    pz_status status = pz_mesh_prepare_quietly_first(&data->mesh, data->name, data->repair_flags, ctx);
    if (status == PZ_OK && data->sketch_path)
        status = pz_sketch_read(data->sketch_path, data->mesh->unit_scale, &data->sketch, ctx);
    if (status == PZ_OK && data->sketch)
        status = pz_sketch_check(data->sketch, data->mesh, data->sketch_path ? data->sketch_path : "sketches", ctx);
    if (status == PZ_OK)
        status = pz_topology_build(data->mesh, &data->topology, ctx);
    data->options.sketch = data->sketch;
    if (status == PZ_OK)
        status = pz_field_compute(data->mesh, data->topology, &data->options, &data->field, ctx);
    return status;
}

/* `value` as a number, or None when the library says it was not measured (< 0). */
static PyObject *figure(double value)
{
    return value < 0 ? Py_NewRef(Py_None) : PyFloat_FromDouble(value);
}

static PyObject *field_object(const field_job *data)
{
    const pz_field *field = data->field;
    const pz_mesh *mesh = data->mesh;
    PyObject *object = PyType_GenericAlloc(&pzpy_field_type, 0);
    if (!object)
        return NULL;
    npy_intp count = field->face_count;
    PyObject *constraint = PyArray_SimpleNew(1, &count, NPY_UINT8);
    if (constraint)
        memcpy(PyArray_DATA((PyArrayObject *)constraint), field->constraint, (size_t)count);
    PyObject *report = Py_BuildValue(
        "{s:i,s:i,s:i,s:i,s:d,s:d,s:i,s:i,s:i,s:d,s:N,s:N,s:N,s:s}", "vertices", (int)mesh->vertex_count, "faces",
        (int)mesh->face_count, "poses", (int)mesh->pose_count, "scales", (int)data->options.scale_count, "smoothness",
        data->options.smoothness, "mean_edge_mm", field->mean_edge_length, "boundary_faces",
        (int)field->boundary_face_count, "sketch_faces", (int)field->sketch_face_count, "singularity_count",
        (int)field->singularity_count, "index_sum", field->index_sum, "curvature_alignment_deg",
        figure(field->curvature_alignment_deg), "boundary_alignment_deg", figure(field->boundary_alignment_deg),
        "sketch_alignment_deg", figure(field->sketch_alignment_deg), "units", pz_units_str(data->used));
    int failed = pzpy_set(object, "directions", pzpy_doubles(field->directions, count, 3)) < 0 ||
                 pzpy_set(object, "normals", pzpy_doubles(field->normals, count, 3)) < 0 ||
                 pzpy_set(object, "curvature_directions", pzpy_doubles(field->curvature_directions, count, 3)) < 0 ||
                 pzpy_set(object, "anisotropy", pzpy_doubles(field->anisotropy, count, 0)) < 0 ||
                 pzpy_set(object, "constraint", constraint) < 0 ||
                 pzpy_set(object, "singular_vertices",
                          pzpy_ints(field->singular_vertices, field->singularity_count, 0)) < 0 ||
                 pzpy_set(object, "singular_indices",
                          pzpy_doubles(field->singular_indices, field->singularity_count, 0)) < 0 ||
                 pzpy_set(object, "vertices", pzpy_doubles(mesh->positions, mesh->vertex_count, 3)) < 0 ||
                 pzpy_set(object, "faces", pzpy_ints(mesh->faces, mesh->face_count, 3)) < 0 ||
                 pzpy_set(object, "report", report) < 0;
    if (failed)
        Py_CLEAR(object);
    return object;
}

const char pzpy_field_doc[] =
    "field(vertices, faces, *, poses=None, units=None, scales=3, smoothness=4.0, sketch=None, sketches=None, "
    "repair=False, progress=None, cancel=None)\n--\n\n"
    "The curvature-aligned cross-field, as `panelize field` computes it (docs/field.md): returns a "
    "panelize.Field (per-face arrays, singularities, report dict). vertices/faces or a Mesh, poses and units as "
    "in run(). scales: curvature scales 1..8; smoothness: the smoothness weight (> 0); sketch: a JSON sketch "
    "file, sketches: (k, 3) curves in the vertices' units, the field follows them. repair=True drops degenerate "
    "and duplicate faces and orients the rest before validation (--repair). Errors as in run(): DataError (65) "
    "for an invalid mesh or a sketch off the surface, UsageError (64) for an option out of range.";

PyObject *pzpy_field(PyObject *self, PyObject *args, PyObject *kwargs_given)
{
    (void)self;
    PyObject *kwargs = pzpy_consumable(kwargs_given), *object = NULL, *progress, *cancel, *value, *sketches;
    if (!kwargs)
        return NULL;
    pzpy_keep keep = {NULL};
    field_job data;
    memset(&data, 0, sizeof data);
    pzpy_garment garment;
    if (pzpy_garment_from_call(args, kwargs, "field", &garment, &keep) < 0 ||
        pzpy_pop_control(kwargs, &keep, &progress, &cancel) < 0 ||
        pzpy_garment_units(&garment, kwargs, &keep, &data.units) < 0 || !(value = pzpy_pop(kwargs, "repair", &keep)) ||
        pzpy_repair(value, &data.repair_flags) < 0 || !(value = pzpy_pop(kwargs, "sketch", &keep)) ||
        pzpy_path(value, "sketch", &keep, &data.sketch_path) < 0 || !(sketches = pzpy_pop(kwargs, "sketches", &keep)) ||
        pzpy_field_options(kwargs, &data.options) < 0 || pzpy_no_more_keywords(kwargs, "field") < 0 ||
        pzpy_garment_mesh(&garment, &data.mesh) < 0)
        goto done;
    data.name = garment.name ? garment.name : "mesh";
    if (sketches != Py_None) {
        if (data.sketch_path) {
            PyErr_SetString(PyExc_TypeError, "field(): give sketch (a file) or sketches (arrays), not both");
            goto done;
        }
        pz_units units = data.units == PZ_UNITS_AUTO ? pz_mesh_guess_units(data.mesh) : data.units;
        if (pzpy_sketch_from_curves(sketches, pz_units_to_mm(units), &data.sketch) < 0)
            goto done;
    }
    pzpy_job job = {run_field, &data};
    if (pzpy_run_job_or_raise(&job, progress, cancel) == 0)
        object = field_object(&data);
done:
    pz_field_free(&data.field);
    pz_topology_free(&data.topology);
    pz_sketch_free(&data.sketch);
    pz_mesh_free(&data.mesh);
    pzpy_keep_clear(&keep);
    Py_DECREF(kwargs);
    return object;
}

/* ---------------------------------------------------------------- prepare */

typedef struct prepare_job {
    pz_mesh *mesh;
    pz_units units, used;
    pz_prepare_options options;
    pz_prepare_result *result;
} prepare_job;

static pz_status run_prepare(pzpy_job *job, pz_ctx *ctx)
{
    prepare_job *data = job->data;
    pz_mesh_to_mm(data->mesh, data->units, &data->used);
    return pz_prepare(data->mesh, &data->options, &data->result, ctx);
}

/* The report of `panelize prepare --json`: steps and counts. */
static PyObject *prepare_report(const pz_prepare_result *result)
{
    const pz_prepare_report *r = &result->report;
    PyObject *steps = PyDict_New();
    for (int s = 0; steps && s < PZ_PREPARE_STEP_COUNT; ++s) {
        PyObject *step = Py_BuildValue("{s:O,s:s,s:d}", "ran", r->steps[s].ran ? Py_True : Py_False, "detail",
                                       r->steps[s].detail, "ms", r->steps[s].seconds * 1000.0);
        if (!step || PyDict_SetItemString(steps, r->steps[s].name, step) < 0)
            Py_CLEAR(steps);
        Py_XDECREF(step);
    }
    if (!steps)
        return NULL;
    PyObject *counts = Py_BuildValue(
        "{s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i,s:i}", "input_vertices",
        (int)r->input_vertices, "input_faces", (int)r->input_faces, "welded_vertices", (int)r->welded_vertices,
        "seam_edges", (int)r->seam_edges, "seam_curves", (int)result->seam_count, "nonfinite_faces",
        (int)r->nonfinite_faces, "degenerate_faces", (int)r->degenerate_faces, "duplicate_faces",
        (int)r->duplicate_faces, "nonmanifold_edge_faces", (int)r->nonmanifold_edge_faces, "split_vertices",
        (int)r->split_vertices, "flipped_faces", (int)r->flipped_faces, "components", (int)r->components,
        "dropped_components", (int)r->dropped_components, "dropped_component_faces", (int)r->dropped_component_faces,
        "decimated_faces", (int)r->decimated_faces, "output_vertices", (int)r->output_vertices, "output_faces",
        (int)r->output_faces, "poses", (int)result->mesh->pose_count);
    return Py_BuildValue("{s:N,s:N,s:d,s:d,s:d,s:d,s:d,s:O,s:d}", "steps", steps, "counts", counts, "target_edge_mm",
                         r->target_edge, "bbox_diagonal_mm", r->bbox_diagonal, "hausdorff_mm", r->hausdorff,
                         "pose_hausdorff_mm", r->pose_hausdorff_max, "hausdorff_bound_mm", r->hausdorff_bound,
                         "within_bound", r->within_bound ? Py_True : Py_False, "min_angle_over_20_fraction",
                         r->min_angle_over_20_fraction);
}

static PyObject *prepared_object(const prepare_job *data)
{
    const pz_prepare_result *result = data->result;
    PyObject *object = PyType_GenericAlloc(&pzpy_prepared_type, 0);
    PyObject *seams = object ? PyList_New(result->seam_count) : NULL;
    for (int32_t s = 0; seams && s < result->seam_count; ++s) {
        int32_t begin = result->seam_offsets[s], end = result->seam_offsets[s + 1];
        PyObject *seam = pzpy_ints(result->seam_vertices + begin, end - begin, 0);
        if (!seam)
            Py_CLEAR(seams);
        else
            PyList_SET_ITEM(seams, s, seam);
    }
    if (!object || pzpy_set(object, "mesh", pzpy_mesh_object(result->mesh, data->used)) < 0 ||
        pzpy_set(object, "seams", seams) < 0 || pzpy_set(object, "report", prepare_report(result)) < 0) {
        Py_XDECREF(object);
        return NULL;
    }
    return object;
}

const char pzpy_prepare_doc[] =
    "prepare(vertices, faces, *, poses=None, units=None, faces_wanted=None, edge=None, weld=None, keep='largest', "
    "repair=False, progress=None, cancel=None)\n--\n\n"
    "Scan-ready input, as `panelize prepare` (docs/prepare.md): welds an unwelded export, repairs, drops "
    "fragments, decimates and remeshes, carries the poses along. Returns a panelize.Prepared: mesh (a "
    "panelize.Mesh, mm), seams (the welded seams as vertex polylines) and report (steps, counts, Hausdorff "
    "distance). faces_wanted: the faces wanted (the command line's --faces; default 20000); edge: the edge length "
    "in mm instead (not both); weld: the weld distance in mm (0: no welding; default 0.01); keep: 'largest' (drop "
    "fragments) or 'all'; repair=True: repair and weld only, no remeshing (as --repair). Errors as in run().";

PyObject *pzpy_prepare(PyObject *self, PyObject *args, PyObject *kwargs_given)
{
    (void)self;
    PyObject *kwargs = pzpy_consumable(kwargs_given), *object = NULL, *progress, *cancel, *value;
    if (!kwargs)
        return NULL;
    pzpy_keep keep = {NULL};
    prepare_job data;
    memset(&data, 0, sizeof data);
    pzpy_garment garment;
    unsigned repair = 0;
    /* --faces is `faces_wanted` here: `faces` is the mesh's own argument */
    PyObject *wanted = PyDict_GetItemString(kwargs, "faces_wanted");
    if (wanted && (PyDict_SetItemString(kwargs, "target_faces", wanted) < 0 ||
                   PyDict_DelItemString(kwargs, "faces_wanted") < 0))
        goto done;
    if (pzpy_garment_from_call(args, kwargs, "prepare", &garment, &keep) < 0 ||
        pzpy_pop_control(kwargs, &keep, &progress, &cancel) < 0 ||
        pzpy_garment_units(&garment, kwargs, &keep, &data.units) < 0 || !(value = pzpy_pop(kwargs, "repair", &keep)) ||
        pzpy_repair(value, &repair) < 0)
        goto done;
    value = PyDict_GetItemString(kwargs, "target_faces");
    if (value && (PyDict_SetItemString(kwargs, "faces", value) < 0 || PyDict_DelItemString(kwargs, "target_faces") < 0))
        goto done;
    if (pzpy_prepare_options(kwargs, &data.options, &keep) < 0 || pzpy_no_more_keywords(kwargs, "prepare") < 0 ||
        pzpy_garment_mesh(&garment, &data.mesh) < 0)
        goto done;
    data.options.no_remesh = repair != 0;
    data.options.name = garment.name;
    pzpy_job job = {run_prepare, &data};
    if (pzpy_run_job_or_raise(&job, progress, cancel) == 0)
        object = prepared_object(&data);
done:
    pz_prepare_result_free(&data.result);
    pz_mesh_free(&data.mesh);
    pzpy_keep_clear(&keep);
    Py_DECREF(kwargs);
    return object;
}
