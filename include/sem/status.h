/*
 * sem/status.h - one error channel for every call (as CHOLMOD's common status).
 *
 * Functions that can fail return a sem_status and, when given a non-NULL sem_error,
 * fill its message with one line: "FILE:LINE: what is wrong" for file errors,
 * "what is wrong" otherwise.
 */
#ifndef SEM_STATUS_H
#define SEM_STATUS_H

#include <stdarg.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sem_status {
    SEM_OK = 0,
    SEM_ERR_IO,       /* cannot open, read or write a file */
    SEM_ERR_PARSE,    /* malformed file */
    SEM_ERR_INVALID,  /* bad argument or inconsistent data */
    SEM_ERR_NOMEM,    /* out of memory */
    SEM_ERR_NUMERIC,  /* NaN, divergence, singular system */
    SEM_ERR_UNSUPPORTED
} sem_status;

typedef struct sem_error {
    sem_status status;
    char message[1024];
} sem_error;

/* Sets err (if non-NULL) and returns status. printf-style. */
sem_status sem_error_set(sem_error *err, sem_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The va_list form, for functions that add their own place to a message: sets err (if
 * non-NULL) to "PREFIX: message" ("message" when prefix is NULL or empty) and returns status.
 * The readers' "FILE:LINE: what is wrong" and the scene's "NAME: KEY: what is wrong" go
 * through it. */
sem_status sem_error_vset(sem_error *err, sem_status status, const char *prefix, const char *fmt,
                          va_list ap)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 0)))
#endif
    ;
void sem_error_clear(sem_error *err);
/* Replaces control bytes (below 0x20, and 0x7f) by '?' in place; every message and model
 * warning goes through it, so text quoted from a file cannot break a line or a terminal. */
void sem_text_sanitize(char *text);
const char *sem_status_name(sem_status status);

#ifdef __cplusplus
}
#endif
#endif
