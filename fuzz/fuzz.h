/*
 * fuzz/fuzz.h - what every harness checks besides "no crash, no leak, no UB".
 *
 * A reader that rejects an input must say why in one printable line; a harness aborts
 * (which libFuzzer reports as a crash, with the input saved) when the message is empty or
 * holds a control byte, so the "one-line error" promise is fuzzed too.
 */
#ifndef SEM_FUZZ_H
#define SEM_FUZZ_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/status.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static inline void fuzz_check_error(sem_status st, const sem_error *err)
{
    if (st == SEM_OK) return;
    if (err->status != st || !err->message[0]) {
        fprintf(stderr, "fuzz: failure %d without a message\n", (int)st);
        abort();
    }
    for (const unsigned char *p = (const unsigned char *)err->message; *p; ++p)
        if (*p < 0x20 || *p == 0x7f) {
            fprintf(stderr, "fuzz: message holds control byte 0x%02x: %s\n", *p, err->message);
            abort();
        }
}

#endif
