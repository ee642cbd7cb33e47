/*
 * penalty.c - the contact spring of one point (see penalty.h).
 */
#include "penalty.h"

double sem_penalty_energy(double k, double d, double thickness, double *slope)
{
    double g = d - thickness;
    if (!(g < 0)) {
        *slope = 0;
        return 0;
    }
    *slope = k * g;
    return 0.5 * k * g * g;
}

void sem_penalty_hessian(double k, const double n[3], double H[9])
{
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) H[3 * a + b] += k * n[a] * n[b];
}
