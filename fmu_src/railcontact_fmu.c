/*
 * railcontact FMU: a thin FMI 2.0 Co-Simulation shim around an embedded CPython.
 *
 * Design (see ../shared/reference/fmu.md):
 *  - no link-time libpython: the few C-API functions are resolved with dlsym, from the
 *    process when it already runs Python (fmpy, libcosimpy), otherwise from the libpython
 *    recorded in resources/python.cfg (overridable: RAILCONTACT_FMU_LIBPYTHON,
 *    RAILCONTACT_FMU_PYTHONHOME), which is loaded and initialised with Py_InitializeEx(0);
 *  - Py_Finalize is never called and the library is linked with -z nodelete;
 *  - each host thread keeps one Python thread state; a call only takes and gives back the
 *    GIL;
 *  - Real and Integer values are read and written in C directly in the slave's numpy
 *    buffers; doStep, initialisation, strings and state go to the Python slave, whose
 *    methods return an FMI status and never raise.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

#include "fmi2Functions.h"

/* the slave's buffers are numpy float64 and int32 arrays */
_Static_assert(sizeof(fmi2Real) == sizeof(double), "fmi2Real must be a double");
_Static_assert(sizeof(fmi2Integer) == sizeof(int32_t), "fmi2Integer must be 32 bits");

typedef void PyObject;
typedef int PyGILState_STATE;

#define Py_file_input 257

static struct {
    int (*IsInitialized)(void);
    void (*InitializeEx)(int);
    void (*SetPythonHome)(const wchar_t *);
    wchar_t *(*DecodeLocale)(const char *, size_t *);
    void *(*EvalSaveThread)(void);
    PyGILState_STATE (*GILEnsure)(void);
    void (*GILRelease)(PyGILState_STATE);
    void *(*GILThisThread)(void);
    PyObject *(*DictNew)(void);
    int (*DictSetItemString)(PyObject *, const char *, PyObject *);
    PyObject *(*DictGetItemString)(PyObject *, const char *);
    PyObject *(*UnicodeFromString)(const char *);
    const char *(*UnicodeAsUTF8)(PyObject *);
    PyObject *(*RunStringFlags)(const char *, int, PyObject *, PyObject *, void *);
    PyObject *(*GetAttrString)(PyObject *, const char *);
    PyObject *(*CallObject)(PyObject *, PyObject *);
    PyObject *(*BuildValue)(const char *, ...);
    long (*LongAsLong)(PyObject *);
    unsigned long long (*LongAsULL)(PyObject *);
    PyObject *(*TupleGetItem)(PyObject *, long);
    long (*BytesSize)(PyObject *);
    char *(*BytesAsString)(PyObject *);
    PyObject *(*BytesFromStringAndSize)(const char *, long);
    void (*DecRef)(PyObject *);
    PyObject *(*ErrOccurred)(void);
    void (*ErrClear)(void);
} py;

static int py_ready = 0;
static char py_error[1024] = "";

enum { OUTPUT = 0, INPUT = 1, PARAMETER = 2 };
enum { INSTANTIATED, INITIALIZATION, STEPPING, TERMINATED, FAILED };

typedef struct {
    char *name;
    fmi2CallbackFunctions cb;
    int logging;
    int mode;
    PyObject *slave;
    PyObject *m_do_step, *m_exit_init, *m_enter_init, *m_reset, *m_get_state, *m_set_state,
        *m_get_string, *m_set_string, *m_pop_log;
    double *real;
    size_t n_real;
    int32_t *integer;
    size_t n_integer;
    double *control;
    unsigned char *real_flags, *integer_flags, *string_flags;
    size_t n_string;
    char **string_cache;
    double time;
} Instance;

typedef struct {
    PyObject *bytes;
} State;

