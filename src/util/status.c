/* status.c - the one error channel (see sem/status.h). */
#include "sem/status.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Messages often quote the input ("parameter 3 'x' is not a number"); a file may hold any
 * byte there. Control bytes (newlines, escape sequences that would drive the terminal) are
 * shown as '?' so that a message stays one printable line. */
void sem_text_sanitize(char *text)
{
    for (unsigned char *p = (unsigned char *)text; *p; ++p)
        if (*p < 0x20 || *p == 0x7f) *p = '?';
}

sem_status sem_error_vset(sem_error *err, sem_status status, const char *prefix, const char *fmt,
                          va_list ap)
{
    if (err) {
        size_t n = 0;
        if (prefix && prefix[0]) {
            int k = snprintf(err->message, sizeof err->message, "%s: ", prefix);
            n = k < 0 ? 0 : (size_t)k < sizeof err->message ? (size_t)k : sizeof err->message - 1;
        }
        vsnprintf(err->message + n, sizeof err->message - n, fmt, ap);
        sem_text_sanitize(err->message);
        err->status = status;
    }
    return status;
}

sem_status sem_error_set(sem_error *err, sem_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    sem_error_vset(err, status, NULL, fmt, ap);
    va_end(ap);
    return status;
}

void sem_error_clear(sem_error *err)
{
    if (err) {
        err->status = SEM_OK;
        err->message[0] = '\0';
    }
}

const char *sem_status_name(sem_status status)
{
    switch (status) {
    case SEM_OK: return "ok";
    case SEM_ERR_IO: return "i/o error";
    case SEM_ERR_PARSE: return "parse error";
    case SEM_ERR_INVALID: return "invalid input";
    case SEM_ERR_NOMEM: return "out of memory";
    case SEM_ERR_NUMERIC: return "numerical failure";
    case SEM_ERR_UNSUPPORTED: return "unsupported";
    }
    return "unknown";
}
