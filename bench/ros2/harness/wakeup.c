/* How long this machine takes to wake a sleeping thread: the floor under every thread hand-off of a
 * DDS path (RustDDS's receive thread -> the node's thread -> RustDDS's event loop -> the wire).
 *
 *   wakeup [COUNT] [PERIOD_US]   (default 2000 wake-ups, one every 10,000 us: 100 Hz, as the bench)
 *
 * A waker thread sleeps PERIOD_US, stamps CLOCK_MONOTONIC and writes an eventfd; a sleeper thread,
 * blocked in poll() on it, stamps on its return. Prints the wake-up latency's p50, p90, p99 and max in
 * microseconds as one JSON line. Idle between wake-ups, as a node at 100 Hz is. */
#define _GNU_SOURCE
#include <poll.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

static int fd;
static long count, period_us;
static int64_t *sent, *woke;

static int64_t monotonic_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void *sleeper(void *arg) {
  (void)arg;
  for (long i = 0; i < count; i++) {
    struct pollfd p = {.fd = fd, .events = POLLIN};
    while (poll(&p, 1, -1) != 1) {}
    woke[i] = monotonic_ns();
    uint64_t v;
    if (read(fd, &v, sizeof v) != sizeof v) exit(1);
  }
  return NULL;
}

static int by_value(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv) {
  count = argc > 1 ? atol(argv[1]) : 2000;
  period_us = argc > 2 ? atol(argv[2]) : 10000;
  fd = eventfd(0, 0);
  sent = calloc(count, sizeof *sent);
  woke = calloc(count, sizeof *woke);
  pthread_t t;
  pthread_create(&t, NULL, sleeper, NULL);
  for (long i = 0; i < count; i++) {
    struct timespec ts = {.tv_sec = period_us / 1000000, .tv_nsec = (period_us % 1000000) * 1000};
    nanosleep(&ts, NULL);
    sent[i] = monotonic_ns();
    uint64_t one = 1;
    if (write(fd, &one, sizeof one) != sizeof one) return 1;
  }
  pthread_join(t, NULL);
  for (long i = 0; i < count; i++) woke[i] -= sent[i];
  qsort(woke, count, sizeof *woke, by_value);
  printf("{\"wakeups\": %ld, \"period_us\": %ld, \"p50_us\": %.1f, \"p90_us\": %.1f, \"p99_us\": %.1f, "
         "\"max_us\": %.1f}\n", count, period_us, woke[count / 2] / 1e3, woke[count * 9 / 10] / 1e3,
         woke[count * 99 / 100] / 1e3, woke[count - 1] / 1e3);
  return 0;
}