/* ---- logging ------------------------------------------------------------------------ */
static void logf_(Instance *c, fmi2Status status, const char *category, const char *fmt, ...) {
    if (!c || !c->cb.logger) return;
    char buf[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    c->cb.logger(c->cb.componentEnvironment, c->name, status, category, "%s", buf);
}

static const char *category_of(fmi2Status s) {
    switch (s) {
    case fmi2Warning: return "logStatusWarning";
    case fmi2Discard: return "logStatusDiscard";
    case fmi2Error: return "logStatusError";
    case fmi2Fatal: return "logStatusFatal";
    default: return "logAll";
    }
}

/* ---- Python start-up ---------------------------------------------------------------- */
static void *sym(void *lib, const char *name) {
    void *p = dlsym(lib ? lib : RTLD_DEFAULT, name);
    return p;
}

static int resolve(void *lib) {
#define R(field, name)                                                                 \
    py.field = sym(lib, name);                                                         \
    if (!py.field) {                                                                   \
        snprintf(py_error, sizeof py_error, "CPython symbol %s not found", name);      \
        return 0;                                                                      \
    }
    R(IsInitialized, "Py_IsInitialized");
    R(InitializeEx, "Py_InitializeEx");
    R(DecodeLocale, "Py_DecodeLocale");
    R(EvalSaveThread, "PyEval_SaveThread");
    R(GILEnsure, "PyGILState_Ensure");
    R(GILRelease, "PyGILState_Release");
    R(GILThisThread, "PyGILState_GetThisThreadState");
    R(DictNew, "PyDict_New");
    R(DictSetItemString, "PyDict_SetItemString");
    R(DictGetItemString, "PyDict_GetItemString");
    R(UnicodeFromString, "PyUnicode_FromString");
    R(UnicodeAsUTF8, "PyUnicode_AsUTF8");
    R(RunStringFlags, "PyRun_StringFlags");
    R(GetAttrString, "PyObject_GetAttrString");
    R(CallObject, "PyObject_CallObject");
    R(BuildValue, "Py_BuildValue");
    R(LongAsLong, "PyLong_AsLong");
    R(LongAsULL, "PyLong_AsUnsignedLongLong");
    R(TupleGetItem, "PyTuple_GetItem");
    R(BytesSize, "PyBytes_Size");
    R(BytesAsString, "PyBytes_AsString");
    R(BytesFromStringAndSize, "PyBytes_FromStringAndSize");
    R(DecRef, "Py_DecRef");
    R(ErrOccurred, "PyErr_Occurred");
    R(ErrClear, "PyErr_Clear");
#undef R
    py.SetPythonHome = sym(lib, "Py_SetPythonHome"); /* optional (removed in 3.13) */
    return 1;
}

/* read "key=value" from resources/python.cfg */
static int config_value(const char *resources, const char *key, char *out, size_t n) {
    char path[4096];
    snprintf(path, sizeof path, "%s/python.cfg", resources);
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    char line[4096];
    size_t k = strlen(key);
    int found = 0;
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, key, k) == 0 && line[k] == '=') {
            line[strcspn(line, "\r\n")] = 0;
            snprintf(out, n, "%s", line + k + 1);
            found = 1;
            break;
        }
    }
    fclose(f);
    return found;
}

static __thread int thread_primed = 0;

/* a persistent thread state for a host thread that has none (C hosts) */
static void prime_thread(void) {
    if (thread_primed) return;
    if (!py.GILThisThread()) {
        py.GILEnsure();      /* creates the thread state (counter 1) and takes the GIL */
        py.EvalSaveThread(); /* gives the GIL back, keeps the thread state */
    }
    thread_primed = 1;
}

static int start_python(const char *resources) {
    if (py_ready) return 1;
    void *self_lib = NULL;
    py.IsInitialized = sym(NULL, "Py_IsInitialized");
    if (py.IsInitialized && py.IsInitialized()) {
        if (!resolve(NULL)) return 0;
        py_ready = 1;
        return 1;
    }
    char lib[4096] = "", home[4096] = "", version[64] = "?";
    const char *env = getenv("RAILCONTACT_FMU_LIBPYTHON");
    if (env && *env) snprintf(lib, sizeof lib, "%s", env);
    else config_value(resources, "libpython", lib, sizeof lib);
    env = getenv("RAILCONTACT_FMU_PYTHONHOME");
    if (env && *env) snprintf(home, sizeof home, "%s", env);
    else config_value(resources, "home", home, sizeof home);
    config_value(resources, "version", version, sizeof version);
    self_lib = dlopen(lib, RTLD_NOW | RTLD_GLOBAL);
    if (!self_lib) {
        snprintf(py_error, sizeof py_error,
                 "cannot load the Python %s library '%s' this FMU was built with (%s); "
                 "install Python %s with its shared library, or set "
                 "RAILCONTACT_FMU_LIBPYTHON to its libpython path",
                 version, lib, dlerror(), version);
        return 0;
    }
    if (!resolve(self_lib)) return 0;
    if (!py.IsInitialized()) {
        if (*home && py.SetPythonHome) {
            static wchar_t *whome = NULL; /* must outlive the interpreter */
            whome = py.DecodeLocale(home, NULL);
            if (whome) py.SetPythonHome(whome);
        } else if (*home) {
            setenv("PYTHONHOME", home, 0);
        }
        py.InitializeEx(0);
        py.EvalSaveThread(); /* the main thread keeps its state, releases the GIL */
    }
    py_ready = 1;
    return 1;
}

