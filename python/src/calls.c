/*
 * python/src/calls.c -- panelize.load, run, flatten, field, prepare and
 * generate: arguments in (arrays checked by arrays.c, options by options.c),
 * the library call run off the GIL (work.c), the result out (objects.c).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <math.h>
#include <string.h>

/* ---------------------------------------------------------------- the garment argument */

/* Reads the positional (vertices, faces) and the keywords poses, labels, uv, uv_faces (popped from kwargs). */
int pzpy_garment_from_call(PyObject *args, PyObject *kwargs, const char *function, pzpy_garment *garment,
                             pzpy_keep *keep)
{
    memset(garment, 0, sizeof *garment);
    Py_ssize_t count = PyTuple_GET_SIZE(args);
    PyObject *first = count > 0 ? PyTuple_GET_ITEM(args, 0) : pzpy_pop(kwargs, "vertices", keep);
    PyObject *second = count > 1 ? PyTuple_GET_ITEM(args, 1) : pzpy_pop(kwargs, "faces", keep);
    if (!first || !second)
        return -1;
    if (count > 2) {
        PyErr_Format(PyExc_TypeError, "%s() takes vertices and faces (or a Mesh) as positional arguments; the "
                     "options are keywords", function);
        return -1;
    }
    const char *names[] = {"poses", "labels", "uv", "uv_faces"};
    PyObject **slots[] = {&garment->poses, &garment->labels, &garment->uv, &garment->uv_faces};
    for (int i = 0; i < 4; ++i)
        if (!(*slots[i] = pzpy_pop(kwargs, names[i], keep)))
            return -1;
    if (first == Py_None) {
        PyErr_Format(PyExc_TypeError, "%s() needs vertices and faces, or a panelize.Mesh", function);
        return -1;
    }
    if (Py_TYPE(first) != &pzpy_mesh_type) {
        garment->vertices = first;
        garment->faces = second;
        if (second == Py_None) {
            PyErr_Format(PyExc_TypeError, "%s(): faces: expected an (m, 3) array of integers, got None", function);
            return -1;
        }
        return 0;
    }
    if (second != Py_None) {
        PyErr_Format(PyExc_TypeError, "%s(): a Mesh carries its own faces: give the Mesh alone", function);
        return -1;
    }
    garment->from_mesh = 1;
    const char *attributes[] = {"vertices", "faces", "poses", "labels", "uv", "uv_faces", "name"};
    PyObject **targets[] = {&garment->vertices, &garment->faces, &garment->poses, &garment->labels, &garment->uv,
                            &garment->uv_faces};
    for (int i = 0; i < 7; ++i) {
        PyObject *value = PyObject_GetAttrString(first, attributes[i]);
        if (!value) {
            if (i < 6)
                return -1;
            PyErr_Clear(); /* a Mesh from generate has no file name */
            continue;
        }
        if (!keep->list && !(keep->list = PyList_New(0))) {
            Py_DECREF(value);
            return -1;
        }
        int status = PyList_Append(keep->list, value);
        Py_DECREF(value);
        if (status < 0)
            return -1;
        if (i == 6)
            garment->name = PyUnicode_Check(value) ? PyUnicode_AsUTF8(value) : NULL;
        else if (i < 2 || *targets[i] == Py_None) /* a keyword given beside the Mesh wins */
            *targets[i] = value;
    }
    return 0;
}

int pzpy_garment_mesh(const pzpy_garment *garment, pz_mesh **out)
{
    return pzpy_mesh_from_arrays(garment->vertices, garment->faces, garment->poses, garment->labels, garment->uv,
                                 garment->uv_faces, out);
}

/* The units of a mesh given as arrays: a Mesh is in millimetres; arrays as the units option says (auto: guessed). */
static pz_units garment_units(const pzpy_garment *garment, PyObject *units_given, pz_units units)
{
    return garment->from_mesh && units_given == Py_None ? PZ_UNITS_MM : units;
}

