/*
 * cli.h - the `sem` command line: subcommands and the helpers they share.
 *
 * Adding a command: write src/cli/cmd_NAME.c with `int cmd_NAME(int argc, char **argv)`
 * (argv[0] is the command name, "--help" is handled before the call), declare it below and
 * add one line to the table in main.c (name, function, usage, summary, help text).
 *
 * Conventions every command follows:
 *  - results go to stdout (human text, or one JSON object with --json via cli_print_json);
 *  - errors are exactly one line "sem: <message>" on stderr and exit status 1 (cli_fail);
 *  - usage errors print "sem: <message>" and the command's usage line, exit status 2
 *    (cli_usage);
 *  - warnings are "sem: warning: <message>" on stderr (cli_warn, cli_print_model_warnings);
 *  - long-running loops report through progress_* (stderr only).
 */
#ifndef SEM_CLI_H
#define SEM_CLI_H

#include <cjson/cJSON.h>

#include "sem/model.h"
#include "sem/status.h"

/* exit statuses */
enum { CLI_OK = 0, CLI_FAILED = 1, CLI_USAGE = 2 };

/* ---- commands (one file each) ---- */
int cmd_primitive(int argc, char **argv);
int cmd_inspect(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_refine(int argc, char **argv);
int cmd_preprocess(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_view(int argc, char **argv);
int cmd_validate(int argc, char **argv);
int cmd_probe(int argc, char **argv); /* hidden: validate's helper */

/* ---- messages (main.c) ---- */
/* Prints "sem: <message>" on stderr; returns CLI_FAILED. */
int cli_fail(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
/* Prints the error of a failed call: "sem: <err->message>", prefixed with "path: " when
 * path is given and the message does not already name it. Returns CLI_FAILED. */
int cli_fail_error(const char *path, const sem_error *err);
/* Prints "sem: <message>" and "usage: sem <command> <usage>" on stderr; returns CLI_USAGE. */
int cli_usage(const char *command, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Prints "sem: warning: <message>" on stderr. */
void cli_warn(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
/* Prints every model->warnings entry with cli_warn. */
void cli_print_model_warnings(const sem_model *model);
/* Prints json (cJSON_Print) and a newline on stdout, then deletes it. Returns CLI_OK, or
 * CLI_FAILED when json is NULL or printing runs out of memory. */
int cli_print_json(cJSON *json);

/* ---- the preprocessing cache (main.c), shared by run and preprocess ---- */
/* Folder: $SEM_CACHE_DIR, else $XDG_CACHE_HOME/sem, else $HOME/.cache/sem. */
void cli_cache_dir(char *out, size_t size);
/* Bound: $SEM_CACHE_MAX_MB megabytes (0: none), else SEM_CACHE_DEFAULT_MAX_BYTES. */
long long cli_cache_max_bytes(void);

/* ---- argument parsing (main.c) ---- */
/* Parses a finite number / an integer for `option` of `command`; on bad text prints a usage
 * error and returns CLI_USAGE, else CLI_OK. */
int cli_parse_double(const char *command, const char *option, const char *text, double *out);
int cli_parse_int(const char *command, const char *option, const char *text, int *out);
/* Makes sure option argv[i] has `count` values after it; prints a usage error if not. */
int cli_need_values(const char *command, int argc, char **argv, int i, int count);
/* An argument that is none of the command's options: a usage error when it looks like an
 * option ('-' and more) or when files[] already holds `most`; else the next of files[]. */
int cli_take_file(const char *command, const char *arg, const char **files, int *n, int most);
/* 1 for "--help" / "-h". */
int cli_is_help(const char *arg);

/* ---- memory (memory.c) ---- */
/* Bytes the machine can give a run now: $SEM_MEMORY_AVAILABLE_MB when set (for tests), else
 * MemAvailable of /proc/meminfo, else the physical memory; 0 when unknown. */
double cli_memory_available(void);
/* The process's peak resident memory so far (getrusage ru_maxrss), bytes. */
double cli_peak_memory(void);
/* "215 MB" or "1.5 GB". */
void cli_format_bytes(double bytes, char *out, size_t size);

/* ---- progress (progress.c) ---- */
/* A progress report on stderr for a loop of `total` steps: a redrawn bar when stderr is a
 * terminal, otherwise one line per ~10%. One report at a time (not thread-safe: call from
 * the thread that owns the loop). */
void progress_start(const char *label, long total);
/* done steps so far; extra (may be NULL) is a short text shown after the count. */
void progress_update(long done, const char *extra);
void progress_finish(void);

#endif
