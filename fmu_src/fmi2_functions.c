/* The FMI 2.0 Co-Simulation entry points (see railcontact_fmu.h): argument and mode checks
 * here, the work in the instance and its Python slave (instance.c). */
#define _GNU_SOURCE
#include <limits.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "railcontact_fmu.h"

typedef struct {
    PyObject *bytes;
} State;

/* the instance's mode, for messages */
static const char *mode_name(int mode) {
    switch (mode) {
    case INSTANTIATED: return "instantiated (before fmi2EnterInitializationMode)";
    case INITIALIZATION: return "in initialization mode";
    case STEPPING: return "in step mode";
    case TERMINATED: return "terminated (fmi2Reset starts it again)";
    default: return "failed at initialization (fmi2Reset starts it again)";
    }
}

/* log that call cannot be made in the instance's mode; fmi2Error */
static fmi2Status wrong_mode(Instance *c, const char *call, const char *expected) {
    logf_(c, fmi2Error, "logStatusError", "%s can be called %s; the instance is %s", call,
          expected, mode_name(c->mode));
    return fmi2Error;
}

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

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources_uri, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean logging) {
    (void)guid;
    (void)visible;
    return instance_new(name, type, resources_uri, cb, logging);
}

void fmi2FreeInstance(fmi2Component comp) { instance_free((Instance *)comp); }

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tol_defined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    (void)tol_defined;
    (void)tol;
    (void)stop_defined;
    (void)stop;
    Instance *c = comp;
    if (!c) return fmi2Error;
    if (c->mode != INSTANTIATED)
        return wrong_mode(c, "fmi2SetupExperiment", "only before fmi2EnterInitializationMode");
    if (!(start - start == 0.0)) { /* NaN or infinite */
        logf_(c, fmi2Error, "logStatusError",
              "fmi2SetupExperiment: startTime = %g s is not a finite number", start);
        return fmi2Error;
    }
    c->control[0] = start;
    c->control[2] = start; /* the last successful time */
    c->discards = 0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    if (c->mode != INSTANTIATED)
        return wrong_mode(c, "fmi2EnterInitializationMode", "only once after instantiation "
                          "(or fmi2Reset)");
    ENTER;
    fmi2Status s = call_status(c, c->m_enter_init, NULL);
    LEAVE;
    c->mode = INITIALIZATION;
    return s;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    if (c->mode != INITIALIZATION)
        return wrong_mode(c, "fmi2ExitInitializationMode", "only in initialization mode");
    c->control[0] = c->control[2];
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
    ENTER;
    fmi2Status s = call_status(c, c->m_terminate, NULL); /* the worker processes end */
    LEAVE;
    c->mode = TERMINATED;
    return s;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    ENTER;
    fmi2Status s = call_status(c, c->m_reset, NULL);
    LEAVE;
    c->mode = INSTANTIATED;
    c->control[2] = 0.0;
    c->discards = 0;
    return s;
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
            logf_(c, fmi2Error, "logStatusError", "no String variable with value reference %u",
                  vr[k]);
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
    if (n) logf_(c, fmi2Error, "logStatusError", "this FMU has no Boolean variables");
    return n ? fmi2Error : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         const fmi2String value[]) {
    Instance *c = comp;
    if (!c) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < n; ++k) {
        int why = refusal(c, vr[k], c->string_flags, c->n_string);
        if (why < 0 && !value[k]) why = REFUSED_NULL;
        if (why >= 0) {
            log_refusal(c, "String", vr[k], why);
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
    if (n) c->discards = 0; /* (a parameter set: the run of discards ends) */
    return status;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    Instance *c = comp;
    if (!c) return fmi2Error;
    if (c->mode != STEPPING)
        return wrong_mode(c, "fmi2DoStep", "only in step mode (after "
                          "fmi2ExitInitializationMode)");
    c->control[0] = t;
    c->control[1] = h;
    ENTER;
    fmi2Status s = call_status(c, c->m_do_step, NULL);
    LEAVE;
    if (s <= fmi2Warning) c->control[2] = t + h;
    if (s != fmi2Discard) {
        c->discards = 0;
    } else if (c->discards > 0 && t == c->discarded_at && h == c->discarded_size) {
        ++c->discards; /* the same step again, with the same inputs */
    } else {
        c->discards = 1;
        c->discarded_at = t;
        c->discarded_size = h;
    }
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
    c->discards = 0;
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
    *value = c->control[2]; /* (a restored state's: the slave restores control) */
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s,
                                fmi2Integer *value) {
    (void)comp; (void)s; (void)value;
    return fmi2Discard;
}

/* fmi2Terminated: true once the same step (communication point and step size) has been
 * discarded twice with no input or parameter changed between the two calls: the slave is
 * deterministic, so a master that retries it as it is (fmpy's simulate_fmu after a
 * discard, with constant or tabulated inputs) would retry for ever; a master that changes
 * an input, the step size or the state goes on */
fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s,
                                fmi2Boolean *value) {
    Instance *c = comp;
    if (!c || s != fmi2Terminated || !value) return fmi2Discard;
    *value = c->discards >= 2 ? fmi2True : fmi2False;
    if (*value)
        logf_(c, fmi2Warning, "logStatusWarning",
              "the step at t = %g s (size %g s) was discarded %d times with the same inputs: "
              "the FMU asks to terminate (change an input to go on)",
              c->discarded_at, c->discarded_size, c->discards);
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s,
                               fmi2String *value) {
    (void)comp; (void)s; (void)value;
    return fmi2Discard;
}