int pzpy_garment_units(const pzpy_garment *garment, PyObject *kwargs, pzpy_keep *keep, pz_units *out)
{
    PyObject *units = pzpy_pop(kwargs, "units", keep);
    if (!units || pzpy_units(units, out) < 0)
        return -1;
    *out = garment_units(garment, units, *out);
    return 0;
}

int pzpy_run_job_or_raise(pzpy_job *job, PyObject *progress, PyObject *cancel)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    int python_error = 0;
    pz_status status = pzpy_run_job(job, &ctx, progress, cancel, &python_error);
    if (python_error)
        return -1;
    return status == PZ_OK ? 0 : (pzpy_raise(status, &ctx), -1);
}

int pzpy_pop_control(PyObject *kwargs, pzpy_keep *keep, PyObject **progress, PyObject **cancel)
{
    *progress = pzpy_pop(kwargs, "progress", keep);
    *cancel = *progress ? pzpy_pop(kwargs, "cancel", keep) : NULL;
    return *progress && *cancel ? 0 : -1;
}

/* A copy of kwargs the option parsers consume (the caller's dict is left alone). */
PyObject *pzpy_consumable(PyObject *kwargs)
{
    return kwargs ? PyDict_Copy(kwargs) : PyDict_New();
}

/* ---------------------------------------------------------------- load and generate */

const char pzpy_load_doc[] =
    "load(path, units=None, poses=())\n--\n\n"
    "Reads a garment mesh (OBJ, PLY, OFF, glTF .glb/.gltf) with its pose files, as `panelize run` reads it, "
    "and returns a panelize.Mesh in millimetres. units: None or 'auto' (guessed from the size, as the command "
    "line does), 'mm', 'cm' or 'm'. poses: paths of extra poses with the same connectivity. Raises OpenError "
    "(66) when a file cannot be read, DataError (65) when it is malformed. The GIL is released while reading.";

typedef struct load_job {
    const char *path;
    const char **pose_paths;
    int pose_count;
    pz_units units, used;
    pz_mesh *mesh;
} load_job;

static pz_status run_load(pzpy_job *job, pz_ctx *ctx)
{
    load_job *load = job->data;
    pz_status status = pz_mesh_read_with_poses(load->path, load->pose_paths, load->pose_count, &load->mesh, ctx);
    if (status == PZ_OK)
        pz_mesh_to_mm(load->mesh, load->units, &load->used);
    return status;
}

PyObject *pzpy_load(PyObject *self, PyObject *args, PyObject *kwargs)
{
    (void)self;
    static char *keywords[] = {"path", "units", "poses", NULL};
    PyObject *path = NULL, *units = Py_None, *poses = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|OO:load", keywords, &path, &units, &poses))
        return NULL;
    pzpy_keep keep = {NULL};
    load_job data = {NULL, NULL, 0, PZ_UNITS_AUTO, PZ_UNITS_AUTO, NULL};
    PyObject *items = NULL, *mesh = NULL;
    if (pzpy_path(path, "path", &keep, &data.path) < 0 || pzpy_units(units, &data.units) < 0)
        goto done;
    if (poses != Py_None) {
        if (PyUnicode_Check(poses) || !(items = PySequence_Fast(poses, "poses: expected a sequence of paths"))) {
            if (!PyErr_Occurred())
                PyErr_SetString(PyExc_TypeError, "poses: expected a sequence of paths, not one string");
            goto done;
        }
        data.pose_count = (int)PySequence_Fast_GET_SIZE(items);
        if (!(data.pose_paths = calloc((size_t)data.pose_count + 1, sizeof(char *)))) {
            PyErr_NoMemory();
            goto done;
        }
        for (int i = 0; i < data.pose_count; ++i)
            if (pzpy_path(PySequence_Fast_GET_ITEM(items, i), "poses", &keep, &data.pose_paths[i]) < 0)
                goto done;
    }
    pzpy_job job = {run_load, &data};
    if (pzpy_run_job_or_raise(&job, Py_None, Py_None) < 0)
        goto done;
    mesh = pzpy_mesh_object(data.mesh, data.used);
    if (mesh && pzpy_set(mesh, "name", PyUnicode_DecodeFSDefault(data.path)) < 0)
        Py_CLEAR(mesh);
done:
    pz_mesh_free(&data.mesh);
    free(data.pose_paths);
    Py_XDECREF(items);
    pzpy_keep_clear(&keep);
    return mesh;
}

