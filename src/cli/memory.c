/*
 * memory.c - what the machine has and what the process took, for `sem run` and `sem bench`.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "cli.h"

double cli_memory_available(void)
{
    /* for tests (docs/simulation.md, "Memory"): pretend the machine has this much */
    const char *v = getenv("SEM_MEMORY_AVAILABLE_MB");
    if (v && *v) {
        char *end;
        errno = 0;
        double mb = strtod(v, &end);
        if (errno == 0 && *end == '\0' && mb > 0 && mb < 1e12) return mb * 1024.0 * 1024.0;
        cli_warn("SEM_MEMORY_AVAILABLE_MB='%s' is not a number of megabytes; ignored", v);
    }
    /* MemAvailable: what can be given without swapping (free memory plus reclaimable
     * caches), which on a shared machine is less than its total */
    FILE *f = fopen("/proc/meminfo", "r");
    if (f) {
        char line[256];
        double kb = -1;
        while (fgets(line, sizeof line, f))
            if (strncmp(line, "MemAvailable:", 13) == 0) {
                kb = strtod(line + 13, NULL);
                break;
            }
        fclose(f);
        if (kb > 0) return kb * 1024.0;
    }
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? (double)pages * (double)page : 0.0;
}

double cli_peak_memory(void)
{
    struct rusage r;
    if (getrusage(RUSAGE_SELF, &r) != 0) return 0.0;
    return (double)r.ru_maxrss * 1024.0; /* Linux reports kilobytes */
}

void cli_format_bytes(double bytes, char *out, size_t size)
{
    const double mb = 1024.0 * 1024.0, gb = 1024.0 * mb;
    if (bytes >= gb) snprintf(out, size, "%.3g GB", bytes / gb);
    else snprintf(out, size, "%.3g MB", bytes / mb);
}