static const char BOOTSTRAP[] =
    "import os, sys, traceback\n"
    "error = ''\n"
    "try:\n"
    "    _p = os.path.join(__rc_resources__, 'python', 'fmu_bootstrap.py')\n"
    "    with open(_p) as _f:\n"
    "        exec(compile(_f.read(), _p, 'exec'))\n"
    "    slave = make_slave(__rc_resources__, __rc_instance__)\n"
    "except BaseException:\n"
    "    error = traceback.format_exc()\n";

/* file:///a/b%20c -> /a/b c */
static char *uri_to_path(const char *uri) {
    if (!uri) return NULL;
    const char *p = uri;
    if (strncmp(p, "file://", 7) == 0) {
        p += 7;
        if (strncmp(p, "localhost/", 10) == 0) p += 9;
    } else if (strncmp(p, "file:", 5) == 0) {
        p += 5;
    }
    char *out = malloc(strlen(p) + 1), *o = out;
    for (; *p; ++p) {
        if (*p == '%' && p[1] && p[2]) {
            char hex[3] = {p[1], p[2], 0};
            *o++ = (char)strtol(hex, NULL, 16);
            p += 2;
        } else {
            *o++ = *p;
        }
    }
    *o = 0;
    size_t n = strlen(out);
    while (n > 1 && out[n - 1] == '/') out[--n] = 0;
    return out;
}

static PyObject *method(PyObject *obj, const char *name) { return py.GetAttrString(obj, name); }

/* call a no-argument (or prebuilt-argument) method that returns an FMI status */
static fmi2Status call_status(Instance *c, PyObject *m, PyObject *args) {
    PyObject *r = py.CallObject(m, args);
    long s = 3;
    if (r) {
        s = py.LongAsLong(r);
        py.DecRef(r);
    } else {
        py.ErrClear();
    }
    if (s != 0) {
        PyObject *msg = py.CallObject(c->m_pop_log, NULL);
        if (msg) {
            const char *t = py.UnicodeAsUTF8(msg);
            if (t && *t) logf_(c, (fmi2Status)s, category_of((fmi2Status)s), "%s", t);
            py.DecRef(msg);
        } else {
            py.ErrClear();
        }
    }
    return (s >= 0 && s <= 3) ? (fmi2Status)s : fmi2Error;
}

#define ENTER                                                                          \
    prime_thread();                                                                    \
    PyGILState_STATE gil_ = py.GILEnsure();
#define LEAVE py.GILRelease(gil_);

/* ---- FMI 2.0 ------------------------------------------------------------------------ */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n,
                               const fmi2String categories[]) {
    (void)n;
    (void)categories;
    if (!comp) return fmi2Error;
    ((Instance *)comp)->logging = on;
    return fmi2OK;
}

static void free_instance(Instance *c) {
    if (!c) return;
    if (c->slave && py_ready) {
        ENTER;
        PyObject *objs[] = {c->m_do_step, c->m_exit_init, c->m_enter_init, c->m_reset,
                            c->m_get_state, c->m_set_state, c->m_get_string, c->m_set_string,
                            c->m_pop_log, c->slave};
        for (size_t k = 0; k < sizeof objs / sizeof objs[0]; ++k)
            if (objs[k]) py.DecRef(objs[k]);
        LEAVE;
    }
    if (c->string_cache) {
        for (size_t k = 0; k < c->n_string; ++k) free(c->string_cache[k]);
        free(c->string_cache);
    }
    free(c->real_flags);
    free(c->integer_flags);
    free(c->string_flags);
    free(c->name);
    free(c);
}