const char pzpy_generate_doc[] =
    "generate(shape='bodice', faces=None, poses=0, open=False)\n--\n\n"
    "A synthetic garment, as `panelize generate` makes it: shape is bodice, skirt, sleeve, hemisphere, "
    "quarter-sphere, saddle, cylinder or cone; faces the approximate face count (default 20000); poses the extra "
    "deformed poses; open cuts a cylinder or cone into a disk. Returns a panelize.Mesh in millimetres.";

PyObject *pzpy_generate(PyObject *self, PyObject *args, PyObject *kwargs)
{
    (void)self;
    static char *keywords[] = {"shape", "faces", "poses", "open", NULL};
    const char *shape_name = "bodice";
    PyObject *faces = Py_None;
    int poses = 0, open = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "|sOip:generate", keywords, &shape_name, &faces, &poses, &open))
        return NULL;
    pz_shape shape = pz_shape_parse(shape_name);
    if (shape == PZ_SHAPE_UNKNOWN)
        return pzpy_usage_error("generate: '%s' is not bodice, skirt, sleeve, hemisphere, quarter-sphere, saddle, "
                                "cylinder or cone", shape_name);
    long target = faces == Py_None ? 0 : PyLong_AsLong(faces);
    if (target == -1 && PyErr_Occurred())
        return NULL;
    if (target < 0 || target > 10000000 || poses < 0 || poses > 16)
        return pzpy_usage_error("generate: faces must be in 0..10000000 and poses in 0..16");
    pz_generate_options options = {(int32_t)target, poses, open};
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    pz_mesh *mesh = NULL;
    pz_status status;
    Py_BEGIN_ALLOW_THREADS
    status = pz_generate(shape, &options, &mesh, &ctx);
    Py_END_ALLOW_THREADS
    if (status != PZ_OK)
        return pzpy_raise(status, &ctx);
    PyObject *object = pzpy_mesh_object(mesh, PZ_UNITS_MM);
    pz_mesh_free(&mesh);
    return object;
}

/* ---------------------------------------------------------------- run and flatten */

/* What pz_run and pz_flatten need, besides the options. */
typedef struct pattern_job {
    pz_mesh *mesh;
    pz_run_options options;
    pz_panels panels;
    int use_panels;        /* run: panels given (else segmentation); flatten: always */
    int flatten;           /* 1: pz_flatten */
    const char *const *seam_paths, *const *dart_paths;
    int seam_count, dart_count;
    pz_correspondences correspondences;
    uint8_t *vertex_used;
    int32_t *face_panel;   /* panels given as an array or a file */
    pz_sketch *sketch;
    pz_result *result;
} pattern_job;

static void pattern_job_clear(pattern_job *data)
{
    pz_mesh_free(&data->mesh);
    pz_correspondences_clear(&data->correspondences);
    free(data->vertex_used);
    free(data->face_panel);
    pz_sketch_free(&data->sketch);
    pz_result_free(&data->result);
}

