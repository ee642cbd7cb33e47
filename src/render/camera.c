/*
 * camera.c - where the camera is and the ray through a point of the picture.
 *
 * A pinhole camera with z up. The orbit camera looks at the centre of the framed box
 * (sem_render_def.bounds: the whole animation, so the camera does not move from frame to
 * frame) from an azimuth and elevation. Its default distance is the smallest at which
 * all 8 corners of the box project inside the picture with a 5% border: for a corner at
 * c = centre + r right + u up + f forward, seen from distance D, its picture coordinates
 * are r / (D + f) and u / (D + f) (in units of the half-angle tangents), so each corner
 * gives a lower bound on D in closed form; the box's bounding sphere would waste most of a
 * wide picture on a long object.
 */
#include <math.h>

#include "render_internal.h"

static void normalize(double v[3])
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (n > 0) {
        v[0] /= n;
        v[1] /= n;
        v[2] /= n;
    }
}

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* right and up from forward, with z up (y up when looking straight up or down). */
static void basis(render_camera *c)
{
    double world_up[3] = {0, 0, 1};
    if (fabs(c->forward[2]) > 0.999999) {
        world_up[1] = 1;
        world_up[2] = 0;
    }
    cross(c->forward, world_up, c->right);
    normalize(c->right);
    cross(c->right, c->forward, c->up);
    normalize(c->up);
}

sem_status render_camera_place(const sem_render_def *def, render_camera *c, sem_error *err)
{
    const sem_camera *cam = &def->camera;
    c->width = def->width;
    c->height = def->height;
    if (!(cam->fov > 0 && cam->fov < 170))
        return sem_error_set(err, SEM_ERR_INVALID, "render: field of view %g must be in (0, 170) degrees",
                             cam->fov);
    c->tan_half_height = tan(0.5 * cam->fov * M_PI / 180.0);
    c->tan_half_width = c->tan_half_height * (double)def->width / (double)def->height;
    const double *b = def->bounds;
    double center[3] = {0.5 * (b[0] + b[3]), 0.5 * (b[1] + b[4]), 0.5 * (b[2] + b[5])};
    if (cam->look_at) {
        for (int k = 0; k < 3; ++k) {
            c->eye[k] = cam->eye[k];
            c->forward[k] = cam->target[k] - cam->eye[k];
        }
        if (!(dot(c->forward, c->forward) > 0))
            return sem_error_set(err, SEM_ERR_INVALID, "render: camera eye and target are the same point");
        normalize(c->forward);
        basis(c);
        return SEM_OK;
    }
    if (!(cam->elevation >= -90 && cam->elevation <= 90) || !isfinite(cam->azimuth))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "render: camera elevation %g must be in [-90, 90] degrees", cam->elevation);
    const double az = cam->azimuth * M_PI / 180.0, el = cam->elevation * M_PI / 180.0;
    /* from the centre towards the camera */
    const double towards[3] = {cos(el) * cos(az), cos(el) * sin(az), sin(el)};
    for (int k = 0; k < 3; ++k) c->forward[k] = -towards[k];
    basis(c);
    double distance = cam->distance;
    if (!(distance > 0)) {
        const double border = 0.9; /* corners stay inside 90% of the half-width and height */
        double diagonal = sqrt((b[3] - b[0]) * (b[3] - b[0]) + (b[4] - b[1]) * (b[4] - b[1]) +
                               (b[5] - b[2]) * (b[5] - b[2]));
        distance = diagonal > 0 ? 1e-3 * diagonal : 1.0;
        for (int corner = 0; corner < 8; ++corner) {
            double p[3] = {b[(corner & 1) ? 3 : 0] - center[0], b[(corner & 2) ? 4 : 1] - center[1],
                           b[(corner & 4) ? 5 : 2] - center[2]};
            double r = fabs(dot(p, c->right)), u = fabs(dot(p, c->up)), f = dot(p, c->forward);
            double need_r = r / (border * c->tan_half_width) - f;
            double need_u = u / (border * c->tan_half_height) - f;
            if (need_r > distance) distance = need_r;
            if (need_u > distance) distance = need_u;
        }
    }
    for (int k = 0; k < 3; ++k) c->eye[k] = center[k] + distance * towards[k];
    return SEM_OK;
}

void render_camera_ray(const render_camera *c, double x, double y, double dir[3])
{
    const double sx = (2.0 * x / c->width - 1.0) * c->tan_half_width;
    const double sy = (1.0 - 2.0 * y / c->height) * c->tan_half_height;
    for (int k = 0; k < 3; ++k) dir[k] = c->forward[k] + sx * c->right[k] + sy * c->up[k];
    normalize(dir);
}
