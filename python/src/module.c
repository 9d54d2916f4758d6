/*
 * python/src/module.c -- the module panelize._panelize (re-exported by the
 * package panelize): its functions, and its exceptions.
 *
 * Every failure of the library becomes one panelize.Error subclass carrying
 * the command line's category: .category (the words of pz_status_str),
 * .exit_code (the CLI's exit code for it, pz_status_exit_code) and .message
 * (the library's one-line message, as `panelize` prints it):
 *
 *   Error                        every failure of the library
 *     UsageError(ValueError)     64  an option out of range, a bad word
 *     DataError(ValueError)      65  bad input data, an invalid mesh
 *     OpenError                  66  an input that cannot be opened
 *     CreateError                73  an output that cannot be created
 *     InternalError              70  out of memory, a failed numerical step
 *     CancelledError             130 stopped through cancel= (Ctrl-C raises KeyboardInterrupt)
 *     GoalsNotMetError           3   run(strict=True): the pattern misses a goal (.result holds it)
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define PZ_PYTHON_MODULE_C
#include "internal.h"

#include <stdarg.h>

static PyObject *error_base, *goals_error, *usage_error, *data_error, *open_error, *create_error, *internal_error,
    *cancelled_error;

/* The class of a status. */
static PyObject *error_class(pz_status status)
{
    switch (status) {
    case PZ_ERR_USAGE: return usage_error;
    case PZ_ERR_DATA:
    case PZ_ERR_INVALID_MESH: return data_error;
    case PZ_ERR_OPEN: return open_error;
    case PZ_ERR_CREATE: return create_error;
    case PZ_ERR_CANCELLED: return cancelled_error;
    default: return internal_error;
    }
}

/* Raises `type` with `message`, its attributes set from `status`. */
static PyObject *raise_status(PyObject *type, pz_status status, const char *message)
{
    PyObject *error = PyObject_CallFunction(type, "s", message);
    if (!error)
        return NULL;
    PyObject *code = PyLong_FromLong(pz_status_exit_code(status));
    PyObject *category = PyUnicode_FromString(pz_status_str(status));
    PyObject *text = PyUnicode_FromString(message);
    if (code && category && text && PyObject_SetAttrString(error, "exit_code", code) == 0 &&
        PyObject_SetAttrString(error, "category", category) == 0 &&
        PyObject_SetAttrString(error, "message", text) == 0)
        PyErr_SetObject(type, error);
    Py_XDECREF(code);
    Py_XDECREF(category);
    Py_XDECREF(text);
    Py_DECREF(error);
    return NULL;
}

PyObject *pzpy_raise(pz_status status, const pz_ctx *ctx)
{
    const char *message = ctx && ctx->error[0] ? ctx->error : pz_status_str(status);
    if (status == PZ_ERR_NOMEM && !ctx->error[0])
        return PyErr_NoMemory();
    return raise_status(error_class(status), status, message);
}

PyObject *pzpy_usage_error(const char *fmt, ...)
{
    char message[sizeof ((pz_ctx *)0)->error];
    va_list arguments;
    va_start(arguments, fmt);
    vsnprintf(message, sizeof message, fmt, arguments);
    va_end(arguments);
    return raise_status(usage_error, PZ_ERR_USAGE, message);
}

void pzpy_goals_error(PyObject *result, const char *reasons)
{
    char message[sizeof ((pz_ctx *)0)->error];
    snprintf(message, sizeof message, "run: goals not met (strict): %s", reasons);
    PyObject *error = PyObject_CallFunction(goals_error, "s", message);
    PyObject *text = PyUnicode_FromString(message);
    if (error && text && PyObject_SetAttrString(error, "message", text) == 0 &&
        PyObject_SetAttrString(error, "result", result) == 0)
        PyErr_SetObject(goals_error, error);
    Py_XDECREF(text);
    Py_XDECREF(error);
}

/* ---------------------------------------------------------------- the module */