/* Seam and dart files (flatten), in the one mesh's vertex ids, as `panelize flatten --seams --darts` reads them. */
static pz_status read_correspondences(pattern_job *data, pz_ctx *ctx)
{
    if (data->seam_count + data->dart_count == 0)
        return PZ_OK;
    const pz_mesh *mesh = data->mesh;
    int32_t offsets[2] = {0, mesh->vertex_count};
    if (!(data->vertex_used = calloc((size_t)mesh->vertex_count + 1, 1)))
        return pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory reading seams");
    pz_mesh_mark_used_vertices(mesh, data->vertex_used);
    pz_vertex_space space = {1, offsets, data->vertex_used, INT32_MAX}; /* panels checked once found */
    pz_correspondences *out = &data->correspondences;
    pz_status status = pz_read_correspondences(data->seam_paths, data->seam_count, data->dart_paths,
                                               data->dart_count, &space, out, ctx);
    pz_panels_use_correspondences(&data->panels, out, data->seam_count ? data->seam_paths[0] : data->dart_paths[0]);
    return status;
}

static pz_status run_pattern(pzpy_job *job, pz_ctx *ctx)
{
    pattern_job *data = job->data;
    pz_status status = PZ_OK;
    if (data->panels.source == PZ_PANELS_FACES && data->panels.face_panel_name && !data->panels.face_panel) {
        /* a panels file: read here, off the GIL */
        if (!(data->face_panel = malloc(((size_t)data->mesh->face_count + 1) * sizeof(int32_t))))
            return pz_error(ctx, PZ_ERR_NOMEM, "out of memory finding panels");
        status = pz_read_panel_file(data->panels.face_panel_name, data->mesh->face_count, data->face_panel,
                                    &data->panels.panel_count, ctx);
        data->panels.face_panel = data->face_panel;
    }
    if (status == PZ_OK)
        status = read_correspondences(data, ctx);
    if (status != PZ_OK)
        return status;
    if (data->flatten)
        return pz_flatten(data->mesh, &data->panels, &data->options, &data->result, ctx);
    data->options.panels = data->use_panels ? &data->panels : NULL;
    return pz_run(data->mesh, &data->options, &data->result, ctx);
}

/*
 * panels=: run: None (segment), "uv", a panels file, or per-face ids; flatten:
 * also "groups" (the default: one panel per connected piece of each label) and
 * "labels" (one panel per label).
 */
static int panels_option(PyObject *panels, pattern_job *data, pzpy_keep *keep)
{
    data->panels.source = PZ_PANELS_GROUPS;
    if (panels == Py_None)
        return 0;
    data->use_panels = 1;
    if (PyUnicode_Check(panels)) {
        const char *text = PyUnicode_AsUTF8(panels);
        if (!text)
            return -1;
        if (strcmp(text, "uv") == 0) {
            data->panels.source = PZ_PANELS_UV;
            return 0;
        }
        if (data->flatten && (strcmp(text, "groups") == 0 || strcmp(text, "labels") == 0)) {
            data->panels.source = text[0] == 'g' ? PZ_PANELS_GROUPS : PZ_PANELS_LABELS;
            return 0;
        }
    }
    if (PyUnicode_Check(panels) || PyObject_HasAttrString(panels, "__fspath__")) {
        data->panels.source = PZ_PANELS_FACES;
        return pzpy_path(panels, "panels", keep, &data->panels.face_panel_name);
    }
    data->panels.source = PZ_PANELS_FACES;
    if (pzpy_face_ints(panels, "panels", data->mesh->face_count, &data->face_panel) < 0)
        return -1;
    int32_t most = -1;
    for (int32_t f = 0; f < data->mesh->face_count; ++f)
        most = data->face_panel[f] > most ? data->face_panel[f] : most;
    data->panels.face_panel = data->face_panel;
    data->panels.panel_count = most + 1;
    data->panels.face_panel_name = "panels";
    return 0;
}

