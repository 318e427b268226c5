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
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <wchar.h>

extern char **environ;

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
static int py_host = 0;             /* the process ran Python before the FMU came */
static char *py_located = NULL;     /* which Python and how: passed to the bootstrap */

enum { OUTPUT = 0, INPUT = 1, PARAMETER = 2 };
enum { INSTANTIATED, INITIALIZATION, STEPPING, TERMINATED, FAILED };

typedef struct {
    char *name;
    fmi2CallbackFunctions cb;
    int logging;
    int mode;
    PyObject *slave;
    PyObject *m_do_step, *m_exit_init, *m_enter_init, *m_reset, *m_get_state, *m_set_state,
        *m_check_state, *m_get_string, *m_set_string, *m_pop_log;
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

/* ---- growing strings ---------------------------------------------------------------- */
typedef struct {
    char *s;
    size_t n, cap;
} Str;

static void str_addn(Str *b, const char *t, size_t k) {
    if (b->n + k + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->n + k + 1) cap *= 2;
        char *s = realloc(b->s, cap);
        if (!s) return;
        b->s = s;
        b->cap = cap;
    }
    memcpy(b->s + b->n, t, k);
    b->n += k;
    b->s[b->n] = 0;
}

static void str_add(Str *b, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    char *t = NULL;
    int k = vasprintf(&t, fmt, ap);
    va_end(ap);
    if (k >= 0) str_addn(b, t, (size_t)k);
    free(t);
}

static const char *str_get(const Str *b) { return b->s ? b->s : ""; }

/* ---- logging ------------------------------------------------------------------------ */
#define LOG_PIECE 1000

/* the whole text, in consecutive pieces of at most LOG_PIECE bytes, cut after a line end
 * where there is one, never inside a UTF-8 character; a piece's final line end is left to
 * the logger */
static void log_text(Instance *c, fmi2Status status, const char *category, const char *text) {
    if (!c || !c->cb.logger || !text) return;
    const char *p = text;
    while (*p) {
        size_t len = strlen(p), take = len;
        if (take > LOG_PIECE) {
            take = LOG_PIECE;
            const char *nl = memrchr(p, '\n', LOG_PIECE);
            if (nl && nl > p) {
                take = (size_t)(nl - p) + 1;
            } else {
                while (take > 1 && ((unsigned char)p[take] & 0xC0) == 0x80) --take;
            }
        }
        size_t k = take;
        if (k && p[k - 1] == '\n') --k;
        char *piece = strndup(p, k);
        if (piece && *piece)
            c->cb.logger(c->cb.componentEnvironment, c->name, status, category, "%s", piece);
        free(piece);
        p += take;
    }
}

