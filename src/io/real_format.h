/*
 * io/real_format.h - doubles as text that reads back bit for bit.
 *
 * Writers must round-trip exactly (a model written and read again has identical control
 * points, weights and knots). "%.17g" always does, but prints 0.1 as 0.10000000000000001;
 * we take the shortest of %.15g, %.16g, %.17g that strtod maps back to the same double,
 * which is just as exact and keeps files readable.
 */
#ifndef SEM_IO_REAL_FORMAT_H
#define SEM_IO_REAL_FORMAT_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Shortest exact "%g" text of x (finite). buf needs 32 chars. Returns the length. */
static inline int sem_format_real(double x, char *buf)
{
    int n = 0;
    for (int digits = 15; digits <= 17; ++digits) {
        n = snprintf(buf, 32, "%.*g", digits, x);
        if (strtod(buf, NULL) == x) break;
    }
    return n;
}

/* The same as an IGES real constant: always a decimal point, upper-case exponent
 * ("1." "2.5E-07" "-0."), so no reader can take it for an integer. */
static inline int sem_format_iges_real(double x, char *buf)
{
    char tmp[32];
    int n = sem_format_real(x, tmp);
    int has_point = strchr(tmp, '.') != NULL;
    int k = 0;
    for (int i = 0; i < n; ++i) {
        if (tmp[i] == 'e' || tmp[i] == 'E') {
            if (!has_point) buf[k++] = '.';
            has_point = 1;
            buf[k++] = 'E';
        } else {
            buf[k++] = tmp[i];
        }
    }
    if (!has_point) buf[k++] = '.';
    buf[k] = '\0';
    return k;
}

#endif