/* A sequence of paths (seams=, darts=) into a C array kept by `keep` (freed by the caller). */
static int path_list(PyObject *object, const char *name, pzpy_keep *keep, const char ***out, int *count)
{
    *out = NULL;
    *count = 0;
    if (object == Py_None)
        return 0;
    PyObject *items = PyUnicode_Check(object) ? NULL : PySequence_Fast(object, "");
    if (!items) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: expected a sequence of paths", name);
        return -1;
    }
    *count = (int)PySequence_Fast_GET_SIZE(items);
    int status = (*out = calloc((size_t)*count + 1, sizeof(char *))) ? 0 : (PyErr_NoMemory(), -1);
    for (int i = 0; i < *count && status == 0; ++i)
        status = pzpy_path(PySequence_Fast_GET_ITEM(items, i), name, keep, &(*out)[i]);
    Py_DECREF(items);
    return status;
}

/* One side of a seam or dart (cut-mesh vertices): its garment vertices (int32) and pattern positions (k x 2). */
static int side_arrays(const pz_result *r, const int32_t *side, npy_intp count, PyObject **vertices,
                       PyObject **positions)
{
    npy_intp shape[2] = {count, 2};
    *vertices = PyArray_SimpleNew(1, &count, NPY_INT32);
    *positions = *vertices ? PyArray_SimpleNew(2, shape, NPY_FLOAT64) : NULL;
    if (!*positions) {
        Py_CLEAR(*vertices);
        return -1;
    }
    int32_t *ids = PyArray_DATA((PyArrayObject *)*vertices);
    double *uv = PyArray_DATA((PyArrayObject *)*positions);
    for (npy_intp i = 0; i < count; ++i) {
        ids[i] = r->pattern->vertex_origin[side[i]];
        memcpy(uv + 2 * i, r->uv + 2 * (size_t)side[i], 2 * sizeof(double));
    }
    return 0;
}

/* A seam's or dart's dict: `head` (its own keys, a new dict) plus the two sides' arrays. */
static PyObject *sewn_item(const pz_result *r, PyObject *head, const int32_t *side_a, const int32_t *side_b,
                           npy_intp count)
{
    PyObject *va = NULL, *pa = NULL, *vb = NULL, *pb = NULL;
    int failed = !head || side_arrays(r, side_a, count, &va, &pa) < 0 || side_arrays(r, side_b, count, &vb, &pb) < 0 ||
                 PyDict_SetItemString(head, "vertices_a", va) < 0 || PyDict_SetItemString(head, "vertices_b", vb) < 0 ||
                 PyDict_SetItemString(head, "pattern_a", pa) < 0 || PyDict_SetItemString(head, "pattern_b", pb) < 0;
    Py_XDECREF(va), Py_XDECREF(pa), Py_XDECREF(vb), Py_XDECREF(pb);
    if (failed)
        Py_CLEAR(head);
    return head;
}

/* The seams and darts of a pattern as lists of dicts (see the Result's doc). */
static int set_seams_and_darts(PyObject *object, const pz_result *r)
{
    const pz_pattern *pattern = r->pattern;
    PyObject *seams = PyList_New(pattern->seam_count), *darts = PyList_New(pattern->dart_count);
    int failed = !seams || !darts;
    for (int32_t s = 0; !failed && s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        PyObject *head = Py_BuildValue("{s:(ii)}", "panels", (int)seam->panel_a, (int)seam->panel_b);
        PyObject *item = sewn_item(r, head, seam->side_a, seam->side_b, seam->pair_count);
        failed = !item;
        if (item)
            PyList_SET_ITEM(seams, s, item);
    }
    for (int32_t d = 0; !failed && d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        PyObject *tip = pzpy_doubles(r->uv + 2 * (size_t)dart->tip, 2, 0);
        PyObject *head = tip ? Py_BuildValue("{s:i,s:i,s:N}", "panel", (int)dart->panel, "tip",
                                             (int)pattern->vertex_origin[dart->tip], "pattern_tip", tip)
                             : NULL;
        PyObject *item = sewn_item(r, head, dart->leg_a, dart->leg_b, dart->pair_count);
        failed = !item;
        if (item)
            PyList_SET_ITEM(darts, d, item);
    }
    if (failed) {
        Py_XDECREF(seams);
        Py_XDECREF(darts);
        return -1;
    }
    return pzpy_set(object, "seams", seams) < 0 || pzpy_set(object, "darts", darts) < 0 ? -1 : 0;
}

