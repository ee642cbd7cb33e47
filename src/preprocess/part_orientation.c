/*
 * part_orientation.c - the orientation fix of the scene's parts (part_sign, raycast.h): which
 * side of each part is out of the solid, and which parts touch (components). Called by
 * raycast_build.c while the scene is built.
 *
 * Design
 * - Orientation fix (part_sign). CAD files have inward faces. For each part we pick up to
 *   9 sample triangles (the largest triangle of each of 9 equal slices of the part's
 *   triangle list, so the samples spread over the part) and from each centre cast 5 pairs
 *   of opposite rays: along +-normal and 4 directions 25 degrees off it. A ray that leaves
 *   a closed solid crosses its boundary an even number of times before escaping, a ray
 *   into it an odd number. Crossings are counted first on the part's own *component*
 *   (parts whose boundaries touch, within 5e-3 of the model size: a box's 6 patches), so
 *   a solid nested in or overlapping another one (the tire's hub, the mug's embedded
 *   handle, the rocket's fins) is judged on its own surface. A pair is decisive when one
 *   ray is even and the other odd; when the component gives no decision (an open sheet,
 *   a gap) the counts on the whole scene are tried. Each decisive pair votes +-area
 *   (+ when the +normal ray is even); the sign of the sum decides, ties keep +1. Several
 *   jittered pairs from several places outvote accidents: a ray escaping through a gap or
 *   an open end (the rocket has no bottom) or grazing an edge.
 * - Orientation votes stop as soon as the votes not cast yet cannot change the sign.
 */
#include "raycast_scene.h"
#include "util/union_find.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SIGN_SAMPLES 9
#define SIGN_RAYS 5

/* Crossings along a ray: all of them and those of parts in component `self`. Returns 0
 * when out of memory. */
static int count_crossings(const sem_raycast_scene *s, const int *component, int self,
                           const double *origin, const double *dir, double t_near,
                           int *n_self, int *n_all)
{
    sem_ray_hit local[128];
    sem_ray_hit *hits = local;
    int n = sem_raycast_all_hits(s, origin, dir, t_near, INFINITY, hits, 128, 0);
    if (n > 128) {
        hits = malloc((size_t)n * sizeof *hits);
        if (!hits) return 0;
        int m = sem_raycast_all_hits(s, origin, dir, t_near, INFINITY, hits, n, 0);
        if (m < n) n = m;
    }
    if (n < 0) return 0;
    int k = 0;
    for (int i = 0; i < n; i++)
        if (component[hits[i].part] == self) k++;
    *n_self = k;
    *n_all = n;
    if (hits != local) free(hits);
    return 1;
}

