/* Growing strings, "key=value" text and whole files (see railcontact_fmu.h). */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "railcontact_fmu.h"

void str_addn(Str *b, const char *t, size_t k) {
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

void str_add(Str *b, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    char *t = NULL;
    int k = vasprintf(&t, fmt, ap);
    va_end(ap);
    if (k >= 0) str_addn(b, t, (size_t)k);
    free(t);
}

const char *str_get(const Str *b) { return b->s ? b->s : ""; }

char *text_value(const char *text, const char *key) {
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

char *read_file(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    Str b = {0};
    char buf[4096];
    size_t k;
    while ((k = fread(buf, 1, sizeof buf, f)) > 0) str_addn(&b, buf, k);
    fclose(f);
    return b.s ? b.s : strdup("");
}