static void logf_(Instance *c, fmi2Status status, const char *category, const char *fmt, ...) {
    if (!c || !c->cb.logger) return;
    va_list ap;
    va_start(ap, fmt);
    char *t = NULL;
    int k = vasprintf(&t, fmt, ap);
    va_end(ap);
    if (k >= 0) log_text(c, status, category, t);
    free(t);
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

static int resolve(void *lib, Str *err) {
#define R(field, name)                                                                 \
    py.field = sym(lib, name);                                                         \
    if (!py.field) {                                                                   \
        str_add(err, "the CPython function %s is not in the Python library", name);  \
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

/* the value of "key=value" in a text of such lines (a new string), or NULL */
static char *text_value(const char *text, const char *key) {
    size_t k = strlen(key);
    for (const char *p = text; p && *p;) {
        const char *end = strchr(p, '\n');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        if (len > k && strncmp(p, key, k) == 0 && p[k] == '=')
            return strndup(p + k + 1, len - k - 1);
        p = end ? end + 1 : NULL;
    }
    return NULL;
}

/* a whole file (a new string), or NULL */
static char *read_file(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    Str b = {0};
    char buf[4096];
    size_t k;
    while ((k = fread(buf, 1, sizeof buf, f)) > 0) str_addn(&b, buf, k);
    fclose(f);
    return b.s ? b.s : strdup("");
}

/* "key=value" from resources/python.cfg (a new string), or NULL */
static char *config_value(const char *resources, const char *key) {
    char *path = NULL;
    if (asprintf(&path, "%s/python.cfg", resources) < 0) return NULL;
    char *text = read_file(path);
    free(path);
    char *v = text ? text_value(text, key) : NULL;
    free(text);
    return v;
}

/* the first non-blank line of resources/python.txt, trimmed (a new string), or NULL */
static char *python_txt(const char *resources) {
    char *path = NULL;
    if (asprintf(&path, "%s/python.txt", resources) < 0) return NULL;
    char *text = read_file(path);
    free(path);
    if (!text) return NULL;
    char *line = NULL, *save = NULL;
    for (char *p = strtok_r(text, "\r\n", &save); p; p = strtok_r(NULL, "\r\n", &save)) {
        while (*p == ' ' || *p == '\t') ++p;
        size_t n = strlen(p);
        while (n && (p[n - 1] == ' ' || p[n - 1] == '\t')) p[--n] = 0;
        if (*p) {
            line = strdup(p);
            break;
        }
    }
    free(text);
    return line;
}

/* path -> a python executable: itself, or a venv/prefix folder's bin/python3 or bin/python
 * (a new string), or NULL with the reason in why */
static char *python_executable(const char *path, Str *why) {
    struct stat st;
    if (stat(path, &st) != 0) {
        str_add(why, "'%s' does not exist (%s): was the environment moved or deleted?", path,
                strerror(errno));
        return NULL;
    }
    char *exe = NULL;
    if (S_ISDIR(st.st_mode)) {
        const char *names[] = {"bin/python3", "bin/python"};
        for (size_t k = 0; k < 2 && !exe; ++k) {
            char *cand = NULL;
            if (asprintf(&cand, "%s/%s", path, names[k]) < 0) return NULL;
            if (access(cand, X_OK) == 0) exe = cand;
            else free(cand);
        }
        if (!exe) {
            str_add(why, "'%s' is a folder without an executable bin/python3 or bin/python "
                    "(or they point at a Python that no longer exists)", path);
            return NULL;
        }
        return exe;
    }
    if (access(path, X_OK) != 0) {
        str_add(why, "'%s' is not an executable file", path);
        return NULL;
    }
    return strdup(path);
}

/* run PYTHON -I resources/python/fmu_bootstrap.py probe RESOURCES; its output (stdout and
 * stderr) in out; 1 when it ended with "end=1" */
static int run_probe(const char *exe, const char *resources, Str *out) {
    char *script = NULL;
    if (asprintf(&script, "%s/python/fmu_bootstrap.py", resources) < 0) return 0;
    int fd[2];
    if (pipe2(fd, O_CLOEXEC) != 0) {
        str_add(out, "cannot create a pipe: %s", strerror(errno));
        free(script);
        return 0;
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fd[1], 1);
    posix_spawn_file_actions_adddup2(&fa, fd[1], 2);
    char *argv[] = {(char *)exe, "-I", script, "probe", (char *)resources, NULL};
    pid_t pid;
    int rc = posix_spawn(&pid, exe, &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    close(fd[1]);
    if (rc != 0) {
        str_add(out, "cannot run '%s': %s", exe, strerror(rc));
        close(fd[0]);
        free(script);
        return 0;
    }
    char buf[4096];
    ssize_t k;
    while ((k = read(fd[0], buf, sizeof buf)) != 0) {
        if (k < 0) {
            if (errno == EINTR) continue;
            break;
        }
        str_addn(out, buf, (size_t)k);
    }
    close(fd[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    free(script);
    const char *t = str_get(out);
    size_t n = strlen(t);
    return n >= 6 && (strcmp(t + n - 6, "end=1\n") == 0);
}

/* Which Python the FMU uses and what it is. On success (returns 1) the text is key=value
 * lines: source, requested, executable and the probe's (version, prefix, libpython, site,
 * ...); on failure (returns 0) it is the whole message for the user. A new string. */
static char *locate(const char *resources, int use_env, int *ok) {
    Str out = {0}, why = {0};
    *ok = 0;
    const char *env = use_env ? getenv("RAILCONTACT_PYTHON") : NULL;
    char *txt = python_txt(resources), *built = config_value(resources, "executable");
    char *requires = config_value(resources, "requires");
    const char *requested = NULL, *source = NULL;
    if (env && *env) {
        requested = env;
        source = "the environment variable RAILCONTACT_PYTHON";
    } else if (txt) {
        requested = txt;
        source = "resources/python.txt (written by `railcontact fmu build --python`)";
    } else if (built && *built) {
        requested = built;
        source = "the Python the FMU was built with (resources/python.cfg)";
    }
    char *exe = NULL;
    Str probe = {0};
    if (!requested) {
        str_add(&why, "no Python is named: resources/python.cfg is missing or has no "
                "executable");
    } else if ((exe = python_executable(requested, &why)) != NULL) {
        if (!run_probe(exe, resources, &probe)) {
            str_add(&why, "asking '%s' about itself (%s -I %s/python/fmu_bootstrap.py probe) "
                    "failed:\n%s", exe, exe, resources, str_get(&probe));
        } else {
            char *problem = text_value(str_get(&probe), "problem");
            if (problem && *problem) str_add(&why, "%s", problem);
            free(problem);
        }
    }
    if (why.n == 0) {
        *ok = 1;
        str_add(&out, "source=%s\nrequested=%s\nexecutable=%s\n%s", source, requested, exe,
                str_get(&probe));
    } else {
        str_add(&out, "cannot start the FMU's Python: %s\n", str_get(&why));
        if (source) str_add(&out, "That Python was chosen from %s.\n", source);
        str_add(&out,
                "The FMU looks for its Python in this order and uses the first that is set:\n"
                "  1. the environment variable RAILCONTACT_PYTHON (a python executable, or a "
                "venv/prefix folder): %s%s%s\n"
                "  2. resources/python.txt, written by `railcontact fmu build --python PATH`: "
                "%s%s%s\n"
                "  3. the Python the FMU was built with: %s%s%s\n",
                env && *env ? "'" : "", env && *env ? env : "not set", env && *env ? "'" : "",
                txt ? "'" : "", txt ? txt : "none", txt ? "'" : "", built ? "'" : "",
                built ? built : "unknown", built ? "'" : "");
        str_add(&out,
                "In a C host it starts that Python's environment only: its site-packages and "
                "the FMU's resources, no user site-packages, no PYTHONPATH.\n"
                "To fix: set RAILCONTACT_PYTHON to a Python or virtual environment that has "
                "railcontact's dependencies (%s) and restart the host, or rebuild the FMU with "
                "`railcontact fmu build --python PATH`; `railcontact fmu check FILE.fmu` "
                "prints what the FMU will use.",
                requires && *requires ? requires : "numpy, scipy, pyfftw, numba");
    }
    free(txt);
    free(built);
    free(requires);
    free(exe);
    free(probe.s);
    free(why.s);
    return out.s ? out.s : strdup("");
}

/* for `railcontact fmu check` and `railcontact fmu build --python`: what locate() finds
 * (use_env = 0: as if RAILCONTACT_PYTHON were not set), without starting Python; *ok = 1
 * when usable. Free the text with railcontact_fmu_free. */
char *railcontact_fmu_locate(const char *resources, int use_env, int *ok) {
    return locate(resources, use_env, ok);
}

void railcontact_fmu_free(char *text) { free(text); }

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

/* set an int configuration global of CPython (Py_NoUserSiteDirectory, ...); one that this
 * Python no longer has (deprecated in 3.12, to be removed in 3.15) is named in *missing,
 * which the bootstrap logs as a warning: that part of the isolation is not done */
static void set_flag(void *lib, const char *name, int value, Str *missing) {
    int *flag = sym(lib, name);
    if (flag) *flag = value;
    else str_add(missing, "%s%s", missing->s ? ", " : "", name);
}

static int start_python_once(const char *resources, Str *err);

/* the first instantiation starts Python; two host threads instantiating at once must not
 * both start it: one does, under this lock, the other waits and then finds it ready */
static pthread_mutex_t start_lock = PTHREAD_MUTEX_INITIALIZER;

static int start_python(const char *resources, Str *err) {
    pthread_mutex_lock(&start_lock);
    int ok = start_python_once(resources, err);
    pthread_mutex_unlock(&start_lock);
    return ok;
}

static int start_python_once(const char *resources, Str *err) {
    if (py_ready) return 1;
    py.IsInitialized = sym(NULL, "Py_IsInitialized");
    int ok = 0;
    char *loc = locate(resources, 1, &ok);
    if (py.IsInitialized && py.IsInitialized()) { /* a Python host: use its interpreter */
        if (!resolve(NULL, err)) {
            free(loc);
            return 0;
        }
        Str t = {0};
        str_add(&t, "mode=host\n");
        if (ok) {
            str_add(&t, "%s", loc);
        } else { /* not fatal here: the host's packages may do; the bootstrap says so */
            for (char *p = loc; *p; ++p)
                if (*p == '\n') *p = '\x1f';
            str_add(&t, "locate_error=%s\n", loc);
        }
        free(loc);
        py_located = t.s;
        py_host = 1;
        py_ready = 1;
        return 1;
    }
    if (!ok) {
        str_add(err, "%s", loc);
        free(loc);
        return 0;
    }
    char *lib = NULL, *exe = text_value(loc, "executable");
    const char *env = getenv("RAILCONTACT_FMU_LIBPYTHON");
    if (env && *env) lib = strdup(env);
    else lib = text_value(loc, "libpython");
    if (!lib || !*lib) {
        char *why = text_value(loc, "libpython_problem");
        str_add(err, "cannot start the FMU's Python %s: %s; or set RAILCONTACT_FMU_LIBPYTHON "
                "to its libpython, or RAILCONTACT_PYTHON to another Python.\n%s",
                exe, why ? why : "no shared libpython", loc);
        free(why);
        free(lib);
        free(exe);
        free(loc);
        return 0;
    }
    void *self_lib = dlopen(lib, RTLD_NOW | RTLD_GLOBAL);
    if (!self_lib) {
        str_add(err, "cannot load the Python library '%s' of %s: %s; install that Python's "
                "shared library, or set RAILCONTACT_FMU_LIBPYTHON to it.\n%s", lib, exe,
                dlerror(), loc);
        free(lib);
        free(exe);
        free(loc);
        return 0;
    }
    if (!resolve(self_lib, err)) {
        free(lib);
        free(exe);
        free(loc);
        return 0;
    }
    Str t = {0};
    str_add(&t, "mode=started\n%slibpython_loaded=%s\n", loc, lib);
    if (!py.IsInitialized()) {
        /* start it as the chosen executable would start: Python's own start-up finds the
         * venv (pyvenv.cfg) and its prefix from the program name; no PYTHONPATH,
         * PYTHONHOME or user site-packages from the host */
        void (*set_program_name)(const wchar_t *) = sym(self_lib, "Py_SetProgramName");
        static wchar_t *wexe = NULL, *whome = NULL; /* must outlive the interpreter */
        Str missing = {0};
        if (set_program_name) { /* deprecated since 3.11, still there in 3.13 and 3.14 */
            set_flag(self_lib, "Py_IgnoreEnvironmentFlag", 1, &missing);
            set_flag(self_lib, "Py_NoUserSiteDirectory", 1, &missing);
            wexe = py.DecodeLocale(exe, NULL);
            if (wexe) set_program_name(wexe);
        } else { /* a Python without it (its removal is planned for 3.15): only the home
                  * can be given; the bootstrap adds the environment's site-packages */
            str_add(&missing, "Py_SetProgramName");
            char *home = text_value(loc, "base_prefix");
            if (home && *home && py.SetPythonHome) {
                whome = py.DecodeLocale(home, NULL);
                if (whome) py.SetPythonHome(whome);
            } else if (home && *home) {
                setenv("PYTHONHOME", home, 1);
            }
            set_flag(self_lib, "Py_NoUserSiteDirectory", 1, &missing);
            free(home);
        }
        if (missing.s) {
            str_add(&t, "isolation_missing=%s\n", missing.s);
            free(missing.s);
        }
        py.InitializeEx(0);
        py.EvalSaveThread(); /* the main thread keeps its state, releases the GIL */
    }
    free(lib);
    free(exe);
    free(loc);
    py_located = t.s;
    py_ready = 1;
    return 1;
}

static const char BOOTSTRAP[] =
    "import os, sys, traceback\n"
    "error = ''\n"
    "info = ''\n"
    "warning = ''\n"
    "try:\n"
    "    _p = os.path.join(__rc_resources__, 'python', 'fmu_bootstrap.py')\n"
    "    with open(_p) as _f:\n"
    "        exec(compile(_f.read(), _p, 'exec'))\n"
    "    _m, info, warning = start(__rc_resources__, __rc_located__)\n"
    "    slave = _m.make_slave(__rc_resources__, __rc_instance__)\n"
    "except BaseException as _e:\n"
    "    if type(_e).__name__ == 'StartError':\n"
    "        error = str(_e)\n"
    "    else:\n"
    "        error = 'the railcontact slave failed to start:\\n' + traceback.format_exc()\n";

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

/* log the slave's messages since the last call (pop_log) with status s; GIL held */
static void log_pending(Instance *c, fmi2Status s) {
    PyObject *msg = py.CallObject(c->m_pop_log, NULL);
    if (msg) {
        const char *t = py.UnicodeAsUTF8(msg);
        if (t && *t) logf_(c, s, category_of(s), "%s", t);
        py.DecRef(msg);
    } else {
        py.ErrClear();
    }
}

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
    if (s != 0) log_pending(c, (s >= 0 && s <= 3) ? (fmi2Status)s : fmi2Error);
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
                            c->m_get_state, c->m_set_state, c->m_check_state,
                            c->m_get_string, c->m_set_string,
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
    Str err = {0};
    if (!start_python(resources, &err)) {
        log_text(c, fmi2Error, "logStatusError", str_get(&err));
        free(err.s);
        free(resources);
        free_instance(c);
        return NULL;
    }
    int ok = 0;
    ENTER;
    PyObject *g = py.DictNew();
    PyObject *s1 = py.UnicodeFromString(resources), *s2 = py.UnicodeFromString(c->name),
             *s3 = py.UnicodeFromString(py_located ? py_located : "");
    py.DictSetItemString(g, "__rc_resources__", s1);
    py.DictSetItemString(g, "__rc_instance__", s2);
    py.DictSetItemString(g, "__rc_located__", s3);
    py.DecRef(s1);
    py.DecRef(s2);
    py.DecRef(s3);
    PyObject *r = py.RunStringFlags(BOOTSTRAP, Py_file_input, g, g, NULL);
    if (!r) {
        py.ErrClear();
        logf_(c, fmi2Error, "logStatusError", "the FMU's Python bootstrap failed");
    } else {
        py.DecRef(r);
        PyObject *e = py.DictGetItemString(g, "error"); /* borrowed */
        const char *etext = e ? py.UnicodeAsUTF8(e) : NULL;
        PyObject *w = py.DictGetItemString(g, "warning");
        const char *wtext = w ? py.UnicodeAsUTF8(w) : NULL;
        PyObject *i = py.DictGetItemString(g, "info");
        const char *itext = i ? py.UnicodeAsUTF8(i) : NULL;
        if (py.ErrOccurred()) py.ErrClear();
        PyObject *slave = py.DictGetItemString(g, "slave");
        if (wtext && *wtext) log_text(c, fmi2Warning, "logStatusWarning", wtext);
        if (etext && *etext) {
            logf_(c, fmi2Error, "logStatusError", "%s%s", etext,
                  py_host ? "" : "\n(the FMU started this Python in the process: restart "
                  "the host after changing the environment)");
        } else if (slave) {
            /* which Python: the whole report with loggingOn, else its first line once per
             * process */
            static int told = 0;
            if (itext && *itext && c->logging) {
                log_text(c, fmi2OK, "logAll", itext);
            } else if (itext && *itext && !told) {
                const char *nl = strchr(itext, '\n');
                char *line = strndup(itext, nl ? (size_t)(nl - itext) : strlen(itext));
                log_text(c, fmi2OK, "logAll", line);
                free(line);
            }
            told = 1;
            c->slave = py.BuildValue("O", slave); /* a new reference to the borrowed one */
            c->m_do_step = method(slave, "do_step");
            c->m_exit_init = method(slave, "exit_initialization");
            c->m_enter_init = method(slave, "enter_initialization");
            c->m_reset = method(slave, "reset");
            c->m_get_state = method(slave, "get_state");
            c->m_set_state = method(slave, "set_state");
            c->m_check_state = method(slave, "check_state");
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
                     c->m_get_state && c->m_set_state && c->m_check_state &&
                     c->m_get_string &&
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
    if (s != fmi2OK) log_pending(c, s); /* why the state could not be saved */
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

/* the bytes are kept only if the slave finds them a state of this FMU (check_state:
 * format, version, lengths, JSON header, archive, GUID and model); else fmi2Error with
 * the reason logged, *state untouched */
fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte data[], size_t size,
                                   fmi2FMUstate *state) {
    Instance *c = comp;
    if (!c || !state || (!data && size) || size > (size_t)LONG_MAX) return fmi2Error;
    ENTER;
    PyObject *b = py.BytesFromStringAndSize(size ? (const char *)data : "", (long)size);
    fmi2Status s = fmi2Error;
    if (b) {
        PyObject *args = py.BuildValue("(O)", b);
        s = args ? call_status(c, c->m_check_state, args) : fmi2Error;
        if (args) py.DecRef(args);
        else py.ErrClear();
    }
    if (s == fmi2OK) {
        s = store_state(state, b);
    } else {
        if (b) py.DecRef(b);
        else py.ErrClear();
        s = fmi2Error;
    }
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
