/* simulation_internal.h - test hooks of simulation.c (not part of the public API). */
#ifndef SEM_SIMULATION_INTERNAL_H
#define SEM_SIMULATION_INTERNAL_H

/* Points per assembly chunk for objects added from now on (default 8192; <= 0 restores
 * it). The stiffness is summed chunk by chunk so that the per-point blocks stay small; a
 * test sets a small chunk to check that the chunked sums equal the single-chunk ones. */
void sem_simulation_set_assembly_chunk(int points);

/* Newton's Hessian (statics and implicit Euler): 1 (default) the exact one once two steps in
 * a row were full, falling back to the PSD-projected one when it is not positive definite;
 * 0 the projected one throughout. Returns the previous setting. A test compares the two. */
int sem_simulation_set_exact_hessian(int on);
/* How often Newton found the exact system not positive definite and fell back (all worlds
 * since the program started). */
long sem_simulation_exact_hessian_fallbacks(void);

#endif
