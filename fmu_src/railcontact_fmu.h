/*
 * railcontact FMU: a thin FMI 2.0 Co-Simulation shim around an embedded CPython.
 *
 * Design (a shim of our own rather than pythonfmu or unifmu: one binary that loads in C and
 * in Python hosts alike, at a few microseconds per call; see also the FMU documentation):
 *  - which Python: the environment variable RAILCONTACT_PYTHON (a python executable or a
 *    venv/prefix folder), else resources/python.txt (`railcontact fmu build --python`),
 *    else the Python the FMU was built with (resources/python.cfg); the first that is set
 *    is used, and a broken one is an error, not a reason to try the next;
 *  - that Python is asked (`PYTHON -I resources/python/fmu_bootstrap.py probe`) for its
 *    version, environment, site-packages and shared libpython;
 *  - no link-time libpython: the few C-API functions are resolved with dlsym, from the
 *    process when it already runs Python (fmpy, libcosimpy: the FMU then runs in the host's
 *    interpreter and says so), otherwise from the chosen Python's libpython (overridable:
 *    RAILCONTACT_FMU_LIBPYTHON), which is loaded and initialised with Py_InitializeEx(0)
 *    as that Python's own executable, ignoring the environment (PYTHONPATH, PYTHONHOME) and
 *    the user site-packages: only that environment's site-packages and the FMU's resources;
 *  - Py_Finalize is never called and the library is linked with -z nodelete;
 *  - each host thread keeps one Python thread state; a call only takes and gives back the
 *    GIL;
 *  - Real and Integer values are read and written in C directly in the slave's numpy
 *    buffers; doStep, initialisation, strings and state go to the Python slave, whose
 *    methods return an FMI status and never raise;
 *  - every message goes to the FMI logger whole, in pieces of at most LOG_PIECE bytes
 *    (hosts format a message into a fixed buffer: fmpy's holds 4096 bytes).
 *
 * The shim's files, by job (every .c file of this folder is compiled into the one binary;
 * only the FMI functions and railcontact_fmu_locate/_free are exported, the build compiles
 * with -fvisibility=hidden):
 *  - fmi2_functions.c  the FMI 2.0 entry points
 *  - instance.c        an instance: its Python slave (bootstrap, bound methods, buffers),
 *                      the value access and the calls that return an FMI status
 *  - python_api.c      the table of CPython C-API functions, resolved with dlsym
 *  - python_locate.c   which Python: the choice, the probe, railcontact_fmu_locate
 *  - python_start.c    the interpreter: start once (or use the host's), thread states
 *  - log.c             messages to the FMI logger, in pieces
 *  - strbuf.c          growing strings, "key=value" text and whole files
 */
#ifndef RAILCONTACT_FMU_H
#define RAILCONTACT_FMU_H

#include <stddef.h>
#include <stdint.h>
#include <wchar.h>

#include "fmi2Functions.h"

/* the slave's buffers are numpy float64 and int32 arrays */
_Static_assert(sizeof(fmi2Real) == sizeof(double), "fmi2Real must be a double");
_Static_assert(sizeof(fmi2Integer) == sizeof(int32_t), "fmi2Integer must be 32 bits");

#define RC_EXPORT __attribute__((visibility("default")))

/* ---- strbuf.c: growing strings ------------------------------------------------------ */
typedef struct {
    char *s;
    size_t n, cap;
} Str;

