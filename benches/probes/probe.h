// What the probes share: the clock they read and the order they sort their samples in.
// Header-only, so each probe still builds with one `gcc -O2 -o NAME NAME.c`.
#ifndef PROBE_H
#define PROBE_H

#include <time.h>

static inline long long now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1000000000LL + t.tv_nsec;
}

// For qsort over long long samples (ns), smallest first.
static inline int by_value(const void *a, const void *b) {
    long long x = *(const long long *)a, y = *(const long long *)b;
    return x < y ? -1 : x > y;
}

#endif