static unsigned char *copy_bytes(PyObject *b, size_t *n) {
    long len = py.BytesSize(b);
    unsigned char *out = malloc(len > 0 ? (size_t)len : 1);
    if (len > 0) memcpy(out, py.BytesAsString(b), (size_t)len);
    if (n) *n = len > 0 ? (size_t)len : 0;
    return out;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources_uri, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean logging) {
    (void)guid;
    (void)visible;
    if (!cb || !cb->logger) return NULL;
    Instance *c = calloc(1, sizeof(Instance));
    c->name = strdup(name ? name : "railcontact");
    c->cb = *cb;
    c->logging = logging;
    if (type != fmi2CoSimulation) {
        logf_(c, fmi2Error, "logStatusError", "railcontact is a Co-Simulation FMU only");
        free_instance(c);
        return NULL;
    }
    char *resources = uri_to_path(resources_uri);
    if (!resources) {
        logf_(c, fmi2Error, "logStatusError", "no resource location given");
        free_instance(c);
        return NULL;
    }
    if (!start_python(resources)) {
        logf_(c, fmi2Error, "logStatusError", "cannot start Python: %s", py_error);
        free(resources);
        free_instance(c);
        return NULL;
    }
    int ok = 0;
    ENTER;
    PyObject *g = py.DictNew();
    PyObject *s1 = py.UnicodeFromString(resources), *s2 = py.UnicodeFromString(c->name);
    py.DictSetItemString(g, "__rc_resources__", s1);
    py.DictSetItemString(g, "__rc_instance__", s2);
    py.DecRef(s1);
    py.DecRef(s2);
    PyObject *r = py.RunStringFlags(BOOTSTRAP, Py_file_input, g, g, NULL);
    if (!r) {
        py.ErrClear();
        logf_(c, fmi2Error, "logStatusError", "the FMU's Python bootstrap failed");
    } else {
        py.DecRef(r);
        PyObject *err = py.DictGetItemString(g, "error"); /* borrowed */
        const char *etext = err ? py.UnicodeAsUTF8(err) : NULL;
        PyObject *slave = py.DictGetItemString(g, "slave");
        if (etext && *etext) {
            logf_(c, fmi2Error, "logStatusError", "cannot start the railcontact slave:\n%s",
                  etext);
        } else if (slave) {
            c->slave = py.BuildValue("O", slave); /* a new reference to the borrowed one */
            c->m_do_step = method(slave, "do_step");
            c->m_exit_init = method(slave, "exit_initialization");
            c->m_enter_init = method(slave, "enter_initialization");
            c->m_reset = method(slave, "reset");
            c->m_get_state = method(slave, "get_state");
            c->m_set_state = method(slave, "set_state");
            c->m_get_string = method(slave, "get_string");
            c->m_set_string = method(slave, "set_string");
            c->m_pop_log = method(slave, "pop_log");
            PyObject *bm = method(slave, "buffers");
            PyObject *b = bm ? py.CallObject(bm, NULL) : NULL;
            if (bm) py.DecRef(bm);
            if (b) {
                c->real = (double *)(uintptr_t)py.LongAsULL(py.TupleGetItem(b, 0));
                c->n_real = (size_t)py.LongAsLong(py.TupleGetItem(b, 1));
                c->integer = (int32_t *)(uintptr_t)py.LongAsULL(py.TupleGetItem(b, 2));
                c->n_integer = (size_t)py.LongAsLong(py.TupleGetItem(b, 3));
                c->control = (double *)(uintptr_t)py.LongAsULL(py.TupleGetItem(b, 4));
                c->real_flags = copy_bytes(py.TupleGetItem(b, 5), NULL);
                c->integer_flags = copy_bytes(py.TupleGetItem(b, 6), NULL);
                c->string_flags = copy_bytes(py.TupleGetItem(b, 7), &c->n_string);
                c->string_cache = calloc(c->n_string ? c->n_string : 1, sizeof(char *));
                py.DecRef(b);
                ok = c->m_do_step && c->m_exit_init && c->m_enter_init && c->m_reset &&
                     c->m_get_state && c->m_set_state && c->m_get_string &&
                     c->m_set_string && c->m_pop_log && !py.ErrOccurred();
            }
            if (!ok) {
                py.ErrClear();
                logf_(c, fmi2Error, "logStatusError", "the railcontact slave is incomplete");
            }
        }
    }
    py.DecRef(g);
    LEAVE;
    free(resources);
    if (!ok) {
        free_instance(c);
        return NULL;
    }
    c->mode = INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component comp) { free_instance((Instance *)comp); }

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tol_defined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    (void)tol_defined;
    (void)tol;
    (void)stop_defined;
    (void)stop;
    Instance *c = comp;
    if (!c) return fmi2Error;
    c->time = start;
    c->control[0] = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    Instance *c = comp;
    if (!c || c->mode != INSTANTIATED) return fmi2Error;
    ENTER;
    fmi2Status s = call_status(c, c->m_enter_init, NULL);
    LEAVE;
    c->mode = INITIALIZATION;
    return s;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Instance *c = comp;
    if (!c || c->mode != INITIALIZATION) return fmi2Error;
    c->control[0] = c->time;
    c->control[1] = 0.0;
    ENTER;
    fmi2Status s = call_status(c, c->m_exit_init, NULL);
    LEAVE;
    c->mode = s <= fmi2Warning ? STEPPING : FAILED;
    return s;
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    c->mode = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    ENTER;
    fmi2Status s = call_status(c, c->m_reset, NULL);
    LEAVE;
    c->mode = INSTANTIATED;
    c->time = 0.0;
    return s;
}