/* Estimates part_sign[part] by ray parity votes (see the file comment). */
int sem_raycast_estimate_part_sign(const sem_raycast_scene *s, const int *component, int part)
{
    int t0 = s->part_tri_offset[part], t1 = s->part_tri_offset[part + 1];
    int n = t1 - t0;
    if (n == 0) return 1;
    int samples = n < SIGN_SAMPLES ? n : SIGN_SAMPLES;
    double vote = 0.0;
    double offset = 1e-6 * s->scale;
    int best_of[SIGN_SAMPLES];
    double remaining = 0.0; /* the most the votes not cast yet can add up to */
    for (int k = 0; k < samples; k++) {
        /* largest triangle of slice k */
        int a = t0 + (int)((long long)n * k / samples);
        int b = t0 + (int)((long long)n * (k + 1) / samples);
        int best = a;
        for (int t = a; t < b; t++)
            if (s->tri_area[t] > s->tri_area[best]) best = t;
        best_of[k] = best;
        remaining += SIGN_RAYS * s->tri_area[best];
    }
    for (int k = 0; k < samples; k++) {
        int best = best_of[k];
        const double *v = s->tri + 9 * (size_t)best;
        const double *nrm = s->tri_normal + 3 * (size_t)best;
        double centre[3];
        for (int d = 0; d < 3; d++) centre[d] = (v[d] + v[3 + d] + v[6 + d]) / 3.0;
        /* tangent frame */
        double e1[3], e2[3];
        sub3(v + 3, v, e1);
        double l1 = sqrt(dot3(e1, e1));
        for (int d = 0; d < 3; d++) e1[d] /= l1;
        cross3(nrm, e1, e2);
        for (int r = 0; r < SIGN_RAYS; r++) {
            /* the sign is decided once the votes left cannot change it (the same answer
             * as casting them all, for a fraction of the rays on a clean part) */
            if (vote >= remaining || vote < -remaining) return vote >= 0 ? 1 : -1;
            remaining -= s->tri_area[best];
            double dir[3], back[3];
            if (r == 0) {
                memcpy(dir, nrm, sizeof dir);
            } else {
                /* 25 degrees off the normal, rotated by 90 degrees plus an odd offset so
                 * the rays avoid the tessellation's grid directions */
                double phi = (r - 1) * 0.5 * M_PI + 0.3;
                double ct = cos(25.0 * M_PI / 180.0), st = sin(25.0 * M_PI / 180.0);
                for (int d = 0; d < 3; d++)
                    dir[d] = ct * nrm[d] + st * (cos(phi) * e1[d] + sin(phi) * e2[d]);
                double l = sqrt(dot3(dir, dir));
                for (int d = 0; d < 3; d++) dir[d] /= l;
            }
            for (int d = 0; d < 3; d++) back[d] = -dir[d];
            int front_self, front_all, back_self, back_all;
            if (!count_crossings(s, component, component[part], centre, dir, offset,
                                 &front_self, &front_all) ||
                !count_crossings(s, component, component[part], centre, back, offset,
                                 &back_self, &back_all))
                continue;
            /* decisive pair: one side odd, the other even; the own component first */
            if ((front_self ^ back_self) & 1)
                vote += (front_self % 2 == 0 ? 1.0 : -1.0) * s->tri_area[best];
            else if ((front_all ^ back_all) & 1)
                vote += (front_all % 2 == 0 ? 1.0 : -1.0) * s->tri_area[best];
        }
    }
    return vote >= 0 ? 1 : -1;
}

/* Boundary vertices of each part (vertices of edges used by one triangle only), up to
 * COMPONENT_SAMPLES per part spread along the list: 3 doubles each into samples
 * (n_parts * COMPONENT_SAMPLES * 3), counts into n_samples. Returns 0 when out of memory. */
