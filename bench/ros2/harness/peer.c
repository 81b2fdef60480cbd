/* The robot's side of bench/ros2/bench.py in C, on Eclipse Cyclone DDS's C library: what a ROS 2
 * driver and a controller (rclcpp over rmw_cyclonedds_cpp) put around the node. Python's Cyclone
 * binding costs a frame about 0.1 ms on its way out and a decision 0.15-0.2 ms on its way in on the
 * project's machine (bench/ros2/README.md), which is the bench's cost, not the node's.
 *
 *   peer pub DOMAIN FRAMES PERIOD_NS REPLAYS RELIABLE SENT   frames from FRAMES (written by bench.py),
 *        REPLAYS times, one every PERIOD_NS (0: flat out); each one's CLOCK_MONOTONIC time just before
 *        dds_write goes to SENT, a line each
 *   peer sub DOMAIN GOT   the decisions, stamped on receipt (CLOCK_MONOTONIC), until SIGTERM or SIGINT:
 *        "frame receipt_ns latency_us" lines in GOT; "ready" on stdout once the node is matched
 *
 * QoS as the Python peer's (tests/ros2/dds_peer.py): best effort keep last 5, or reliable keep all,
 * XCDR1 either way. Errors go to stderr with a non-zero exit. */
#define _GNU_SOURCE
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "ros2_types.h"

static volatile sig_atomic_t stopped = 0;
static void on_signal(int sig) { (void)sig; stopped = 1; }

static int64_t monotonic_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void die(const char *what, dds_return_t rc) {
  fprintf(stderr, "peer: %s: %s\n", what, rc < 0 ? dds_strretcode(rc) : "failed");
  exit(1);
}

static dds_qos_t *peer_qos(int reliable) {
  dds_qos_t *qos = dds_create_qos();
  if (reliable) {
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  } else {
    dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 5);
  }
  dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos, 1, &xcdr1);
  return qos;
}

/* Until the node's end of `entity` (a writer's reader, or a reader's writer) is matched: 30 s at most. */
static void wait_matched(dds_entity_t entity, int is_writer) {
  for (int tries = 0;; tries++) {
    uint32_t matched;
    if (is_writer) {
      dds_publication_matched_status_t st;
      dds_get_publication_matched_status(entity, &st);
      matched = st.current_count;
    } else {
      dds_subscription_matched_status_t st;
      dds_get_subscription_matched_status(entity, &st);
      matched = st.current_count;
    }
    if (matched > 0) return;
    if (tries == 1500) die(is_writer ? "the node's reader was not found within 30 s"
                                     : "the node's writer was not found within 30 s", 0);
    dds_sleepfor(DDS_MSECS(20));
  }
}

/* --- the frames file: u32 count, then per frame u32 height, width, step, u8 is_bigendian, and three
 * u32-length-prefixed byte strings (encoding, frame_id, data), i32 sec, u32 nanosec; little-endian. */

static void read_exact(FILE *f, void *out, size_t n, const char *path) {
  if (fread(out, 1, n, f) != n) {
    fprintf(stderr, "peer: %s: the frames file ends early\n", path);
    exit(1);
  }
}

static uint32_t read_u32(FILE *f, const char *path) {
  uint8_t b[4];
  read_exact(f, b, 4, path);
  return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static char *read_bytes(FILE *f, uint32_t *len, const char *path) {
  *len = read_u32(f, path);
  char *s = calloc(*len + 1, 1);
  if (!s) die("out of memory", 0);
  read_exact(f, s, *len, path);
  return s;
}

static sensor_msgs_msg_dds__Image_ *read_frames(const char *path, uint32_t *count) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "peer: cannot open %s: %s\n", path, strerror(errno));
    exit(1);
  }
  *count = read_u32(f, path);
  sensor_msgs_msg_dds__Image_ *frames = calloc(*count, sizeof *frames);
  if (!frames) die("out of memory", 0);
  for (uint32_t i = 0; i < *count; i++) {
    sensor_msgs_msg_dds__Image_ *m = &frames[i];
    uint32_t len;
    m->height = read_u32(f, path);
    m->width = read_u32(f, path);
    m->step = read_u32(f, path);
    read_exact(f, &m->is_bigendian, 1, path);
    m->encoding = read_bytes(f, &len, path);
    m->header.frame_id = read_bytes(f, &len, path);
    m->data._buffer = (uint8_t *)read_bytes(f, &len, path);
    m->data._length = m->data._maximum = len;
    m->header.stamp.sec = (int32_t)read_u32(f, path);
    m->header.stamp.nanosec = read_u32(f, path);
  }
  fclose(f);
  return frames;
}