static int settable(Instance *c, unsigned char flag) {
    if (flag == INPUT) return c->mode != TERMINATED && c->mode != FAILED;
    if (flag == PARAMETER) return c->mode == INSTANTIATED || c->mode == INITIALIZATION;
    return 0;
}

/* Real and Integer values live in the slave's numpy buffers (double, int32): get and set
 * copy them element by element, checking the value reference (and, to set, the causality). */
static fmi2Status get_values(Instance *c, const char *type, const fmi2ValueReference vr[],
                             size_t n, const void *buffer, size_t count, size_t size,
                             void *value) {
    for (size_t k = 0; k < n; ++k) {
        if (vr[k] >= count) {
            logf_(c, fmi2Error, "logStatusError", "no %s variable %u", type, vr[k]);
            return fmi2Error;
        }
        memcpy((char *)value + k * size, (const char *)buffer + vr[k] * size, size);
    }
    return fmi2OK;
}

static fmi2Status set_values(Instance *c, const char *type, const fmi2ValueReference vr[],
                             size_t n, void *buffer, const unsigned char *flags, size_t count,
                             size_t size, const void *value) {
    for (size_t k = 0; k < n; ++k) {
        if (vr[k] >= count || !settable(c, flags[vr[k]])) {
            logf_(c, fmi2Error, "logStatusError", "%s variable %u cannot be set now", type,
                  vr[k]);
            return fmi2Error;
        }
        memcpy((char *)buffer + vr[k] * size, (const char *)value + k * size, size);
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[]) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    return get_values(c, "Real", vr, n, c->real, c->n_real, sizeof *value, value);
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer value[]) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    return get_values(c, "Integer", vr, n, c->integer, c->n_integer, sizeof *value, value);
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    Instance *c = comp;
    if (!c) return fmi2Error;
    if (n) logf_(c, fmi2Error, "logStatusError", "this FMU has no Boolean variables");
    return n ? fmi2Error : fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         fmi2String value[]) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    fmi2Status status = fmi2OK;
    ENTER;
    for (size_t k = 0; k < n; ++k) {
        if (vr[k] >= c->n_string) {
            status = fmi2Error;
            break;
        }
        PyObject *args = py.BuildValue("(I)", vr[k]);
        PyObject *r = py.CallObject(c->m_get_string, args);
        py.DecRef(args);
        const char *t = r ? py.UnicodeAsUTF8(r) : NULL;
        if (!t) {
            py.ErrClear();
            status = fmi2Error;
            if (r) py.DecRef(r);
            break;
        }
        free(c->string_cache[vr[k]]);
        c->string_cache[vr[k]] = strdup(t);
        value[k] = c->string_cache[vr[k]];
        py.DecRef(r);
    }
    LEAVE;
    return status;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real value[]) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    return set_values(c, "Real", vr, n, c->real, c->real_flags, c->n_real, sizeof *value,
                      value);
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer value[]) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    return set_values(c, "Integer", vr, n, c->integer, c->integer_flags, c->n_integer,
                      sizeof *value, value);
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    Instance *c = comp;
    if (!c) return fmi2Error;
    return n ? fmi2Error : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         const fmi2String value[]) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < n; ++k) {
        if (vr[k] >= c->n_string || !settable(c, c->string_flags[vr[k]]) || !value[k]) {
            logf_(c, fmi2Error, "logStatusError", "String variable %u cannot be set now",
                  vr[k]);
            return fmi2Error;
        }
    }
    ENTER;
    for (size_t k = 0; k < n && status == fmi2OK; ++k) {
        PyObject *args = py.BuildValue("(Is)", vr[k], value[k]);
        if (!args) {
            py.ErrClear();
            status = fmi2Error;
            break;
        }
        status = call_status(c, c->m_set_string, args);
        py.DecRef(args);
    }
    LEAVE;
    return status;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    Instance *c = comp;
    if (!c || c->mode != STEPPING) {
        if (c) logf_(c, fmi2Error, "logStatusError", "doStep outside step mode");
        return fmi2Error;
    }
    c->control[0] = t;
    c->control[1] = h;
    ENTER;
    fmi2Status s = call_status(c, c->m_do_step, NULL);
    LEAVE;
    if (s <= fmi2Warning) c->time = t + h;
    return s;
}

