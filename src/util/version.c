/*
 * version.c - sem_version() and sem_has_step(): what the library in use is (sem/version.h).
 */
#include "sem/version.h"

const char *sem_version(void) { return SEM_VERSION_STRING; }

int sem_has_step(void)
{
#ifdef SEM_HAVE_OCCT
    return 1;
#else
    return 0;
#endif
}