/* The layout's seams and darts as 3D polylines on the garment. */
static int set_curves(PyObject *object, const pz_result *r)
{
    PyObject *curves = PyList_New(0);
    npy_intp count = r->layout_curve_count;
    PyObject *is_dart = PyArray_SimpleNew(1, &count, NPY_BOOL);
    int failed = !curves || !is_dart;
    for (int32_t c = 0; !failed && c < r->layout_curve_count; ++c) {
        int32_t begin = r->layout_offsets[c], end = r->layout_offsets[c + 1];
        npy_intp shape[2] = {end - begin, 3};
        PyObject *curve = PyArray_SimpleNew(2, shape, NPY_FLOAT64);
        for (int32_t i = begin; curve && i < end; ++i)
            memcpy((double *)PyArray_DATA((PyArrayObject *)curve) + 3 * (i - begin),
                   r->garment->positions + 3 * (size_t)r->layout_vertices[i], 3 * sizeof(double));
        failed = !curve || PyList_Append(curves, curve) < 0;
        Py_XDECREF(curve);
        ((npy_bool *)PyArray_DATA((PyArrayObject *)is_dart))[c] = r->layout_is_dart[c] != 0;
    }
    if (failed) {
        Py_XDECREF(curves);
        Py_XDECREF(is_dart);
        return -1;
    }
    return pzpy_set(object, "curves", curves) < 0 || pzpy_set(object, "curve_is_dart", is_dart) < 0 ? -1 : 0;
}

/* Every attribute of a Result (its doc lists them). */
static int set_result_attributes(PyObject *object, const pz_result *r)
{
    const pz_pattern *pattern = r->pattern;
    const pz_mesh *cut = pattern->mesh;
    npy_intp shape[3] = {cut->face_count, 3, 2};
    PyObject *corners = PyArray_SimpleNew(3, shape, NPY_FLOAT64);
    for (int32_t c = 0; corners && c < 3 * cut->face_count; ++c)
        memcpy((double *)PyArray_DATA((PyArrayObject *)corners) + 2 * c, r->uv + 2 * (size_t)cut->faces[c],
               2 * sizeof(double));
    double worst = 0;
    for (int i = 0; i < r->metrics_count; ++i)
        worst = fmax(worst, r->metrics[i]->max_abs_strain);
    PyObject *names = pzpy_names(r->panel_names, pattern->panel_count);
    cJSON *report = pz_result_report(r);
    int failed = pzpy_set(object, "vertices", pzpy_doubles(r->garment->positions, r->garment->vertex_count, 3)) < 0 ||
                 pzpy_set(object, "faces", pzpy_ints(r->garment->faces, r->garment->face_count, 3)) < 0 ||
                 pzpy_set(object, "face_panel", pzpy_ints(pattern->face_panel, cut->face_count, 0)) < 0 ||
                 pzpy_set(object, "panel_count", PyLong_FromLong(pattern->panel_count)) < 0 ||
                 pzpy_set(object, "panel_names", names) < 0 || pzpy_set(object, "pattern", corners) < 0 ||
                 pzpy_set(object, "pattern_uv", pzpy_doubles(r->uv, cut->vertex_count, 2)) < 0 ||
                 pzpy_set(object, "pattern_faces", pzpy_ints(cut->faces, cut->face_count, 3)) < 0 ||
                 pzpy_set(object, "pattern_vertex", pzpy_ints(pattern->vertex_origin, cut->vertex_count, 0)) < 0 ||
                 set_seams_and_darts(object, r) < 0 || set_curves(object, r) < 0 ||
                 pzpy_set(object, "goals_met", r->verdict.judged ? PyBool_FromLong(r->verdict.goals_met)
                                                                 : Py_NewRef(Py_None)) < 0 ||
                 pzpy_set(object, "worst_strain", PyFloat_FromDouble(worst)) < 0 ||
                 pzpy_set(object, "units", PyUnicode_FromString(pz_units_str(r->units))) < 0 ||
                 pzpy_set(object, "report", report ? pzpy_from_json(report) : PyErr_NoMemory()) < 0;
    cJSON_Delete(report);
    return failed ? -1 : 0;
}

