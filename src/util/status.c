/* status.c - the one error channel (see sem/status.h). */
#include "sem/status.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

sem_status sem_error_set(sem_error *err, sem_status status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
        err->status = status;
    }
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