fmi2Status fmi2CancelStep(fmi2Component comp) {
    (void)comp;
    return fmi2Error;
}

/* keep the state bytes b (a new reference, or NULL on a Python error) in *state,
 * allocating the State on first use; called with the GIL held */
static fmi2Status store_state(fmi2FMUstate *state, PyObject *b) {
    if (!b) {
        py.ErrClear();
        return fmi2Error;
    }
    State *st = *state ? (State *)*state : calloc(1, sizeof(State));
    if (st->bytes) py.DecRef(st->bytes);
    st->bytes = b;
    *state = st;
    return fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    Instance *c = comp;
    if (!c || !state) return fmi2Error;
    ENTER;
    PyObject *b = py.CallObject(c->m_get_state, NULL);
    fmi2Status s = store_state(state, b);
    LEAVE;
    return s;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state) {
    Instance *c = comp;
    State *st = state;
    if (!c || !st || !st->bytes) return fmi2Error;
    ENTER;
    PyObject *args = py.BuildValue("(O)", st->bytes);
    fmi2Status s = call_status(c, c->m_set_state, args);
    py.DecRef(args);
    LEAVE;
    return s;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    (void)comp;
    if (!state || !*state) return fmi2OK;
    State *st = *state;
    if (st->bytes) {
        ENTER;
        py.DecRef(st->bytes);
        LEAVE;
    }
    free(st);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size) {
    (void)comp;
    State *st = state;
    if (!st || !st->bytes || !size) return fmi2Error;
    ENTER;
    *size = (size_t)py.BytesSize(st->bytes);
    LEAVE;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte data[],
                                 size_t size) {
    (void)comp;
    State *st = state;
    if (!st || !st->bytes) return fmi2Error;
    fmi2Status s = fmi2OK;
    ENTER;
    long n = py.BytesSize(st->bytes);
    if (n < 0 || (size_t)n > size) s = fmi2Error;
    else memcpy(data, py.BytesAsString(st->bytes), (size_t)n);
    LEAVE;
    return s;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte data[], size_t size,
                                   fmi2FMUstate *state) {
    (void)comp;
    if (!state) return fmi2Error;
    ENTER;
    PyObject *b = py.BytesFromStringAndSize((const char *)data, (long)size);
    fmi2Status s = store_state(state, b);
    LEAVE;
    return s;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real du[], fmi2Real dz[]) {
    (void)comp; (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz;
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)comp; (void)vr; (void)n; (void)order; (void)value;
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)comp; (void)vr; (void)n; (void)order; (void)value;
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value) {
    (void)comp; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
    Instance *c = comp;
    if (!c || s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = c->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s,
                                fmi2Integer *value) {
    (void)comp; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s,
                                fmi2Boolean *value) {
    Instance *c = comp;
    if (!c || s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s,
                               fmi2String *value) {
    (void)comp; (void)s; (void)value;
    return fmi2Discard;
}
