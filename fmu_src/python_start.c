/* The FMU's Python interpreter: started once per process from the located Python's
 * libpython (or the host's own, when the process runs Python already), never finalised;
 * one persistent thread state per host thread (see railcontact_fmu.h). */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

#include "railcontact_fmu.h"

int py_ready = 0;
int py_host = 0;
char *py_located = NULL;

static __thread int thread_primed = 0;

/* a persistent thread state for a host thread that has none (C hosts) */
void prime_thread(void) {
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

int start_python(const char *resources, Str *err) {
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
