/*
 * friction.c - the smoothed Coulomb friction potential of one contact (see friction.h).
 */
#include "friction.h"

#include <math.h>

double sem_friction_potential(double mu_lambda, const double u[2], double eps, double g[2], double H[4])
{
    double y = sqrt(u[0] * u[0] + u[1] * u[1]);
    double f0, f1y, df1; /* f1(y) / y and f1'(y), f1 = f0' */
    if (y < eps) {
        f0 = -y * y * y / (3 * eps * eps) + y * y / eps + eps / 3;
        f1y = -y / (eps * eps) + 2 / eps;
        df1 = -2 * y / (eps * eps) + 2 / eps;
    } else {
        f0 = y;
        f1y = 1 / y;
        df1 = 0;
    }
    if (g) {
        g[0] = mu_lambda * f1y * u[0];
        g[1] = mu_lambda * f1y * u[1];
    }
    if (H) {
        double uu[4] = {0, 0, 0, 0};
        if (y > 0) {
            uu[0] = u[0] * u[0] / (y * y);
            uu[1] = uu[2] = u[0] * u[1] / (y * y);
            uu[3] = u[1] * u[1] / (y * y);
        }
        for (int k = 0; k < 4; ++k) {
            double I = k == 0 || k == 3 ? 1.0 : 0.0;
            H[k] = mu_lambda * (f1y * (I - uu[k]) + df1 * uu[k]);
        }
    }
    return mu_lambda * f0;
}

void sem_tangent_basis(const double n[3], double T[6])
{
    /* the axis least aligned with n, made orthogonal to it */
    int a = fabs(n[0]) <= fabs(n[1]) && fabs(n[0]) <= fabs(n[2]) ? 0 : fabs(n[1]) <= fabs(n[2]) ? 1 : 2;
    double e[3] = {0, 0, 0};
    e[a] = 1;
    double d = e[0] * n[0] + e[1] * n[1] + e[2] * n[2];
    double t1[3] = {e[0] - d * n[0], e[1] - d * n[1], e[2] - d * n[2]};
    double l = sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
    for (int k = 0; k < 3; ++k) t1[k] /= l;
    double t2[3] = {n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]};
    for (int k = 0; k < 3; ++k) {
        T[2 * k] = t1[k];
        T[2 * k + 1] = t2[k];
    }
}

double sem_friction_curvature(double mu_lambda, const double u[2], double eps)
{
    double y = sqrt(u[0] * u[0] + u[1] * u[1]);
    return mu_lambda * (y < eps ? -y / (eps * eps) + 2 / eps : 1 / y);
}
