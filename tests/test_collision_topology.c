/* test_collision_topology.c - the normals that give a distance its sign between objects
 * (src/contact/collision_topology.h, collision_mesh.h).
 *
 * A box made of six separate Bezier patches, three of them turned inside out (their u
 * direction reversed, as a modeller's file may have them): the collision mesh must weld the
 * patches' coinciding boundary points, find a neighbour across every edge (the box is
 * closed), turn the three patches back (every face normal away from the centre), give each
 * corner the angle-weighted pseudonormal of its three faces (the diagonal exactly: three
 * right angles), and so call every point near the box inside or outside correctly: points
 * 0.02-0.3 outside of it, around corners and edges included, have a positive distance, points
 * 0.02-0.2 inside a negative one (brute force over all triangles). With one patch's normals
 * alone (the collision mesh before the eighth session's astronauts), a point outside next to
 * a corner was inside at the distance to the corner.
 * The welding itself: a flat grid of points (all one z, the case a sort by one coordinate
 * would make quadratic) with a copy 1e-7 away welds to its first copy, and a copy 1e-3 away
 * does not. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "contact/collision_mesh.h"
#include "contact/collision_topology.h"
#include "geometry/weld_points.h"
#include "contact/narrow_phase.h"
#include "sem/primitives.h"
#include "test_util.h"

/* Reverses a patch's u direction: the same surface, its normal the other way. */
static void reverse_u(sem_surface *s)
{
    for (int j = 0; j < s->n_v; ++j)
        for (int i = 0; i < s->n_u / 2; ++i) {
            int a = i + s->n_u * j, b = s->n_u - 1 - i + s->n_u * j;
            for (int k = 0; k < 3; ++k) {
                double x = s->ctrl[3 * a + k];
                s->ctrl[3 * a + k] = s->ctrl[3 * b + k];
                s->ctrl[3 * b + k] = x;
            }
            double w = s->weights[a];
            s->weights[a] = s->weights[b];
            s->weights[b] = w;
        }
    int nk = s->n_u + s->degree_u + 1;
    double lo = s->knots_u[0], hi = s->knots_u[nk - 1];
    for (int i = 0; i < nk / 2; ++i) {
        double x = s->knots_u[i];
        s->knots_u[i] = lo + hi - s->knots_u[nk - 1 - i];
        s->knots_u[nk - 1 - i] = lo + hi - x;
    }
    if (nk % 2) s->knots_u[nk / 2] = lo + hi - s->knots_u[nk / 2];
}

static unsigned long long rng = 88172645463325252ULL;
static double uniform(void) { return test_uniform(&rng); }

/* Signed distance of p to the mesh, as contact_world.c measures it. */
static double signed_distance(const sem_collision_mesh *m, const double p[3])
{
    double best = INFINITY;
    sem_tri_closest cl, bestcl;
    int bt = -1;
    for (int t = 0; t < m->n_triangles; ++t) {
        const int *tri = m->triangles + 3 * t;
        sem_point_triangle_closest(p, m->x + 3 * (size_t)tri[0], m->x + 3 * (size_t)tri[1], m->x + 3 * (size_t)tri[2],
                                   &cl);
        if (cl.dist2 < best) {
            best = cl.dist2;
            bestcl = cl;
            bt = t;
        }
    }
    double outward[3], n[3];
    sem_collision_mesh_outward(m, bt, bestcl.feature, bestcl.index, outward);
    return sem_signed_distance(p, bestcl.point, outward, n);
}

