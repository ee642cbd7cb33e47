/*
 * run_folder.h - reading the output folder of `sem run` (for `sem render` and `sem view`).
 *
 * A run folder holds frame_NNNN.igs (or frame_NNNN_nurbs.obj when IGES output is off)
 * for frames 0..N-1, summary.json (frame times and energies, objects and their parts, the
 * files written) and preprocess_K.semdisc per object (what the diagnostic colourings
 * show). See docs/render.md.
 */
#ifndef SEM_CLI_RUN_FOLDER_H
#define SEM_CLI_RUN_FOLDER_H

#include <cjson/cJSON.h>

#include "sem/model.h"
#include "sem/status.h"

typedef struct run_folder {
    char dir[4096];
    const char *suffix;   /* ".igs" or "_nurbs.obj": frame files are frame_NNNN<suffix> */
    int n_frames;         /* frames 0..n_frames-1, all present */
    cJSON *summary;       /* summary.json, or NULL when absent */
    double fps;           /* frames per second (summary.json; 24 without it) */
    int n_objects;        /* from summary.json; 1 without it */
    int *object_parts;    /* parts per object (0 = unknown, without summary.json) */
} run_folder;

/* Scans dir. Fails (one-line message) when dir has no frames, or a frame is missing between
 * the first and the last (or before the count summary.json records). */
sem_status run_folder_open(const char *dir, run_folder *rf, sem_error *err);
void run_folder_close(run_folder *rf);
/* dir/frame_NNNN<suffix> */
void run_folder_frame_path(const run_folder *rf, int frame, char *out, size_t size);
/* An object's entry of summary.json's "objects", or NULL. */
const cJSON *run_folder_object(const run_folder *rf, int object);

/* Is frame a frame of rest: the same parts, degrees and control grids (only control points
 * move)? */
int run_frame_matches(const sem_model *rest, const sem_model *frame);

/* Whole file into a NUL-terminated buffer (caller frees); NULL when it cannot be read. */
char *read_text_file(const char *path, size_t *size);

#endif