int sem_raycast_boundary_samples(const raw_mesh *mesh, int n_parts, double *samples, int *n_samples)
{
    for (int p = 0; p < n_parts; p++) n_samples[p] = 0;
    size_t n_edges = 3 * (size_t)mesh->n_triangles;
    int nv = mesh->n_vertices;
    /* edges (lo, hi) bucketed by lo (counting sort), each bucket sorted by hi: the edges
     * in (lo, hi) order in linear time; an edge used by one triangle only is a boundary
     * edge */
    int *bucket = calloc((size_t)nv + 2, sizeof *bucket);
    int *hi_of = malloc((n_edges > 0 ? n_edges : 1) * sizeof *hi_of);
    int *vertex_part = malloc(((size_t)nv + 1) * sizeof *vertex_part);
    int *count = calloc((size_t)n_parts + 1, sizeof *count);
    int *seen = calloc((size_t)n_parts + 1, sizeof *seen);
    int *bverts = malloc((n_edges > 0 ? n_edges : 1) * sizeof *bverts);
    if (!bucket || !hi_of || !vertex_part || !count || !seen || !bverts) {
        free(bucket);
        free(hi_of);
        free(vertex_part);
        free(count);
        free(seen);
        free(bverts);
        return 0;
    }
    for (int t = 0; t < mesh->n_triangles; t++)
        for (int c = 0; c < 3; c++) {
            int a = mesh->triangles[3 * (size_t)t + c];
            int b = mesh->triangles[3 * (size_t)t + (c + 1) % 3];
            int lo = a < b ? a : b;
            if (lo >= 0 && lo < nv) bucket[lo + 1]++;
        }
    for (int v = 0; v < nv; v++) bucket[v + 1] += bucket[v];
    int *fill = vertex_part; /* scratch for the fill positions, reset below */
    for (int v = 0; v < nv; v++) fill[v] = bucket[v];
    for (int t = 0; t < mesh->n_triangles; t++)
        for (int c = 0; c < 3; c++) {
            int a = mesh->triangles[3 * (size_t)t + c];
            int b = mesh->triangles[3 * (size_t)t + (c + 1) % 3];
            int lo = a < b ? a : b, hi = a < b ? b : a;
            if (lo >= 0 && lo < nv) hi_of[fill[lo]++] = hi;
        }
    /* vertices belong to one part in the shared tessellation: vertex -> part */
    for (int v = 0; v < nv; v++) vertex_part[v] = -1;
    for (int t = 0; t < mesh->n_triangles; t++)
        for (int c = 0; c < 3; c++) {
            int v = mesh->triangles[3 * (size_t)t + c];
            if (v >= 0 && v < nv) vertex_part[v] = mesh->triangle_part[t];
        }
    size_t n_boundary = 0;
    for (int v = 0; v < nv; v++) {
        int b0 = bucket[v], b1 = bucket[v + 1];
        for (int i = b0 + 1; i < b1; i++) { /* insertion sort: a handful per vertex */
            int x = hi_of[i], j = i - 1;
            while (j >= b0 && hi_of[j] > x) {
                hi_of[j + 1] = hi_of[j];
                j--;
            }
            hi_of[j + 1] = x;
        }
        for (int i = b0; i < b1;) {
            int j = i + 1;
            while (j < b1 && hi_of[j] == hi_of[i]) j++;
            if (j == i + 1) bverts[n_boundary++] = v;
            i = j;
        }
    }
    /* count per part, then take evenly spread ones */
    for (size_t e = 0; e < n_boundary; e++) {
        int p = vertex_part[bverts[e]];
        if (p >= 0 && p < n_parts) count[p]++;
    }
    for (size_t e = 0; e < n_boundary; e++) {
        int v = bverts[e];
        int p = vertex_part[v];
        if (p < 0 || p >= n_parts) continue;
        int idx = seen[p]++;
        int stride = count[p] / COMPONENT_SAMPLES + 1;
        if (idx % stride != 0 || n_samples[p] >= COMPONENT_SAMPLES) continue;
        memcpy(samples + 3 * ((size_t)p * COMPONENT_SAMPLES + (size_t)n_samples[p]),
               mesh->vertices + 3 * (size_t)v, 3 * sizeof(double));
        n_samples[p]++;
    }
    free(bucket);
    free(hi_of);
    free(vertex_part);
    free(count);
    free(seen);
    free(bverts);
    return 1;
}

/* Components of parts that touch: a boundary sample of one part within tol of another
 * part joins them (a box's 6 patches form one component; a nested or embedded solid whose
 * boundary does not touch the outer one is its own component). */
int sem_raycast_part_components(const sem_raycast_scene *s, const double *samples,
                           const int *n_samples, int *component)
{
    int n_parts = s->n_parts;
    int *parent = malloc((size_t)n_parts * sizeof *parent);
    int *found = malloc((size_t)n_parts * sizeof *found);
    double *dist = malloc((size_t)n_parts * sizeof *dist);
    if (!parent || !found || !dist) {
        free(parent);
        free(found);
        free(dist);
        return 0;
    }
    for (int p = 0; p < n_parts; p++) parent[p] = p;
    double tol = 5e-3 * s->scale; /* above the tessellation's chord error along shared edges */
    for (int p = 0; p < n_parts; p++)
        for (int k = 0; k < n_samples[p]; k++) {
            const double *X = samples + 3 * ((size_t)p * COMPONENT_SAMPLES + (size_t)k);
            int n = sem_raycast_closest_parts_embree(s, X, tol, found, dist, NULL);
            for (int i = 0; i < n; i++) {
                sem_uf_unite(parent, p, found[i]);
            }
        }
    for (int p = 0; p < n_parts; p++) component[p] = sem_uf_find(parent, p);
    free(parent);
    free(found);
    free(dist);
    return 1;
}
