// How much a process pays to wake another through a Unix datagram socket (what iceoryx2's
// notify does), and when the woken process runs.
//
//   gcc -O2 -o wake wake.c && ./wake N GAP_MS WORK_US PIN QOS
//
// N wake-ups, GAP_MS apart; before and after each send the sender computes WORK_US (as the
// analysis thread does around an alert). PIN: 0 the kernel places both, 1 sender on CPU 0 and
// receiver on CPU 1, 2 both on CPU 0. QOS: 1 holds /dev/cpu_dma_latency at 0 from just before
// the work until after it (bearingd's outputs.cpu_awake_during_analysis), 0 not.
// Prints send()'s own duration and send start -> receipt, p50 / p90 / p99, and how often the
// receiver held the datagram before send() had returned (it ran on the sender's CPU).
#define _GNU_SOURCE
#include <fcntl.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "probe.h"

static void print_spread(const char *name, long long *v, int n) {
    qsort(v, n, sizeof *v, by_value);
    printf("  %-22s p50 %6.1f p90 %6.1f p99 %6.1f us\n", name, v[n / 2] / 1e3,
           v[n * 9 / 10] / 1e3, v[n * 99 / 100] / 1e3);
}

static void pin_to(int cpu) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    sched_setaffinity(0, sizeof set, &set);
}

static void compute_for(long long us) {
    volatile double x = 1;
    long long end = now_ns() + us * 1000;
    while (now_ns() < end) x = x * 1.0000001 + 1e-9;
}

int main(int argc, char **argv) {
    if (argc != 6) {
        fprintf(stderr, "usage: %s N GAP_MS WORK_US PIN(0|1|2) QOS(0|1)\n", argv[0]);
        return 2;
    }
    int n = atoi(argv[1]), gap_ms = atoi(argv[2]), work_us = atoi(argv[3]);
    int pin = atoi(argv[4]), qos = atoi(argv[5]);
    int pair[2];
    if (socketpair(AF_UNIX, SOCK_DGRAM, 0, pair) != 0) return 1;
    // Send start, send end and receipt of each wake-up, shared with the receiver.
    long long *t = mmap(0, sizeof(long long) * 3 * n, PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    long long *sent = t, *returned = t + n, *received = t + 2 * n;
    pid_t receiver = fork();
    if (receiver == 0) {
        if (pin) pin_to(pin == 1 ? 1 : 0);
        char byte[8];
        for (int i = 0; i < n; i++) {
            recv(pair[1], byte, sizeof byte, 0);
            received[i] = now_ns();
        }
        _exit(0);
    }
    if (pin) pin_to(0);
    int device = qos ? open("/dev/cpu_dma_latency", O_RDWR) : -1;
    if (qos && device < 0) {
        perror("/dev/cpu_dma_latency");
        return 1;
    }
    int awake = 0, unconstrained = 2000000000;
    for (int i = 0; i < n; i++) {
        usleep(gap_ms * 1000);
        if (qos) write(device, &awake, sizeof awake);
        compute_for(work_us);
        sent[i] = now_ns();
        send(pair[0], "x", 1, 0);
        returned[i] = now_ns();
        compute_for(work_us);
        if (qos) write(device, &unconstrained, sizeof unconstrained);
    }
    waitpid(receiver, 0, 0);
    long long *send_cost = malloc(sizeof(long long) * n);
    long long *latency = malloc(sizeof(long long) * n);
    int before = 0;
    for (int i = 0; i < n; i++) {
        send_cost[i] = returned[i] - sent[i];
        latency[i] = received[i] - sent[i];
        before += received[i] < returned[i];
    }
    printf("%d wake-ups %d ms apart, work %d us, pin %d, qos %d: received before send() returned: %d\n",
           n, gap_ms, work_us, pin, qos, before);
    print_spread("send() duration", send_cost, n);
    print_spread("send start -> receipt", latency, n);
    return 0;
}