/* run and flatten: everything but which library call. */
static PyObject *pattern_call(PyObject *args, PyObject *kwargs_given, int flatten)
{
    const char *function = flatten ? "flatten" : "run";
    PyObject *kwargs = pzpy_consumable(kwargs_given), *object = NULL;
    if (!kwargs)
        return NULL;
    pzpy_keep keep = {NULL};
    pattern_job data;
    memset(&data, 0, sizeof data);
    data.flatten = flatten;
    pzpy_garment garment;
    PyObject *progress, *cancel, *panels, *sketches = NULL, *strict = NULL, *seams = NULL, *darts = NULL,
                                                    *units = NULL;
    int strict_flag = 0;
    if (pzpy_garment_from_call(args, kwargs, function, &garment, &keep) < 0 ||
        pzpy_pop_control(kwargs, &keep, &progress, &cancel) < 0 || !(panels = pzpy_pop(kwargs, "panels", &keep)))
        goto done;
    units = PyDict_GetItemString(kwargs, "units"); /* borrowed: pzpy_run_options pops it into `keep` */
    units = units ? units : Py_None;
    if (flatten ? !(seams = pzpy_pop(kwargs, "seams", &keep)) || !(darts = pzpy_pop(kwargs, "darts", &keep))
                : !(sketches = pzpy_pop(kwargs, "sketches", &keep)) || !(strict = pzpy_pop(kwargs, "strict", &keep)))
        goto done;
    if (!flatten && strict != Py_None && (strict_flag = PyObject_IsTrue(strict)) < 0)
        goto done;
    int parsed = pzpy_run_options(kwargs, !flatten, &data.options, &keep);
    data.options.units = garment_units(&garment, units, data.options.units);
    if (parsed < 0 || pzpy_no_more_keywords(kwargs, function) < 0 || pzpy_garment_mesh(&garment, &data.mesh) < 0)
        goto done;
    if (!data.options.name)
        data.options.name = garment.name;
    if (panels_option(panels, &data, &keep) < 0)
        goto done;
    if (flatten && (path_list(seams, "seams", &keep, (const char ***)&data.seam_paths, &data.seam_count) < 0 ||
                    path_list(darts, "darts", &keep, (const char ***)&data.dart_paths, &data.dart_count) < 0))
        goto done;
    if (!flatten && sketches != Py_None) {
        pz_units sketch_units = data.options.units == PZ_UNITS_AUTO ? pz_mesh_guess_units(data.mesh) : data.options.units;
        if (pzpy_sketch_from_curves(sketches, pz_units_to_mm(sketch_units), &data.sketch) < 0)
            goto done;
        data.options.sketch = data.sketch;
    }
    pzpy_job job = {run_pattern, &data};
    if (pzpy_run_job_or_raise(&job, progress, cancel) < 0)
        goto done;
    if (!(object = pzpy_result_object(&data.result)))
        goto done;
    const pz_result *kept = pzpy_result_of(object);
    if (set_result_attributes(object, kept) < 0)
        Py_CLEAR(object);
    else if (strict_flag && !kept->verdict.goals_met) {
        pzpy_goals_error(object, kept->verdict.reasons);
        Py_CLEAR(object);
    }
done:
    free((void *)data.seam_paths);
    free((void *)data.dart_paths);
    pattern_job_clear(&data);
    pzpy_keep_clear(&keep);
    Py_DECREF(kwargs);
    return object;
}

