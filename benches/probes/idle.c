// Whether memory left alone for a while is slower to touch again: one buffer (or several, in
// turn, as a channel's buffers are used once per window) swept after a sleep, one touch per
// page. On a host that takes back the pages a guest has not touched lately, the sweep after a
// long enough pause pays per page; warm it costs well under a µs per page.
//
//   gcc -O2 -o idle idle.c && ./idle KB BUFFERS PAUSE_US SWEEPS [huge]
//
// KB: each buffer's size; BUFFERS: how many, swept in turn (each is left alone for
// BUFFERS × PAUSE_US); PAUSE_US: the sleep before each sweep; SWEEPS: how many sweeps;
// `huge`: ask for transparent huge pages (madvise) on each buffer. Prints the sweep time,
// p50, p90, p99 and the maximum.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "probe.h"

#define HUGE_PAGE (2u << 20)

int main(int argc, char **argv) {
    if (argc != 5 && argc != 6) {
        fprintf(stderr, "usage: %s KB BUFFERS PAUSE_US SWEEPS [huge]\n", argv[0]);
        return 2;
    }
    size_t size = (size_t)atol(argv[1]) * 1024;
    int buffers = atoi(argv[2]), pause_us = atoi(argv[3]), sweeps = atoi(argv[4]);
    int huge = argc == 6 && strcmp(argv[5], "huge") == 0;
    if (size == 0 || buffers <= 0 || pause_us < 0 || sweeps <= 0) {
        fprintf(stderr, "KB, BUFFERS and SWEEPS must be positive, PAUSE_US not negative\n");
        return 2;
    }
    // Whole huge pages, aligned, so that a huge page can back each buffer if asked for.
    size_t mapped = (size + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE;
    char **buffer = calloc(buffers, sizeof *buffer);
    long long *took = calloc(sweeps, sizeof *took);
    if (!buffer || !took) return 1;
    for (int b = 0; b < buffers; b++) {
        buffer[b] = aligned_alloc(HUGE_PAGE, mapped);
        if (!buffer[b]) return 1;
        if (huge) madvise(buffer[b], mapped, MADV_HUGEPAGE);
        memset(buffer[b], 1, size);
    }
    for (int s = 0; s < sweeps; s++) {
        if (pause_us) usleep(pause_us);
        volatile char *swept = buffer[s % buffers];
        long long start = now_ns();
        for (size_t i = 0; i < size; i += 4096) swept[i]++;
        took[s] = now_ns() - start;
    }
    qsort(took, sweeps, sizeof *took, by_value);
    printf("%zu KB, %d buffer(s) in turn, %d µs apart (each left alone %.0f ms)%s, %d sweeps: "
           "p50 %.1f µs, p90 %.1f, p99 %.1f, max %.1f\n",
           size / 1024, buffers, pause_us, buffers * pause_us / 1e3, huge ? ", huge pages" : "",
           sweeps, took[sweeps / 2] / 1e3, took[sweeps * 9 / 10] / 1e3,
           took[sweeps * 99 / 100] / 1e3, took[sweeps - 1] / 1e3);
    return 0;
}
