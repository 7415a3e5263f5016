/* cyclone_sub: a subscriber to stepbridge's AxisStatus and AxisPosition topics written
 * against bridge/idl/stepnode.idl alone, with Eclipse Cyclone DDS (C types from idlc).
 * It proves the bridge's topics are standard DDS and not Fast-DDS-only.
 *
 *   cyclone_sub [--domain N] [--count N] [--until-both] [--timeout-ms MS]
 *
 * Prints one line per sample and flushes it:
 *   AxisStatus node=5 axis=1 status_bits=0x0100 position_valid=1 moving=0 ... can_time_ns=...
 *   AxisPosition node=5 axis=1 motor_position=100 encoder_position=0 velocity=0 ...
 *   AxisStatus node=5 axis=1 disposed
 * Exits 0 after --count samples, or with --until-both once at least one sample of each
 * topic arrived (neither: run until the timeout or a signal); 1 when the timeout passed
 * first (and --count or --until-both was given), 2 on bad arguments. Reader QoS: RELIABLE;
 * AxisStatus TRANSIENT_LOCAL (a late joiner gets the current status), AxisPosition VOLATILE. */
#include <dds/dds.h>
#include <inttypes.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stepnode.h"

#define MAX_SAMPLES 64

static volatile sig_atomic_t stop_requested = 0;
static void on_signal(int sig) {
  (void)sig;
  stop_requested = 1;
}

static int parse_uint(const char* text, long max, long* out) {
  char* end = NULL;
  long v = strtol(text, &end, 10);
  if (!text[0] || *end || v < 0 || v > max) return 0;
  *out = v;
  return 1;
}

static void print_status(const stepnode_AxisStatus* s) {
  printf(
      "AxisStatus node=%u axis=%u status_bits=0x%04x error_bits=0x%02x emergency_stop=%d "
      "lower_limit=%d "
      "upper_limit=%d illegal_move=%d motor_stalled=%d power_up_error=%d position_valid=%d "
      "resumable=%d "
      "axis2_selected=%d axis3_selected=%d at_home=%d accelerating=%d decelerating=%d moving=%d "
      "done_code=%d "
      "hp_error=%u can_time_ns=%" PRIu64 "\n",
      s->node, s->axis, s->status_bits, s->error_bits, s->emergency_stop, s->lower_limit,
      s->upper_limit, s->illegal_move, s->motor_stalled, s->power_up_error, s->position_valid,
      s->resumable, s->axis2_selected, s->axis3_selected, s->at_home, s->accelerating,
      s->decelerating, s->moving, s->done_code, s->hp_error, s->can_time_ns);
}

static void print_position(const stepnode_AxisPosition* p) {
  printf("AxisPosition node=%u axis=%u motor_position=%" PRId32 " encoder_position=%" PRId32
         " motor_user_units=%.6g encoder_user_units=%.6g velocity=%" PRId32
         " motion_phase=%u sync_counter=%u"
         " can_time_ns=%" PRIu64 " publish_time_ns=%" PRIu64 "\n",
         p->node, p->axis, p->motor_position, p->encoder_position, p->motor_user_units,
         p->encoder_user_units, p->velocity, p->motion_phase, p->sync_counter, p->can_time_ns,
         p->publish_time_ns);
}

