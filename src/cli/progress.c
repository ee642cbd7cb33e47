/*
 * progress.c - progress reports for long commands (API in cli.h).
 *
 * On a terminal the bar is redrawn in place (at most ~10 times a second, so that a tight
 * loop does not spend its time printing); when stderr is a file or a pipe (CI logs) one
 * plain line per 10% keeps logs short and readable. Only stderr is used: stdout stays
 * clean for results and JSON.
 */
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"

#define BAR_WIDTH 30

static struct {
    int active, tty;
    char label[64];
    long total, done;
    int last_decile;     /* non-terminal: last 10% step printed */
    double start, last_draw;
    char extra[128];
} P;

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void draw_bar(void)
{
    double frac = P.total > 0 ? (double)P.done / (double)P.total : 1.0;
    if (frac < 0) frac = 0;
    if (frac > 1) frac = 1;
    int filled = (int)(frac * BAR_WIDTH + 0.5);
    char bar[BAR_WIDTH + 1];
    for (int i = 0; i < BAR_WIDTH; ++i) bar[i] = i < filled ? '#' : '.';
    bar[BAR_WIDTH] = '\0';
    double elapsed = now_seconds() - P.start;
    fprintf(stderr, "\r%s [%s] %3d%% %ld/%ld %.1fs%s%s\033[K", P.label, bar, (int)(100 * frac),
            P.done, P.total, elapsed, P.extra[0] ? "  " : "", P.extra);
    fflush(stderr);
}

static void print_line(void)
{
    double frac = P.total > 0 ? (double)P.done / (double)P.total : 1.0;
    fprintf(stderr, "%s: %3d%% (%ld/%ld) %.1fs%s%s\n", P.label, (int)(100 * frac + 1e-9),
            P.done, P.total, now_seconds() - P.start, P.extra[0] ? "  " : "", P.extra);
    fflush(stderr);
}

void progress_start(const char *label, long total)
{
    memset(&P, 0, sizeof P);
    P.active = 1;
    P.tty = isatty(STDERR_FILENO);
    snprintf(P.label, sizeof P.label, "%s", label ? label : "");
    P.total = total > 0 ? total : 0;
    P.start = now_seconds();
    P.last_draw = -1.0;
    P.last_decile = 0;
    if (P.tty) draw_bar();
}

void progress_update(long done, const char *extra)
{
    if (!P.active) return;
    P.done = done;
    snprintf(P.extra, sizeof P.extra, "%s", extra ? extra : "");
    if (P.tty) {
        double t = now_seconds();
        if (t - P.last_draw >= 0.1 || done >= P.total) {
            P.last_draw = t;
            draw_bar();
        }
        return;
    }
    int decile = P.total > 0 ? (int)(10 * (double)done / (double)P.total) : 10;
    if (decile > 10) decile = 10;
    if (decile > P.last_decile) {
        P.last_decile = decile;
        print_line();
    }
}

void progress_finish(void)
{
    if (!P.active) return;
    if (P.tty) {
        draw_bar();
        fputc('\n', stderr);
        fflush(stderr);
    } else if (P.last_decile < 10) {
        print_line();
    }
    P.active = 0;
}