static void test_box(void)
{
    sem_model *model = sem_model_create();
    sem_error err;
    sem_box_def def = sem_default_box_def();
    CHECK(sem_primitive_box(model, &def, &err) == SEM_OK, "box: %s", err.message);
    CHECK(model->n_parts == 6, "box parts %d", model->n_parts);
    for (int p = 1; p < model->n_parts; p += 2) reverse_u(&model->parts[p].surface);
    sem_collision_mesh m;
    CHECK(sem_collision_mesh_build(model, 4, &m, &err) == SEM_OK, "collision mesh: %s", err.message);
    int welded = 0, open_edges = 0, inward = 0, bad_corners = 0, corners = 0;
    for (int p = 0; p < m.n_points; ++p) welded += m.weld[p] != p;
    for (int e = 0; e < 3 * m.n_triangles; ++e) open_edges += m.edge_other[e] < 0;
    for (int t = 0; t < m.n_triangles; ++t) {
        double c[3] = {0, 0, 0};
        for (int v = 0; v < 3; ++v)
            for (int k = 0; k < 3; ++k) c[k] += m.x[3 * (size_t)m.triangles[3 * t + v] + k] / 3;
        const double *n = m.face_normal + 3 * (size_t)t;
        inward += c[0] * n[0] + c[1] * n[1] + c[2] * n[2] <= 0;
    }
    for (int p = 0; p < m.n_points; ++p) {
        const double *x = m.x + 3 * (size_t)p, *n = m.pseudo_normal + 3 * (size_t)p;
        if (fabs(fabs(x[0]) - 0.5) > 1e-12 || fabs(fabs(x[1]) - 0.5) > 1e-12 || fabs(fabs(x[2]) - 0.5) > 1e-12)
            continue;
        ++corners;
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; ++k) bad_corners += fabs(n[k] / l - copysign(1 / sqrt(3.0), x[k])) > 1e-9;
    }
    printf("box of 6 patches (3 turned): %d points, %d welded to another, %d open edges, %d inward faces, "
           "%d corner points\n", m.n_points, welded, open_edges, inward, corners);
    CHECK(welded > 0, "no point welded");
    CHECK(open_edges == 0, "%d edges without a neighbour on a closed box", open_edges);
    CHECK(inward == 0, "%d faces facing inward", inward);
    CHECK(corners == 24, "%d corner points (6 patches x 4)", corners);
    CHECK(bad_corners == 0, "%d corner pseudonormal components off the diagonal", bad_corners);
    /* points around the box: out along a random direction from a random surface point */
    int wrong_out = 0, wrong_in = 0;
    for (int i = 0; i < 400; ++i) {
        double x[3], dir[3];
        for (int k = 0; k < 3; ++k) x[k] = uniform() - 0.5;
        int axis = (int)(3 * uniform()) % 3;
        x[axis] = uniform() < 0.5 ? -0.5 : 0.5;
        /* near corners and edges: pushed to the box's edges half of the time */
        if (i % 2) x[(axis + 1) % 3] = x[(axis + 1) % 3] < 0 ? -0.5 : 0.5;
        double l = 0;
        for (int k = 0; k < 3; ++k) {
            dir[k] = uniform() - 0.5;
            l += dir[k] * dir[k];
        }
        l = sqrt(l);
        double out[3], in[3], s = 0.02 + 0.28 * uniform(), si = 0.02 + 0.18 * uniform();
        for (int k = 0; k < 3; ++k) {
            /* outside: away from the box along the outward side of dir */
            double d = dir[k] / l;
            out[k] = x[k] + s * (fabs(x[k]) == 0.5 ? copysign(fabs(d), x[k]) : d);
            in[k] = x[k];
        }
        /* inside: towards the centre from a surface point */
        for (int k = 0; k < 3; ++k) in[k] = x[k] * (1 - 2 * si);
        int outside = fabs(out[0]) > 0.5 || fabs(out[1]) > 0.5 || fabs(out[2]) > 0.5;
        if (outside && !(signed_distance(&m, out) > 0)) ++wrong_out;
        if (!(signed_distance(&m, in) < 0)) ++wrong_in;
    }
    printf("400 points outside and 400 inside: %d and %d with the wrong sign\n", wrong_out, wrong_in);
    CHECK(wrong_out == 0, "%d points outside called inside", wrong_out);
    CHECK(wrong_in == 0, "%d points inside called outside", wrong_in);
    sem_collision_mesh_free(&m);
    sem_model_destroy(model);
}

static void test_weld(void)
{
    const int n = 100, total = 3 * n * n;
    double *x = malloc(3 * (size_t)total * sizeof(double));
    int *weld = malloc((size_t)total * sizeof(int));
    for (int i = 0; i < n * n; ++i) {
        double p[3] = {i % n, i / n, 0};
        for (int k = 0; k < 3; ++k) {
            x[3 * i + k] = p[k];
            x[3 * (n * n + i) + k] = p[k] + (k == 0 ? 1e-7 : 0);
            x[3 * (2 * n * n + i) + k] = p[k] + (k == 1 ? 1e-3 : 0);
        }
    }
    sem_error err;
    CHECK(sem_weld_points(x, total, 1e-5, weld, &err) == SEM_OK, "weld");
    int wrong = 0;
    for (int i = 0; i < n * n; ++i)
        wrong += weld[i] != i || weld[n * n + i] != i || weld[2 * n * n + i] != 2 * n * n + i;
    CHECK(wrong == 0, "%d of %d grid points welded wrongly", wrong, n * n);
    free(x);
    free(weld);
}

int main(void)
{
    test_weld();
    test_box();
    return test_finish("test_collision_topology");
}
