/* simulation_internal.h - test hooks of simulation.c (not part of the public API). */
#ifndef SEM_SIMULATION_INTERNAL_H
#define SEM_SIMULATION_INTERNAL_H

/* Points per assembly chunk for objects added from now on (default 8192; <= 0 restores
 * it). The stiffness is summed chunk by chunk so that the per-point blocks stay small; a
 * test sets a small chunk to check that the chunked sums equal the single-chunk ones. */
void sem_simulation_set_assembly_chunk(int points);

#endif
