/*
 * sem/cache.h - the preprocessing cache: discretizations stored under the hash of their
 * model and settings (sem_preprocess_hash), so that `sem run` starts simulating at once
 * when a scene's objects were preprocessed before, by `sem run` or by `sem preprocess`.
 *
 * A cache is a folder of DIR/<hash>.semdisc files (sem_discretization_save). It is bounded:
 * after a store, the least recently used entries (a hit refreshes an entry's time) are
 * removed until the folder's entries take at most max_bytes; an entry larger than that on
 * its own is not stored. A damaged, truncated or forged entry is a miss (and is replaced by
 * the next store): every load checks the format, the checksum, the hash and that the
 * discretization fits the model (control points, parts and their offsets).
 */
#ifndef SEM_CACHE_H
#define SEM_CACHE_H

#include "sem/preprocess.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The default bound of a cache folder (SEM_CACHE_MAX_MB overrides it on the command line). */
#define SEM_CACHE_DEFAULT_MAX_BYTES (2LL << 30)

/* Path of the entry for (model, options) in dir. */
void sem_cache_entry_path(const char *dir, const sem_model *model,
                          const sem_preprocess_options *options, char *out, size_t size);
/* SEM_OK and *out on a hit; any other status is a miss, with the reason in err. */
sem_status sem_cache_load(const char *dir, const sem_model *model,
                          const sem_preprocess_options *options, sem_discretization **out,
                          sem_error *err);
/* Stores d (made from model and options) in dir (created if missing), then removes least
 * recently used entries until the folder holds at most max_bytes (<= 0: no bound). */
sem_status sem_cache_store(const char *dir, long long max_bytes, const sem_model *model,
                           const sem_preprocess_options *options, const sem_discretization *d,
                           sem_error *err);
/* Removes least recently used entries (never `keep`, a file name, may be NULL) until dir's
 * entries take at most max_bytes; also removes temporaries left by killed writers. */
sem_status sem_cache_trim(const char *dir, long long max_bytes, const char *keep, sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
