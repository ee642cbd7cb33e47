/*
 * ray_segments.c - where one ray is inside the model: the segments between its hits, each
 * inside or not, with the part whose material it takes (sem_ray_inside_segments), and the
 * growing point list the quadratures fill (sem_ray_points_push). Used by every volume
 * quadrature (quadrature.c, quadrature_cells.c, quadrature_subrays.c; declared in steps.h).
 *
 * Inside intervals - robustness choices:
 * 1. Enter/leave counting (CSG union, Fig. 17). With the orientation-corrected normals of
 *    raycast_hits.c (fixed by part_orientation.c), a hit with dir . n < 0 enters a solid,
 *    otherwise it leaves. The ray is inside while the count (depth) is >= 1, so overlapping
 *    parts (the mug's embedded handle, the rocket's fins through its body) are counted once.
 * 2. The count is trusted only when it is consistent: it never goes negative and returns
 *    to 0 at the end of the ray. Open surfaces (the rocket has no bottom, the starship is
 *    12 open pieces), gaps (the chicken) or a misoriented part break that. Such a ray falls
 *    back to the generalized winding number (Jacobson et al. 2013) at the midpoint of each
 *    segment between consecutive hits, and of the two end segments between the bounding
 *    box and the first/last hit (a ray along the starship enters its open back end
 *    without any hit): inside when > 1/2. The winding number degrades
 *    gracefully across holes and gaps (it is the harmonic extension of the inside
 *    indicator), which parity or counting cannot do; it costs O(triangles) per segment, so
 *    it is used only on the rays that need it.
 * 3. A consistent count can still be wrong (two open sheets facing each other, as the
 *    castle's walls, count as one solid): an inside segment whose midpoint winding number
 *    is below 1/4 (clearly outside) is dropped. The inside of an open-ended solid (the
 *    rocket's tube, a lamp shade) keeps winding numbers near or above 1/2, so such solids
 *    keep their counted volume, which is what the modeller meant.
 * 4. Hits on shared edges, duplicate reports and grazing touches are already merged by
 *    sem_raycast_all into single crossings (see raycast_hits.c).
 *
 * Material (quad_part): a stack of entered parts along the ray: push the part on entering;
 * on leaving a part remove its most recent occurrence, or, when the part is not on the
 * stack (a multi-patch solid is entered through one patch and left through another), pop
 * the top. A point takes the part on top of the stack, i.e. the innermost solid (the tire's
 * steel hub inside its rubber tread). Rays in winding-number mode take the part of the
 * nearest hit before the point.
 */
#include <stdlib.h>
#include <string.h>

#include "steps.h"

#define WINDING_INSIDE 0.5 /* fallback: inside when the winding number is above */

#define WINDING_VETO 0.25  /* consistent counting: outside when the winding number is below */

int sem_ray_points_push(sem_ray_points *r, int *cap, const double X[3], double volume, int part)
{
    if (r->n == *cap) {
        int c = *cap ? 2 * *cap : 16;
        double *nx = realloc(r->X, (size_t)c * 3 * sizeof *nx);
        if (!nx) return 0;
        r->X = nx;
        double *nv = realloc(r->volume, (size_t)c * sizeof *nv);
        if (!nv) return 0;
        r->volume = nv;
        int *np = realloc(r->part, (size_t)c * sizeof *np);
        if (!np) return 0;
        r->part = np;
        *cap = c;
    }
    memcpy(r->X + 3 * (size_t)r->n, X, 3 * sizeof *X);
    r->volume[r->n] = volume;
    r->part[r->n] = part;
    r->n++;
    return 1;
}

/* The segments of one ray between consecutive hits, each inside or not, with the part whose
 * material it takes (innermost entered component, see the file comment). The ray crosses the
 * bounding box for t in [t_begin, t_end]. *seg is allocated (n + 1 segments: [t_begin,
 * hit 0], [hit 0, hit 1], ..., [hit n-1, t_end]); *n_seg 0 when the ray hits nothing. Returns 0
 * on out of memory. */
