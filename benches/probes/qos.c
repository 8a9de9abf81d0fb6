// What a PM QoS request costs its writer (bearingd's outputs.cpu_awake_during_analysis writes
// 0 to /dev/cpu_dma_latency when a block arrives and the unconstrained value when it is done).
//
//   gcc -O2 -o qos qos.c && ./qos N GAP_US
//
// N pairs of writes, GAP_US apart (a sleep, so the CPUs are idle when the request tightens),
// with a little arithmetic between the two writes of a pair. Prints each write's duration,
// p50 / p90 / p99.
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "probe.h"

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s N GAP_US\n", argv[0]);
        return 2;
    }
    int n = atoi(argv[1]), gap_us = atoi(argv[2]);
    int device = open("/dev/cpu_dma_latency", O_RDWR);
    if (device < 0) {
        perror("/dev/cpu_dma_latency");
        return 1;
    }
    long long *tighten = malloc(sizeof(long long) * n), *release = malloc(sizeof(long long) * n);
    int awake = 0, unconstrained = 2000000000;
    for (int i = 0; i < n; i++) {
        usleep(gap_us);
        long long t0 = now_ns();
        write(device, &awake, sizeof awake);
        long long t1 = now_ns();
        volatile double x = 1;
        for (int j = 0; j < 20000; j++) x *= 1.000001;
        long long t2 = now_ns();
        write(device, &unconstrained, sizeof unconstrained);
        long long t3 = now_ns();
        tighten[i] = t1 - t0;
        release[i] = t3 - t2;
    }
    qsort(tighten, n, sizeof *tighten, by_value);
    qsort(release, n, sizeof *release, by_value);
    printf("write 0: p50 %.1f p90 %.1f p99 %.1f us; release: p50 %.1f p90 %.1f p99 %.1f us\n",
           tighten[n / 2] / 1e3, tighten[n * 9 / 10] / 1e3, tighten[n * 99 / 100] / 1e3,
           release[n / 2] / 1e3, release[n * 9 / 10] / 1e3, release[n * 99 / 100] / 1e3);
    return 0;
}
