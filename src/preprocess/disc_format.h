/*
 * disc_format.h - what the preprocessing's hash and its file share (internal to
 * src/preprocess/): the .semdisc magic, format version and byte-order mark, and the revision
 * of the default quadrature that salts the hash.
 */
#ifndef SEM_PREPROCESS_DISC_FORMAT_H
#define SEM_PREPROCESS_DISC_FORMAT_H

#define SEM_DISC_FORMAT_VERSION 6u
/* The revision of what the default quadrature computes (object-frame cells, no `rays`): the
 * file's layout is that of SEM_DISC_FORMAT_VERSION, but a cached discretization made by an
 * earlier revision holds other points for the same model and options, so the revision salts
 * their hash (sem_preprocess_hash) and such entries are made again. 1: rays refined and the
 * midpoint rule corrected by the surface's curvature (issue 27). The authors' explicit ray
 * grids compute what they did, and keep their hashes. */
#define SEM_DEFAULT_QUADRATURE_REVISION 1
#define SEM_DISC_BYTE_ORDER 0x01020304u
static const char sem_disc_magic[8] __attribute__((unused)) = {'S', 'E', 'M', 'D', 'I', 'S', 'C', '\0'};

#endif