int sem_ray_inside_segments(const sem_raycast_scene *scene, const double origin[3],
                        const double dir[3], double t_begin, double t_end, double length,
                             sem_ray_segment **seg_out, int *n_seg_out, sem_ray_hit **hits_out,
                             int *n_hits_out)
{
    *seg_out = NULL;
    *n_seg_out = 0;
    if (hits_out) {
        *hits_out = NULL;
        *n_hits_out = 0;
    }
    sem_ray_hit local[64];
    sem_ray_hit *hits = local;
    int n = sem_raycast_all(scene, origin, dir, 0.0, length, hits, 64);
    if (n > 64) {
        hits = malloc((size_t)n * sizeof *hits);
        if (!hits) return 0;
        int m = sem_raycast_all(scene, origin, dir, 0.0, length, hits, n);
        if (m < n) n = m;
    }
    if (n < 1) {
        if (hits != local) free(hits);
        return 1;
    }

    int ok = 1;
    /* the stack holds (component, part entered through) */
    int *stack = malloc(2 * (size_t)n * sizeof *stack);
    sem_ray_segment *seg = malloc((size_t)(n + 1) * sizeof *seg);
    if (!stack || !seg) {
        ok = 0;
        free(seg);
        seg = NULL;
        goto done;
    }
    int n_seg = n + 1;
    seg[0].t0 = t_begin < hits[0].t ? t_begin : hits[0].t;
    seg[0].t1 = hits[0].t;
    seg[0].inside = 0;
    seg[0].part = hits[0].part;
    seg[n].t0 = hits[n - 1].t;
    seg[n].t1 = t_end > hits[n - 1].t ? t_end : hits[n - 1].t;
    seg[n].inside = 0;
    seg[n].part = hits[n - 1].part;

    /* 1. enter/leave counting with the component stack */
    int depth = 0, consistent = n >= 2;
    for (int i = 0; i < n && consistent; i++) {
        double dn = dir[0] * hits[i].normal[0] + dir[1] * hits[i].normal[1] +
                    dir[2] * hits[i].normal[2];
        int comp = sem_raycast_part_component(scene, hits[i].part);
        if (dn < 0) {
            stack[2 * depth] = comp;
            stack[2 * depth + 1] = hits[i].part;
            depth++;
        } else {
            if (depth == 0) {
                consistent = 0;
                break;
            }
            int k = depth - 1;
            while (k >= 0 && stack[2 * k] != comp) k--;
            if (k < 0) k = depth - 1; /* left a component it did not enter: pop the top */
            memmove(stack + 2 * k, stack + 2 * k + 2, 2 * (size_t)(depth - 1 - k) * sizeof *stack);
            depth--;
        }
        if (i + 1 < n) {
            seg[i + 1].t0 = hits[i].t;
            seg[i + 1].t1 = hits[i + 1].t;
            seg[i + 1].inside = depth > 0;
            seg[i + 1].part = depth > 0 ? stack[2 * depth - 1] : hits[i].part;
        }
    }
    if (depth != 0) consistent = 0;

    /* a consistent count can still be wrong: two open sheets whose normals happen to face
     * each other (the castle's walls) look like one solid. Veto an inside segment whose
     * midpoint is clearly outside by the winding number (< 1/4; the inside of an open
     * tube or shade stays >= ~1/2, so open-ended solids keep their counted volume). */
    if (consistent) {
        for (int i = 1; i < n; i++) {
            if (!seg[i].inside || !(seg[i].t1 > seg[i].t0)) continue;
            double tm = 0.5 * (seg[i].t0 + seg[i].t1), X[3];
            for (int d = 0; d < 3; d++) X[d] = origin[d] + tm * dir[d];
            if (!sem_raycast_winding_above(scene, X, WINDING_VETO)) seg[i].inside = 0;
        }
    }

    /* 2. fallback: winding number at each segment's midpoint, including the two end
     * segments (a ray may enter an open tube through its open end without a hit) */
    if (!consistent) {
        for (int i = 0; i < n_seg; i++) {
            if (i > 0 && i < n) {
                seg[i].t0 = hits[i - 1].t;
                seg[i].t1 = hits[i].t;
                seg[i].part = hits[i - 1].part;
            }
            seg[i].inside = 0;
            if (!(seg[i].t1 > seg[i].t0)) continue;
            double tm = 0.5 * (seg[i].t0 + seg[i].t1), X[3];
            for (int d = 0; d < 3; d++) X[d] = origin[d] + tm * dir[d];
            seg[i].inside = sem_raycast_winding_above(scene, X, WINDING_INSIDE);
        }
    }
    if (hits_out) {
        sem_ray_hit *copy = malloc((size_t)n * sizeof *copy);
        if (!copy) {
            ok = 0;
            free(seg);
            goto done;
        }
        memcpy(copy, hits, (size_t)n * sizeof *copy);
        *hits_out = copy;
        *n_hits_out = n;
    }
    *seg_out = seg;
    *n_seg_out = n_seg;
done:
    free(stack);
    if (hits != local) free(hits);
    return ok;
}
