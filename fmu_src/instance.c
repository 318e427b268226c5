/* An instance of the FMU: its Python slave (started by the bootstrap, its methods bound
 * once, its numpy buffers read and written in place), the value access and the calls that
 * return an FMI status (see railcontact_fmu.h). */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "railcontact_fmu.h"

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
void log_pending(Instance *c, fmi2Status s) {
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
fmi2Status call_status(Instance *c, PyObject *m, PyObject *args) {
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

void instance_free(Instance *c) {
    if (!c) return;
    if (c->slave && py_ready) {
        ENTER;
        if (c->m_close) { /* the slave's threads and worker processes end with it */
            PyObject *r = py.CallObject(c->m_close, NULL);
            if (r) py.DecRef(r);
            else py.ErrClear();
        }
        PyObject *objs[] = {c->m_do_step, c->m_exit_init, c->m_enter_init, c->m_reset,
                            c->m_get_state, c->m_set_state, c->m_check_state,
                            c->m_get_string, c->m_set_string,
                            c->m_pop_log, c->m_terminate, c->m_close, c->m_refusal,
                            c->slave};
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

Instance *instance_new(fmi2String name, fmi2Type type, fmi2String resources_uri,
                       const fmi2CallbackFunctions *cb, fmi2Boolean logging) {
    if (!cb || !cb->logger) return NULL;
    Instance *c = calloc(1, sizeof(Instance));
    c->name = strdup(name ? name : "railcontact");
    c->cb = *cb;
    c->logging = logging;
    if (type != fmi2CoSimulation) {
        logf_(c, fmi2Error, "logStatusError", "railcontact is a Co-Simulation FMU only");
        instance_free(c);
        return NULL;
    }
    char *resources = uri_to_path(resources_uri);
    if (!resources) {
        logf_(c, fmi2Error, "logStatusError", "no resource location given");
        instance_free(c);
        return NULL;
    }
    Str err = {0};
    if (!start_python(resources, &err)) {
        log_text(c, fmi2Error, "logStatusError", str_get(&err));
        free(err.s);
        free(resources);
        instance_free(c);
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
            c->m_terminate = method(slave, "terminate");
            c->m_close = method(slave, "close");
            c->m_refusal = method(slave, "refusal");
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
                     c->m_set_string && c->m_pop_log && c->m_terminate && c->m_close &&
                     c->m_refusal && !py.ErrOccurred();
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
        instance_free(c);
        return NULL;
    }
    c->mode = INSTANTIATED;
    return c;
}

int refusal(const Instance *c, fmi2ValueReference vr, const unsigned char *flags,
            size_t count) {
    if (vr >= count) return REFUSED_UNKNOWN;
    if (flags[vr] == INPUT)
        return c->mode != TERMINATED && c->mode != FAILED ? -1 : REFUSED_ENDED;
    if (flags[vr] == PARAMETER)
        return c->mode == INSTANTIATED || c->mode == INITIALIZATION ? -1 : REFUSED_PARAMETER;
    return REFUSED_OUTPUT;
}

void log_refusal(Instance *c, const char *type, fmi2ValueReference vr, int reason) {
    ENTER;
    PyObject *args = py.BuildValue("(sIi)", type, vr, reason);
    PyObject *r = args ? py.CallObject(c->m_refusal, args) : NULL;
    const char *t = r ? py.UnicodeAsUTF8(r) : NULL;
    if (t) {
        logf_(c, fmi2Error, "logStatusError", "%s", t);
    } else { /* (the slave failed to word it) */
        py.ErrClear();
        logf_(c, fmi2Error, "logStatusError", "%s variable %u cannot be set now", type, vr);
    }
    if (r) py.DecRef(r);
    if (args) py.DecRef(args);
    LEAVE;
}

/* Real and Integer values live in the slave's numpy buffers (double, int32): get and set
 * copy them element by element, checking the value reference (and, to set, the causality). */
fmi2Status get_values(Instance *c, const char *type, const fmi2ValueReference vr[], size_t n,
                      const void *buffer, size_t count, size_t size, void *value) {
    for (size_t k = 0; k < n; ++k) {
        if (vr[k] >= count) {
            logf_(c, fmi2Error, "logStatusError", "no %s variable with value reference %u",
                  type, vr[k]);
            return fmi2Error;
        }
        memcpy((char *)value + k * size, (const char *)buffer + vr[k] * size, size);
    }
    return fmi2OK;
}

fmi2Status set_values(Instance *c, const char *type, const fmi2ValueReference vr[], size_t n,
                      void *buffer, const unsigned char *flags, size_t count, size_t size,
                      const void *value) {
    for (size_t k = 0; k < n; ++k) {
        int why = refusal(c, vr[k], flags, count);
        if (why >= 0) {
            log_refusal(c, type, vr[k], why);
            return fmi2Error;
        }
        char *dst = (char *)buffer + vr[k] * size;
        const char *src = (const char *)value + k * size;
        if (memcmp(dst, src, size) != 0) c->discards = 0; /* a changed input: a new step */
        memcpy(dst, src, size);
    }
    return fmi2OK;
}
