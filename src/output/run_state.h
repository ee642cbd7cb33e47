/*
 * output/run_state.h - what a stopped `sem run` needs to continue (docs/scenes.md,
 * "Interrupted runs").
 *
 * Why: a long run stopped by Ctrl-C, SIGTERM, kill -9 or a power cut keeps its frames, and
 * should continue from the last of them with the result an uninterrupted run would have
 * given, bit for bit. A frame file alone cannot give that (IGES stores rounded control
 * points, and velocities not at all), so every frame also gets a state file:
 *
 *     OUT/state/run.json          which run the folder holds: the scene file and a hash of
 *                                 its text, frames, steps per frame, the frame name width,
 *                                 and each object's model-and-settings hash
 *     OUT/state/frame_NNNN.state  after frame NNNN: time, step count, q and v of every
 *                                 object (exact doubles), and the frame's summary numbers
 *
 * A state file is written atomically after the frame's other files, so a frame whose state
 * file exists and checks out (magic, version, run id, sizes, FNV-1a checksum) is complete.
 * The world carries nothing else from one step to the next (no solver or Newton history),
 * so time, q and v restore it exactly.
 *
 * The same module keeps runs apart: a folder that holds another run's frames is reported,
 * and cleared (only the files a run writes) when the user asks to overwrite it.
 */
#ifndef SEM_OUTPUT_RUN_STATE_H
#define SEM_OUTPUT_RUN_STATE_H

#include <stddef.h>

#include "sem/status.h"

#define SEM_RUN_MAX_STATS 32

typedef struct sem_run_info {
    char scene_path[4096];         /* absolute path of the scene file; "" for the default */
    unsigned long long scene_hash; /* FNV-1a 64 of the scene text */
    int frames, steps_per_frame;
    int digits;                    /* width of NNNN in frame names */
    int n_objects;
    unsigned long long object_hash[64]; /* sem_preprocess_hash of each object (first 64) */
} sem_run_info;

typedef struct sem_run_frame_state {
    int frame;
    long long steps;
    double time;
    int n_objects;
    size_t *n;      /* doubles in q (and in v) per object */
    double **q, **v;
    int n_stats;
    double stats[SEM_RUN_MAX_STATS];
} sem_run_frame_state;

/* Digits of frame names for a run of `frames` frames: 4, or more when needed. */
int sem_run_frame_digits(int frames);
/* FNV-1a 64 of a text (scene files). */
unsigned long long sem_run_text_hash(const char *text, size_t len);
/* Identifies a run in its state files: a hash of everything in info. */
unsigned long long sem_run_id(const sem_run_info *info);

sem_status sem_run_info_write(const char *dir, const sem_run_info *info, sem_error *err);
sem_status sem_run_info_read(const char *dir, sem_run_info *info, sem_error *err);

sem_status sem_run_state_write(const char *dir, int digits, unsigned long long run_id,
                               const sem_run_frame_state *state, sem_error *err);
/* Reads frame `frame` of run `run_id`; n_objects and dofs[] (doubles in q per object) must
 * match. Allocates state->q, ->v, ->n (sem_run_frame_state_free). */
sem_status sem_run_state_read(const char *dir, int digits, int frame, unsigned long long run_id,
                              int n_objects, const size_t *dofs, sem_run_frame_state *state,
                              sem_error *err);
void sem_run_frame_state_free(sem_run_frame_state *state);

/* 1 when dir holds files a run writes (frame_*, animation.usda/.glb, summary.json, state/),
 * with the first one found in example. */
int sem_run_folder_in_use(const char *dir, char *example, size_t size);
/* Removes exactly those files (and the state folder), and temporary files they left. */
sem_status sem_run_folder_clear(const char *dir, sem_error *err);

#endif
