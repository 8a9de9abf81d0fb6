// Whether a switch to another process makes memory slower to touch right after (a flushed
// TLB would): a buffer swept warm, after a 5 ms sleep, and right after a round trip to another
// process on the same CPU.
//
//   gcc -O2 -o tlb tlb.c && ./tlb KB STRIDE
//
// KB: the buffer's size; STRIDE: bytes between touches (4096: one per page, 64: one per cache
// line). Prints each condition's sweep time, p50 (and p90), over 300 sweeps.
#define _GNU_SOURCE
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "probe.h"

#define REPS 300

static long long sweep_ns(volatile char *buffer, size_t size, size_t stride) {
    long long start = now_ns();
    for (size_t i = 0; i < size; i += stride) buffer[i]++;
    return now_ns() - start;
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s KB STRIDE\n", argv[0]);
        return 2;
    }
    size_t size = (size_t)atoi(argv[1]) << 10, stride = (size_t)atoi(argv[2]);
    char *buffer = malloc(size);
    memset(buffer, 1, size);
    cpu_set_t cpu0;
    CPU_ZERO(&cpu0);
    CPU_SET(0, &cpu0);
    sched_setaffinity(0, sizeof cpu0, &cpu0);
    int there[2], back[2];
    if (pipe(there) != 0 || pipe(back) != 0) return 1;
    if (fork() == 0) {  // the other process, on the same CPU: echoes each byte
        close(there[1]);
        char byte;
        while (read(there[0], &byte, 1) == 1) write(back[1], &byte, 1);
        _exit(0);
    }
    close(there[0]);
    long long warm[REPS], slept[REPS], switched[REPS];
    for (int i = 0; i < REPS; i++) {
        sweep_ns(buffer, size, stride);
        warm[i] = sweep_ns(buffer, size, stride);
    }
    for (int i = 0; i < REPS; i++) {
        sweep_ns(buffer, size, stride);
        usleep(5000);
        slept[i] = sweep_ns(buffer, size, stride);
    }
    for (int i = 0; i < REPS; i++) {
        sweep_ns(buffer, size, stride);
        char byte = 'x';
        write(there[1], &byte, 1);
        read(back[0], &byte, 1);
        switched[i] = sweep_ns(buffer, size, stride);
    }
    close(there[1]);
    wait(0);
    qsort(warm, REPS, sizeof(long long), by_value);
    qsort(slept, REPS, sizeof(long long), by_value);
    qsort(switched, REPS, sizeof(long long), by_value);
    printf("%zu KB, a touch every %zu B: warm p50 %.1f | after a 5 ms sleep p50 %.1f p90 %.1f | "
           "right after a switch to another process p50 %.1f p90 %.1f us\n",
           size >> 10, stride, warm[REPS / 2] / 1e3, slept[REPS / 2] / 1e3,
           slept[REPS * 9 / 10] / 1e3, switched[REPS / 2] / 1e3, switched[REPS * 9 / 10] / 1e3);
    return 0;
}
