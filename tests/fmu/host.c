/* A bare FMI 2.0 co-simulation host: dlopen the FMU binary, run it, unload it.
 *
 *   host BINARY RESOURCE_URI GUID N_STEPS CYCLES [bench]
 *
 * Each cycle loads the library, instantiates, sets parameters and inputs (lateral
 * displacement sweeping +-6 mm), runs N_STEPS steps of 1 ms, checks that every output
 * read is finite, frees the instance and unloads the library. Exit code 0 on success.
 * With "bench" it prints per-call timings (set+get in C; a Python round trip; a step).
 * Every logger call is printed to stderr as "[instance|status|category] message"; the
 * environment variable LOGGING=1 instantiates with loggingOn (the FMU then says which
 * Python it runs in).
 */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    va_list ap;
    va_start(ap, message);
    fprintf(stderr, "[%s|%d|%s] ", name, status, category);
    vfprintf(stderr, message, ap);
    fprintf(stderr, "\n");
    va_end(ap);
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

#define LOAD(name)                                                                     \
    name##TYPE *name = (name##TYPE *)dlsym(lib, #name);                                \
    if (!name) {                                                                       \
        fprintf(stderr, "missing %s\n", #name);                                        \
        return 3;                                                                      \
    }

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: host BINARY RESOURCE_URI GUID N_STEPS CYCLES [bench]\n");
        return 2;
    }
    int steps = atoi(argv[4]), cycles = atoi(argv[5]);
    int bench = argc > 6 && strcmp(argv[6], "bench") == 0;
    /* value references: read from the command line environment-free, fixed by the table */
    unsigned vr_lat = (unsigned)atoi(getenv("VR_LAT") ? getenv("VR_LAT") : "-1");
    unsigned vr_out = (unsigned)atoi(getenv("VR_OUT") ? getenv("VR_OUT") : "-1");
    for (int cycle = 0; cycle < cycles; ++cycle) {
        void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
        if (!lib) {
            fprintf(stderr, "dlopen: %s\n", dlerror());
            return 3;
        }
        LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationMode) LOAD(fmi2DoStep) LOAD(fmi2GetReal) LOAD(fmi2SetReal)
        LOAD(fmi2GetInteger) LOAD(fmi2GetString) LOAD(fmi2Terminate) LOAD(fmi2FreeInstance)
        fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
        const char *logging = getenv("LOGGING");
        fmi2Component c = fmi2Instantiate("host", fmi2CoSimulation, argv[3], argv[2], &cb,
                                          fmi2False, logging && *logging == '1');
        if (!c) {
            fprintf(stderr, "instantiate failed\n");
            return 4;
        }
        if (fmi2SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0) > fmi2Warning ||
            fmi2EnterInitializationMode(c) > fmi2Warning ||
            fmi2ExitInitializationMode(c) > fmi2Warning) {
            fprintf(stderr, "initialization failed\n");
            return 5;
        }
        double t = 0, h = 1e-3, out[64];
        unsigned all[64];
        for (unsigned k = 0; k < 64; ++k) all[k] = vr_out + k;
        double t_step = 0;
        for (int i = 0; i < steps; ++i) {
            double y = 6e-3 * sin(2 * M_PI * i / (double)steps);
            double t0 = now();
            if (fmi2SetReal(c, &vr_lat, 1, &y) != fmi2OK) return 6;
            fmi2Status s = fmi2DoStep(c, t, h, fmi2True);
            if (s > fmi2Discard) {
                fprintf(stderr, "doStep failed at step %d\n", i);
                return 7;
            }
            if (fmi2GetReal(c, all, 40, out) != fmi2OK) return 8;
            t_step += now() - t0;
            for (int k = 0; k < 40; ++k)
                if (!isfinite(out[k])) {
                    fprintf(stderr, "non-finite output %d at step %d\n", k, i);
                    return 9;
                }
            t += h;
        }
        if (bench) {
            int n = 100000;
            double y = 1e-3, t0 = now();
            for (int i = 0; i < n; ++i) {
                fmi2SetReal(c, &vr_lat, 1, &y);
                fmi2GetReal(c, all, 40, out);
            }
            double t_c = (now() - t0) / n;
            unsigned vr_s = 0;
            fmi2String str;
            n = 20000;
            t0 = now();
            for (int i = 0; i < n; ++i) fmi2GetString(c, &vr_s, 1, &str);
            double t_py = (now() - t0) / n;
            printf("set+get (C only) %.3f us; Python round trip %.3f us; "
                   "set+doStep+get %.3f ms\n",
                   1e6 * t_c, 1e6 * t_py, 1e3 * t_step / steps);
        }
        fmi2Terminate(c);
        fmi2FreeInstance(c);
        dlclose(lib);
    }
    printf("ok: %d cycles of %d steps\n", cycles, steps);
    return 0;
}
