/* Messages to the FMI logger (see railcontact_fmu.h). */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "railcontact_fmu.h"

/* the whole text, in consecutive pieces of at most LOG_PIECE bytes, cut after a line end
 * where there is one, never inside a UTF-8 character; a piece's final line end is left to
 * the logger */
void log_text(Instance *c, fmi2Status status, const char *category, const char *text) {
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

void logf_(Instance *c, fmi2Status status, const char *category, const char *fmt, ...) {
    if (!c || !c->cb.logger) return;
    va_list ap;
    va_start(ap, fmt);
    char *t = NULL;
    int k = vasprintf(&t, fmt, ap);
    va_end(ap);
    if (k >= 0) log_text(c, status, category, t);
    free(t);
}

const char *category_of(fmi2Status s) {
    switch (s) {
    case fmi2Warning: return "logStatusWarning";
    case fmi2Discard: return "logStatusDiscard";
    case fmi2Error: return "logStatusError";
    case fmi2Fatal: return "logStatusFatal";
    default: return "logAll";
    }
}
