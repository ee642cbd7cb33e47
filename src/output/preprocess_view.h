/*
 * preprocess_view.h - what of the preprocessing a run folder keeps (internal; see
 * sem_animation_write_preprocess in sem/animation.h).
 */
#ifndef SEM_OUTPUT_PREPROCESS_VIEW_H
#define SEM_OUTPUT_PREPROCESS_VIEW_H

#include "sem/preprocess.h"

/* Saves d without its boundary samples and simulation operators to path. */
sem_status output_write_preprocess(const char *path, const sem_discretization *d, sem_error *err);

#endif
