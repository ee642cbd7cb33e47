/*
 * geometry/vector3.h - the three small vector operations that the geometry, preprocessing and
 * contact files share (internal): dot and cross products and a difference of 3-vectors.
 * Inline, and written once so that every caller rounds the same way.
 */
#ifndef SEM_GEOMETRY_VECTOR3_H
#define SEM_GEOMETRY_VECTOR3_H

static inline double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* r = a - b */
static inline void sub3(const double *a, const double *b, double *r)
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}

/* r = a x b (r must not alias a or b) */
static inline void cross3(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

#endif