/* Takes everything waiting on `reader`; returns the number of samples printed. */
static long drain(dds_entity_t reader, int is_status, long* valid) {
  void* samples[MAX_SAMPLES] = {NULL};
  dds_sample_info_t infos[MAX_SAMPLES];
  long printed = 0;
  for (;;) {
    samples[0] = NULL;
    dds_return_t n = dds_take(reader, samples, infos, MAX_SAMPLES, MAX_SAMPLES);
    if (n <= 0) break;
    for (dds_return_t i = 0; i < n; i++) {
      if (infos[i].valid_data) {
        (*valid)++;
        if (is_status) print_status((const stepnode_AxisStatus*)samples[i]);
        else print_position((const stepnode_AxisPosition*)samples[i]);
      } else if (infos[i].instance_state != DDS_IST_ALIVE) {
        /* An invalid sample carries the instance's key fields. */
        unsigned node = is_status ? ((const stepnode_AxisStatus*)samples[i])->node
                                  : ((const stepnode_AxisPosition*)samples[i])->node;
        unsigned axis = is_status ? ((const stepnode_AxisStatus*)samples[i])->axis
                                  : ((const stepnode_AxisPosition*)samples[i])->axis;
        printf("%s node=%u axis=%u %s\n", is_status ? "AxisStatus" : "AxisPosition", node, axis,
               infos[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED ? "disposed" : "unregistered");
      }
      printed++;
    }
    dds_return_loan(reader, samples, n);
    fflush(stdout);
  }
  return printed;
}

struct options {
  long domain, count, timeout_ms;
  int until_both;
};

/* Parses the command line into `o`. Returns -1 to go on, or the exit status (0 for --help,
   2 for a bad argument). */
static int parse_options(int argc, char** argv, struct options* o) {
  for (int i = 1; i < argc; i++) {
    long* into = NULL;
    long max = 0;
    if (!strcmp(argv[i], "--domain")) into = &o->domain, max = 232;
    else if (!strcmp(argv[i], "--count")) into = &o->count, max = 1000000000L;
    else if (!strcmp(argv[i], "--timeout-ms")) into = &o->timeout_ms, max = 3600000L;
    else if (!strcmp(argv[i], "--until-both")) {
      o->until_both = 1;
      continue;
    } else if (!strcmp(argv[i], "--help")) {
      printf("usage: cyclone_sub [--domain N] [--count N] [--until-both] [--timeout-ms MS]\n");
      return 0;
    } else {
      fprintf(stderr, "cyclone_sub: unknown argument %s\n", argv[i]);
      return 2;
    }
    if (i + 1 >= argc || !parse_uint(argv[i + 1], max, into)) {
      fprintf(stderr, "cyclone_sub: %s needs an integer 0..%ld\n", argv[i], max);
      return 2;
    }
    i++;
  }
  return -1;
}

int main(int argc, char** argv) {
  struct options o = {0, 0, 0, 0};
  int parsed = parse_options(argc, argv, &o);
  if (parsed >= 0) return parsed;
  const long domain = o.domain, count = o.count, timeout_ms = o.timeout_ms;
  const int until_both = o.until_both;
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);

  dds_entity_t participant = dds_create_participant((dds_domainid_t)domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "cyclone_sub: dds_create_participant: %s\n", dds_strretcode(-participant));
    return 1;
  }
  dds_entity_t status_topic =
      dds_create_topic(participant, &stepnode_AxisStatus_desc, "AxisStatus", NULL, NULL);
  dds_entity_t position_topic =
      dds_create_topic(participant, &stepnode_AxisPosition_desc, "AxisPosition", NULL, NULL);
  if (status_topic < 0 || position_topic < 0) {
    fprintf(stderr, "cyclone_sub: dds_create_topic failed\n");
    dds_delete(participant);
    return 1;
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 64);
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_entity_t status_reader = dds_create_reader(participant, status_topic, qos, NULL);
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_entity_t position_reader = dds_create_reader(participant, position_topic, qos, NULL);
  dds_delete_qos(qos);
  if (status_reader < 0 || position_reader < 0) {
    fprintf(stderr, "cyclone_sub: dds_create_reader failed\n");
    dds_delete(participant);
    return 1;
  }

  dds_entity_t waitset = dds_create_waitset(participant);
  dds_entity_t status_cond = dds_create_readcondition(status_reader, DDS_ANY_STATE);
  dds_entity_t position_cond = dds_create_readcondition(position_reader, DDS_ANY_STATE);
  dds_waitset_attach(waitset, status_cond, status_reader);
  dds_waitset_attach(waitset, position_cond, position_reader);
  fprintf(stderr, "cyclone_sub: domain %ld, waiting for AxisStatus and AxisPosition\n", domain);

  long received = 0, statuses = 0, positions = 0;
  dds_time_t deadline = timeout_ms > 0 ? dds_time() + DDS_MSECS(timeout_ms) : DDS_NEVER;
  int rc = 0;
  for (;;) {
    if (stop_requested || (count > 0 && received >= count) ||
        (until_both && statuses > 0 && positions > 0))
      break;
    dds_time_t now = dds_time();
    if (now >= deadline) {
      rc = count > 0 || until_both ? 1 : 0;
      break;
    }
    dds_duration_t wait = DDS_MSECS(100);
    if (deadline - now < wait) wait = deadline - now;
    dds_waitset_wait(waitset, NULL, 0, wait);
    received += drain(status_reader, 1, &statuses);
    received += drain(position_reader, 0, &positions);
  }
  if (rc)
    fprintf(stderr,
            "cyclone_sub: timeout after %ld ms: %ld samples (%ld AxisStatus, %ld AxisPosition)\n",
            timeout_ms, received, statuses, positions);
  dds_delete(participant);
  return rc;
}
