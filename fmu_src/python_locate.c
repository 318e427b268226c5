/* Which Python the FMU uses: RAILCONTACT_PYTHON, resources/python.txt or the building
 * Python, asked about itself by the probe (`PYTHON -I fmu_bootstrap.py probe`); see
 * railcontact_fmu.h. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "railcontact_fmu.h"

extern char **environ;

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
char *locate(const char *resources, int use_env, int *ok) {
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