void str_addn(Str *b, const char *t, size_t k);
void str_add(Str *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
const char *str_get(const Str *b);
/* the value of "key=value" in a text of such lines (a new string), or NULL */
char *text_value(const char *text, const char *key);
/* a whole file (a new string), or NULL */
char *read_file(const char *path);

/* ---- python_api.c: the CPython C-API, resolved at run time -------------------------- */
typedef void PyObject;
typedef int PyGILState_STATE;

#define Py_file_input 257

typedef struct {
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
} PythonApi;

extern PythonApi py;

/* the symbol name in lib (NULL: the process) */
void *sym(void *lib, const char *name);
/* fill the table py from lib (NULL: the process); 0 with the reason in err */
int resolve(void *lib, Str *err);

/* ---- python_locate.c: which Python ------------------------------------------------ */
/* On success (*ok = 1) key=value lines: source, requested, executable and the probe's
 * (version, prefix, libpython, site, ...); on failure the whole message for the user.
 * A new string. use_env = 0: as if RAILCONTACT_PYTHON were not set. */
char *locate(const char *resources, int use_env, int *ok);
RC_EXPORT char *railcontact_fmu_locate(const char *resources, int use_env, int *ok);
RC_EXPORT void railcontact_fmu_free(char *text);

/* ---- python_start.c: the interpreter ---------------------------------------------- */
extern int py_ready;
extern int py_host;          /* the process ran Python before the FMU came */
extern char *py_located;     /* which Python and how: passed to the bootstrap */

/* start Python once per process (or take the host's); 0 with the message in err */
int start_python(const char *resources, Str *err);
/* a persistent thread state for a host thread that has none (C hosts) */
void prime_thread(void);

/* every call into Python: this thread's state, the GIL taken and given back */
#define ENTER                                                                          \
    prime_thread();                                                                    \
    PyGILState_STATE gil_ = py.GILEnsure();
#define LEAVE py.GILRelease(gil_);

/* ---- instance.c: an instance and its slave ------------------------------------------ */
enum { OUTPUT = 0, INPUT = 1, PARAMETER = 2 };
enum { INSTANTIATED, INITIALIZATION, STEPPING, TERMINATED, FAILED };
/* why a value was not set (the slave's refusal() words it, naming the variable) */
enum { REFUSED_UNKNOWN, REFUSED_OUTPUT, REFUSED_PARAMETER, REFUSED_ENDED, REFUSED_NULL };

typedef struct {
    char *name;
    fmi2CallbackFunctions cb;
    int logging;
    int mode;
    PyObject *slave;
    PyObject *m_do_step, *m_exit_init, *m_enter_init, *m_reset, *m_get_state, *m_set_state,
        *m_check_state, *m_get_string, *m_set_string, *m_pop_log, *m_terminate, *m_close,
        *m_refusal;
    double *real;
    size_t n_real;
    int32_t *integer;
    size_t n_integer;
    /* the slave's (time [s], step size [s]) of the step asked for and the last successful
     * time [s] (fmi2LastSuccessfulTime): in the slave's array, so that a saved FMU state
     * holds them and a restored one brings them back */
    double *control;
    unsigned char *real_flags, *integer_flags, *string_flags;
    size_t n_string;
    char **string_cache;
    /* the run of fmi2DoStep calls discarded at the same communication point and step size
     * with no input changed between them (0: the last step was not discarded), its point
     * and size: repeated, such a call would give the same answer (fmi2Terminated) */
    int discards;
    double discarded_at, discarded_size;
} Instance;

/* a new instance with its started slave, or NULL (the reason logged) */
Instance *instance_new(fmi2String name, fmi2Type type, fmi2String resources_uri,
                       const fmi2CallbackFunctions *cb, fmi2Boolean logging);
void instance_free(Instance *c);
/* log the slave's messages since the last call (pop_log) with status s; GIL held */
void log_pending(Instance *c, fmi2Status s);
/* call a method (no arguments, or prebuilt ones) that returns an FMI status; GIL held */
fmi2Status call_status(Instance *c, PyObject *m, PyObject *args);
/* Real and Integer values in the slave's numpy buffers (double, int32), copied element by
 * element, checking the value reference (and, to set, the causality) */
fmi2Status get_values(Instance *c, const char *type, const fmi2ValueReference vr[],
                      size_t n, const void *buffer, size_t count, size_t size, void *value);
fmi2Status set_values(Instance *c, const char *type, const fmi2ValueReference vr[],
                      size_t n, void *buffer, const unsigned char *flags, size_t count,
                      size_t size, const void *value);
/* why the variable vr of count, with causality flags, cannot be set in the instance's
 * mode (REFUSED_*), or -1: it can */
int refusal(const Instance *c, fmi2ValueReference vr, const unsigned char *flags,
            size_t count);
/* log the refusal to set the type variable vr for reason (REFUSED_*), the variable named by
 * the slave; GIL not held */
void log_refusal(Instance *c, const char *type, fmi2ValueReference vr, int reason);

/* ---- log.c: the FMI logger ---------------------------------------------------------- */
#define LOG_PIECE 1000

/* the whole text, in pieces of at most LOG_PIECE bytes */
void log_text(Instance *c, fmi2Status status, const char *category, const char *text);
void logf_(Instance *c, fmi2Status status, const char *category, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
const char *category_of(fmi2Status s);

#endif
