/* Several host threads instantiate the FMU at the same moment, the first instantiation in
 * the process (which starts Python), then each steps its own instance.
 *
 *   threads BINARY RESOURCE_URI GUID N_THREADS N_STEPS
 *
 * Exit code 0 and "ok: N threads" on success.
 */
#include <dlfcn.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

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

static void *lib;
static char **args;
static int steps;
static pthread_barrier_t barrier;

static void *run(void *arg) {
    long k = (long)arg;
    fmi2InstantiateTYPE *inst = (fmi2InstantiateTYPE *)dlsym(lib, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = (fmi2SetupExperimentTYPE *)dlsym(lib, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter =
        (fmi2EnterInitializationModeTYPE *)dlsym(lib, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *leave =
        (fmi2ExitInitializationModeTYPE *)dlsym(lib, "fmi2ExitInitializationMode");
    fmi2DoStepTYPE *step = (fmi2DoStepTYPE *)dlsym(lib, "fmi2DoStep");
    fmi2FreeInstanceTYPE *release = (fmi2FreeInstanceTYPE *)dlsym(lib, "fmi2FreeInstance");
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    char name[32];
    snprintf(name, sizeof name, "thread%ld", k);
    pthread_barrier_wait(&barrier); /* all at once */
    fmi2Component c = inst(name, fmi2CoSimulation, args[3], args[2], &cb, fmi2False,
                           fmi2False);
    if (!c) return (void *)1;
    if (setup(c, fmi2False, 0, 0, fmi2False, 0) > fmi2Warning ||
        enter(c) > fmi2Warning || leave(c) > fmi2Warning)
        return (void *)2;
    for (int i = 0; i < steps; ++i)
        if (step(c, i * 1e-3, 1e-3, fmi2True) > fmi2Warning) return (void *)3;
    release(c);
    return NULL;
}

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: threads BINARY RESOURCE_URI GUID N_THREADS N_STEPS\n");
        return 2;
    }
    args = argv;
    int n = atoi(argv[4]);
    steps = atoi(argv[5]);
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 3;
    }
    pthread_t th[64];
    pthread_barrier_init(&barrier, NULL, (unsigned)n);
    for (long k = 0; k < n; ++k) pthread_create(&th[k], NULL, run, (void *)k);
    int failed = 0;
    for (int k = 0; k < n; ++k) {
        void *r;
        pthread_join(th[k], &r);
        if (r) {
            fprintf(stderr, "thread %d failed (%ld)\n", k, (long)r);
            failed = 1;
        }
    }
    if (failed) return 4;
    printf("ok: %d threads\n", n);
    return 0;
}