const char pzpy_run_doc[] =
    "run(vertices, faces, *, poses=None, units=None, max_strain=0.05, max_corners=8, max_seam_mismatch=0.005, "
    "min_piece_width=40, min_piece_area=0.01, min_dart_intake=6, strict=False, symmetry='auto', fold=False, "
    "darts=True, truing=True, consolidate=True, sketch=None, sketches=None, mirror_sketch=False, panels=None, prepare='auto', grain=None, grain_hints=None, "
    "backend='textile', iterations=20, weights=(5, 1, 5, 5), fabric=None, scheme=None, relax=None, features=None, "
    "seam_allowance=10, hem_allowance=None, allowances=None, notch_spacing=100, paper='a4', dxf_strict=False, "
    "fabric_width=1500, gap=5, size='base', repair=False, name=None, progress=None, cancel=None)\n--\n\n"
    "The whole pipeline, as `panelize run`: cuts the garment into panels along field-aligned seams, adds darts and "
    "flattens every panel; returns a panelize.Result (numpy arrays, report, write()).\n\n"
    "vertices: (n, 3) real numbers; faces: (m, 3) integers in 0..n-1; or a panelize.Mesh alone in their place "
    "(then in millimetres). poses: extra poses, a sequence of (n, 3) arrays or a (k, n, 3) array. units: None "
    "or 'auto' (guessed, as the command line does), 'mm', 'cm', 'm'. Every other keyword is the command line's "
    "option of the same name (--max-strain is max_strain=, see `panelize run --help` and docs/python.md), with "
    "the same default (None keeps it) and the same range; on/off options take True/False. sketches: seams the "
    "user drew, a sequence of (k, 3) arrays in the vertices' units (sketch= is a JSON file). panels: None "
    "(segment), 'uv', a panels file, or one id per face (0..K-1, each used). symmetry: 'auto', 'off', 'x', 'y', "
    "'z', (nx, ny, nz, d) or (px, py, pz, nx, ny, nz). strict=True raises GoalsNotMetError (carrying .result) "
    "when a goal is missed.\n\n"
    "progress: called as progress(stage, fraction, message) on the calling thread, fraction never decreasing. "
    "cancel: an object with is_set() (threading.Event): once set, the run stops and raises CancelledError. "
    "Ctrl-C stops it too (KeyboardInterrupt). The GIL is released while the library works.\n\n"
    "Raises TypeError / ValueError naming an argument of the wrong type or shape; UsageError (64) for an option "
    "out of range; DataError (65) for bad data (indices out of range, no faces, an invalid mesh); OpenError "
    "(66) for an option file that cannot be read.";

const char pzpy_flatten_doc[] =
    "flatten(vertices, faces, *, panels=None, labels=None, uv=None, uv_faces=None, seams=None, darts=None, "
    "poses=None, units=None, grain=None, grain_hints=None, backend='textile', iterations=20, weights=(5, 1, 5, 5), fabric=None, "
    "scheme=None, relax=None, features=None, seam_allowance=10, hem_allowance=None, allowances=None, "
    "notch_spacing=100, paper='a4', dxf_strict=False, fabric_width=1500, gap=5, size='base', repair=False, "
    "name=None, progress=None, cancel=None)\n--\n\n"
    "The user's own panels flattened, as `panelize flatten`: no segmentation, no goals (goals_met is None). "
    "panels: None or 'groups' (one panel per connected piece of each label), 'labels' (one per label), 'uv' "
    "(the UV islands: give uv and uv_faces), a panels file, or one id per face. labels: one integer per face "
    "(a Mesh carries its own). seams, darts: seam and dart files (docs/flatten.md), in the mesh's vertex ids. "
    "The other keywords, progress, cancel, the result and the errors are as in run().";

PyObject *pzpy_run(PyObject *self, PyObject *args, PyObject *kwargs)
{
    (void)self;
    return pattern_call(args, kwargs, 0);
}

PyObject *pzpy_flatten(PyObject *self, PyObject *args, PyObject *kwargs)
{
    (void)self;
    return pattern_call(args, kwargs, 1);
}
