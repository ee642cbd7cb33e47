/*
 * geometry/trim_fix.h - a part's trim loops made usable as the readers find them (internal;
 * used by the IGES and STEP readers): gaps between curves closed, loops that cross the seam of
 * a closed surface unwrapped, and the surface's seam moved out of the loops' way.
 */
#ifndef SEM_GEOMETRY_TRIM_FIX_H
#define SEM_GEOMETRY_TRIM_FIX_H

#include "sem/model.h"

typedef struct sem_loop_fix {
    double bridge;      /* in: model-space gaps between curves up to this are bridged */
    double widest_gap;  /* out: the widest gap bridged (0: none); the caller warns */
    double gap_limit;   /* out: the bridge used (bridge, or 1e-4 of the surface if larger) */
    int outer_dropped;  /* out: the outer loop could not be closed and was left out */
    int holes_dropped;  /* out: holes left out for the same reason */
    int wound;          /* out: the loops could not share one period of a closed surface (they
                           wind around it): they are kept as they came, nothing else done */
    int changed;        /* out: anything was done */
} sem_loop_fix;

/* Does nothing to loops that need nothing (curves that chain within trim.c's closure
 * tolerance and lie in the domain). Otherwise, loop by loop: curves turned head to tail
 * (exact reversal), a jump of whole periods across the seam of a closed surface taken away,
 * each remaining gap bridged by a straight (u,v) connector when its image is one point (a
 * collapsed edge: a pole) or shorter than fix->gap_limit; a loop with a wider gap is left out.
 * Then, in each closed direction, the surface's seam is moved (geometry/seam.h, exact) to
 * where no loop crosses it and every loop is shifted by whole periods into the new domain.
 * Fails only when out of memory. */
sem_status sem_part_fix_loops(sem_part *part, sem_loop_fix *fix);

/* What a reader does with a face whose loops cannot be made usable: the part keeps only its
 * surface (untrimmed); its loops and everything else are freed and zeroed. */
void sem_part_untrim(sem_part *part);

/* Exact reversal of a curve: control points and weights in reverse order, knots t -> a + b - t. */
void sem_curve_reverse(sem_curve *c);

#endif