static PyMethodDef module_functions[] = {
    {"load", (PyCFunction)(void (*)(void))pzpy_load, METH_VARARGS | METH_KEYWORDS, pzpy_load_doc},
    {"run", (PyCFunction)(void (*)(void))pzpy_run, METH_VARARGS | METH_KEYWORDS, pzpy_run_doc},
    {"flatten", (PyCFunction)(void (*)(void))pzpy_flatten, METH_VARARGS | METH_KEYWORDS, pzpy_flatten_doc},
    {"field", (PyCFunction)(void (*)(void))pzpy_field, METH_VARARGS | METH_KEYWORDS, pzpy_field_doc},
    {"prepare", (PyCFunction)(void (*)(void))pzpy_prepare, METH_VARARGS | METH_KEYWORDS, pzpy_prepare_doc},
    {"generate", (PyCFunction)(void (*)(void))pzpy_generate, METH_VARARGS | METH_KEYWORDS, pzpy_generate_doc},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module_definition = {
    PyModuleDef_HEAD_INIT, "panelize._panelize",
    "The C extension of the panelize package (see help(panelize)): a thin caller of libpanelize.", -1,
    module_functions, NULL, NULL, NULL, NULL};

/* One exception class: panelize.NAME, its base(s), its doc, and its class attributes. */
static PyObject *add_error(PyObject *module, const char *name, PyObject *bases, const char *doc, pz_status status)
{
    char qualified[64];
    snprintf(qualified, sizeof qualified, "panelize.%s", name);
    PyObject *type = PyErr_NewExceptionWithDoc(qualified, doc, bases, NULL);
    if (!type)
        return NULL;
    int exit_code = status == PZ_OK ? 1 : status == (pz_status)3 ? 3 : pz_status_exit_code(status);
    const char *words = status == PZ_OK ? "error" : status == (pz_status)3 ? "goals not met" : pz_status_str(status);
    PyObject *code = PyLong_FromLong(exit_code);
    PyObject *category = PyUnicode_FromString(words);
    int failed = !code || !category || PyObject_SetAttrString(type, "exit_code", code) < 0 ||
                 PyObject_SetAttrString(type, "category", category) < 0;
    Py_XDECREF(code);
    Py_XDECREF(category);
    if (failed || PyModule_AddObjectRef(module, name, type) < 0) {
        Py_DECREF(type);
        return NULL;
    }
    return type; /* the module holds a reference; this one is kept for the life of the process */
}

static int add_errors(PyObject *module)
{
    error_base = add_error(module, "Error", PyExc_Exception,
                           "A failure of panelize: .category (as the command line names it), .exit_code (the "
                           "command line's exit code) and .message (its one-line message).", PZ_OK);
    if (!error_base)
        return -1;
    struct {
        PyObject **type;
        const char *name;
        PyObject *other_base;
        const char *doc;
        pz_status status;
    } classes[] = {
        {&usage_error, "UsageError", PyExc_ValueError, "An option out of range or a bad word (exit code 64).",
         PZ_ERR_USAGE},
        {&data_error, "DataError", PyExc_ValueError, "Bad input data or an invalid mesh (exit code 65).",
         PZ_ERR_DATA},
        {&open_error, "OpenError", NULL, "An input that cannot be opened or read (exit code 66).", PZ_ERR_OPEN},
        {&create_error, "CreateError", NULL, "An output that cannot be created or written (exit code 73).",
         PZ_ERR_CREATE},
        {&internal_error, "InternalError", NULL, "Out of memory or a failed numerical step (exit code 70).",
         PZ_ERR_INTERNAL},
        {&goals_error, "GoalsNotMetError", NULL,
         "run(strict=True): the pattern misses a goal (exit code 3, as `panelize run --strict`); .result holds it.",
         (pz_status)3},
        {&cancelled_error, "CancelledError", NULL,
         "The call was stopped through its cancel= object (exit code 130; Ctrl-C raises KeyboardInterrupt).",
         PZ_ERR_CANCELLED},
    };
    for (size_t i = 0; i < sizeof classes / sizeof classes[0]; ++i) {
        PyObject *bases = classes[i].other_base ? PyTuple_Pack(2, error_base, classes[i].other_base)
                                                : PyTuple_Pack(1, error_base);
        if (!bases)
            return -1;
        *classes[i].type = add_error(module, classes[i].name, bases, classes[i].doc, classes[i].status);
        Py_DECREF(bases);
        if (!*classes[i].type)
            return -1;
    }
    return 0;
}

PyMODINIT_FUNC PyInit__panelize(void)
{
    import_array();
    PyObject *module = PyModule_Create(&module_definition);
    if (!module)
        return NULL;
    PyTypeObject *types[] = {&pzpy_mesh_type, &pzpy_field_type, &pzpy_prepared_type, &pzpy_result_type};
    int failed = add_errors(module) < 0 || PyModule_AddStringConstant(module, "__version__", pz_version()) < 0;
    for (size_t i = 0; !failed && i < sizeof types / sizeof types[0]; ++i)
        failed = PyType_Ready(types[i]) < 0 || PyModule_AddObjectRef(module, strrchr(types[i]->tp_name, '.') + 1,
                                                                     (PyObject *)types[i]) < 0;
    if (failed) {
        Py_DECREF(module);
        return NULL;
    }
    return module;
}