static int publish(int argc, char **argv) {
  if (argc != 8) {
    fprintf(stderr, "usage: peer pub DOMAIN FRAMES PERIOD_NS REPLAYS RELIABLE SENT\n");
    return 2;
  }
  uint32_t count;
  sensor_msgs_msg_dds__Image_ *frames = read_frames(argv[3], &count);
  int64_t period = atoll(argv[4]);
  long replays = atol(argv[5]);
  int reliable = atoi(argv[6]);
  FILE *out = fopen(argv[7], "w");
  if (!out) die("cannot write the sent times", 0);
  int64_t *sent = calloc((size_t)count * (size_t)replays + 1, sizeof *sent);
  if (!sent) die("out of memory", 0);

  dds_entity_t dp = dds_create_participant((dds_domainid_t)atoi(argv[2]), NULL, NULL);
  if (dp < 0) die("participant", dp);
  dds_entity_t topic = dds_create_topic(dp, &sensor_msgs_msg_dds__Image__desc, "rt/foot/pressure", NULL, NULL);
  if (topic < 0) die("topic", topic);
  dds_qos_t *qos = peer_qos(reliable);
  dds_entity_t writer = dds_create_writer(dp, topic, qos, NULL);
  dds_delete_qos(qos);
  if (writer < 0) die("writer", writer);

  wait_matched(writer, 1);
  dds_sleepfor(DDS_MSECS(500));

  int64_t start = monotonic_ns();
  size_t n = 0;
  for (long r = 0; r < replays && !stopped; r++) {
    for (uint32_t i = 0; i < count; i++, n++) {
      if (period > 0) {
        int64_t due = start + (int64_t)n * period;
        struct timespec ts = {.tv_sec = due / 1000000000, .tv_nsec = due % 1000000000};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {}
      }
      sent[n] = monotonic_ns();
      dds_return_t rc = dds_write(writer, &frames[i]);
      if (rc < 0) die("write", rc);
    }
  }
  if (reliable) dds_wait_for_acks(writer, DDS_SECS(30));
  for (size_t k = 0; k < n; k++) fprintf(out, "%lld\n", (long long)sent[k]);
  fclose(out);
  dds_delete(dp);
  return 0;
}

static int subscribe(int argc, char **argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: peer sub DOMAIN GOT\n");
    return 2;
  }
  FILE *out = fopen(argv[3], "w");
  if (!out) die("cannot write the decisions", 0);
  dds_entity_t dp = dds_create_participant((dds_domainid_t)atoi(argv[2]), NULL, NULL);
  if (dp < 0) die("participant", dp);
  dds_entity_t topic = dds_create_topic(dp, &presrs_msgs_msg_dds__TerrainDecision__desc,
                                        "rt/presrs/decisions", NULL, NULL);
  if (topic < 0) die("topic", topic);
  dds_qos_t *qos = peer_qos(1);
  dds_entity_t reader = dds_create_reader(dp, topic, qos, NULL);
  dds_delete_qos(qos);
  if (reader < 0) die("reader", reader);

  wait_matched(reader, 0);
  printf("ready\n");
  fflush(stdout);

  dds_entity_t ws = dds_create_waitset(dp);
  dds_entity_t cond = dds_create_readcondition(reader, DDS_ANY_STATE);
  dds_waitset_attach(ws, cond, 0);
  enum { BATCH = 64 };
  void *samples[BATCH];
  dds_sample_info_t infos[BATCH];
  while (!stopped) {
    if (dds_waitset_wait(ws, NULL, 0, DDS_MSECS(50)) <= 0) continue;
    int64_t now = monotonic_ns();
    samples[0] = NULL;
    dds_return_t n = dds_take(reader, samples, infos, BATCH, BATCH);
    if (n < 0) die("take", n);
    for (int k = 0; k < n; k++) {
      if (!infos[k].valid_data) continue;
      const presrs_msgs_msg_dds__TerrainDecision_ *d = samples[k];
      fprintf(out, "%llu %lld %.3f\n", (unsigned long long)d->frame, (long long)now, d->latency_us);
    }
    if (n > 0) dds_return_loan(reader, samples, n);
  }
  fclose(out);
  dds_delete(dp);
  return 0;
}

int main(int argc, char **argv) {
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  if (argc >= 2 && strcmp(argv[1], "pub") == 0) return publish(argc, argv);
  if (argc >= 2 && strcmp(argv[1], "sub") == 0) return subscribe(argc, argv);
  fprintf(stderr, "usage: peer pub|sub ... (see the head of peer.c)\n");
  return 2;
}
