/* net_size.c - the box and size of a surface's control net (see net_size.h). */
#include "geometry/net_size.h"

#include <math.h>

void sem_surface_net_box(const sem_surface *s, double lo[3], double hi[3])
{
    for (int d = 0; d < 3; ++d) {
        lo[d] = INFINITY;
        hi[d] = -INFINITY;
    }
    size_t n = (size_t)s->n_u * (size_t)s->n_v;
    for (size_t i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d) {
            lo[d] = fmin(lo[d], s->ctrl[3 * i + d]);
            hi[d] = fmax(hi[d], s->ctrl[3 * i + d]);
        }
}

double sem_surface_net_size(const sem_surface *s)
{
    double lo[3], hi[3];
    sem_surface_net_box(s, lo, hi);
    double size = sqrt((lo[0] - hi[0]) * (lo[0] - hi[0]) + (lo[1] - hi[1]) * (lo[1] - hi[1]) +
                       (lo[2] - hi[2]) * (lo[2] - hi[2]));
    return size > 0 && isfinite(size) ? size : 1.0;
}
