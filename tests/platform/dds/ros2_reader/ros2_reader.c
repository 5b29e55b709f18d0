/* vp_test_ros2_reader: a stand-alone ROS 2-style subscriber, built only from the C types that
 * idlc generated from interfaces/ and from ddsc (no project header), as an independent party
 * would write one. It reads the drone's ROS 2 topics the way a ROS 2 node on rmw_cyclonedds
 * does: DDS topics rt/<ns>/vehicle_states, rt/<ns>/drone_status, rt/<ns>/occupancy and
 * rt<autoware topic>, default partition, plain CDR only (XCDR1: a writer offering anything
 * else does not match), reliable and transient-local (the grid: best effort, volatile). Every field
 * of every sample it takes is printed as "<topic>.<field path>=<value>" between "BEGIN <topic>" and
 * "END <topic>" lines; doubles with 17 and floats with 9 significant digits, so that the values
 * read back are exactly those sent. It stops once it has the requested number of samples of each
 * topic (status 0), or at the timeout (status 3); status 1 for a DDS error, 2 for usage. With
 * --until-writers-gone it also waits, after having the requested samples, until every writer it
 * matched has left (the sender's process or participant ended), taking whatever they wrote:
 * the counts are then minimums and the reader sees everything a sender wrote up to its end.
 *
 * usage: vp_test_ros2_reader --domain N --namespace NS --autoware-topic /T
 *          [--states K] [--status K] [--occupancy K] [--objects K] [--timeout-s S]
 *          [--until-writers-gone] */
#include <dds/dds.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "autoware_perception_msgs/msg/TrackedObjects_.h"
#include "nav_msgs/msg/OccupancyGrid_.h"
#include "vp_msgs/msg/DroneStatus_.h"
#include "vp_msgs/msg/VehicleStateArray_.h"

enum { kStates, kStatus, kOccupancy, kObjects, kTopics };

static const char* const kNames[kTopics] = {"vehicle_states", "drone_status", "occupancy",
                                            "tracked_objects"};

static int check(dds_return_t rc, const char* call) {
  if (rc < 0) {
    fprintf(stderr, "vp_test_ros2_reader: %s: %s\n", call, dds_strretcode(-rc));
    exit(1);
  }
  return rc;
}

static void d(const char* topic, const char* path, double value) {
  printf("%s.%s=%.17g\n", topic, path, value);
}
static void f(const char* topic, const char* path, float value) {
  printf("%s.%s=%.9g\n", topic, path, (double)value);
}
static void u(const char* topic, const char* path, unsigned long long value) {
  printf("%s.%s=%llu\n", topic, path, value);
}
static void i(const char* topic, const char* path, long long value) {
  printf("%s.%s=%lld\n", topic, path, value);
}

static void header(const char* t, const char* prefix, const std_msgs_msg_dds__Header_* h) {
  char path[128];
  snprintf(path, sizeof path, "%sheader.stamp.sec", prefix);
  i(t, path, h->stamp.sec);
  snprintf(path, sizeof path, "%sheader.stamp.nanosec", prefix);
  u(t, path, h->stamp.nanosec);
  printf("%s.%sheader.frame_id=%s\n", t, prefix, h->frame_id ? h->frame_id : "");
}

static void geodetic(const char* t, const char* name, const vp_msgs_msg_dds__GeodeticPoint_* p) {
  char path[128];
  snprintf(path, sizeof path, "%s.latitude_deg", name);
  d(t, path, p->latitude_deg);
  snprintf(path, sizeof path, "%s.longitude_deg", name);
  d(t, path, p->longitude_deg);
  snprintf(path, sizeof path, "%s.height_m", name);
  d(t, path, p->height_m);
}

static void point(const char* t, const char* name, double x, double y, double z) {
  char path[128];
  snprintf(path, sizeof path, "%s.x", name);
  d(t, path, x);
  snprintf(path, sizeof path, "%s.y", name);
  d(t, path, y);
  snprintf(path, sizeof path, "%s.z", name);
  d(t, path, z);
}

static void floats(const char* t, const char* name, const float* values, unsigned count) {
  char path[128];
  for (unsigned k = 0; k < count; ++k) {
    snprintf(path, sizeof path, "%s.%u", name, k);
    f(t, path, values[k]);
  }
}

static void doubles(const char* t, const char* name, const double* values, unsigned count) {
  char path[128];
  for (unsigned k = 0; k < count; ++k) {
    snprintf(path, sizeof path, "%s.%u", name, k);
    d(t, path, values[k]);
  }
}

static void printStates(const vp_msgs_msg_dds__VehicleStateArray_* a) {
  const char* t = kNames[kStates];
  char p[128];
  header(t, "", &a->header);
  u(t, "drone_id", a->drone_id);
  u(t, "vehicles.length", a->vehicles._length);
  for (unsigned k = 0; k < a->vehicles._length; ++k) {
    const vp_msgs_msg_dds__VehicleState_* v = &a->vehicles._buffer[k];
#define FIELD(fn, name, value)                      \
  snprintf(p, sizeof p, "vehicles.%u.%s", k, name); \
  fn(t, p, value)
    FIELD(u, "drone_id", v->drone_id);
    FIELD(u, "track_id", v->track_id);
    FIELD(i, "measurement_time.sec", v->measurement_time.sec);
    FIELD(u, "measurement_time.nanosec", v->measurement_time.nanosec);
    FIELD(f, "track_age_s", v->track_age_s);
    snprintf(p, sizeof p, "vehicles.%u.position", k);
    geodetic(t, p, &v->position);
    snprintf(p, sizeof p, "vehicles.%u.enu_m", k);
    point(t, p, v->enu_m.x, v->enu_m.y, v->enu_m.z);
    FIELD(d, "heading_enu_rad", v->heading_enu_rad);
    FIELD(d, "heading_true_north_deg", v->heading_true_north_deg);
    FIELD(f, "speed_mps", v->speed_mps);
    snprintf(p, sizeof p, "vehicles.%u.velocity_enu_mps", k);
    floats(t, p, v->velocity_enu_mps, 2);
    FIELD(f, "yaw_rate_radps", v->yaw_rate_radps);
    FIELD(f, "acceleration_mps2", v->acceleration_mps2);
    FIELD(f, "length_m", v->length_m);
    FIELD(f, "width_m", v->width_m);
    FIELD(f, "height_m", v->height_m);
    FIELD(u, "type", v->type);
    snprintf(p, sizeof p, "vehicles.%u.type_probability", k);
    floats(t, p, v->type_probability, 7);
    FIELD(u, "asm_gamma.length", v->asm_gamma._length);
    snprintf(p, sizeof p, "vehicles.%u.asm_gamma", k);
    floats(t, p, v->asm_gamma._buffer, v->asm_gamma._length);
    snprintf(p, sizeof p, "vehicles.%u.pose_covariance", k);
    floats(t, p, v->pose_covariance, 6);
    FIELD(f, "height_variance_m2", v->height_variance_m2);
    FIELD(f, "speed_variance_m2ps2", v->speed_variance_m2ps2);
    FIELD(f, "yaw_rate_variance_rad2ps2", v->yaw_rate_variance_rad2ps2);
    FIELD(f, "detection_confidence", v->detection_confidence);
    FIELD(u, "status", v->status);
    FIELD(u, "utm_zone", v->utm_zone);
    FIELD(u, "utm_northern_hemisphere", v->utm_northern_hemisphere ? 1U : 0U);
    FIELD(d, "utm_easting_m", v->utm_easting_m);
    FIELD(d, "utm_northing_m", v->utm_northing_m);
    snprintf(p, sizeof p, "vehicles.%u.rear_axle_enu_m", k);
    point(t, p, v->rear_axle_enu_m.x, v->rear_axle_enu_m.y, v->rear_axle_enu_m.z);
    snprintf(p, sizeof p, "vehicles.%u.rear_axle_position", k);
    geodetic(t, p, &v->rear_axle_position);
    FIELD(f, "length_variance_m2", v->length_variance_m2);
    FIELD(f, "width_variance_m2", v->width_variance_m2);
    FIELD(u, "keypoints_enu_m.length", v->keypoints_enu_m._length);
    for (unsigned j = 0; j < v->keypoints_enu_m._length; ++j) {
      const geometry_msgs_msg_dds__Point32_* q = &v->keypoints_enu_m._buffer[j];
      snprintf(p, sizeof p, "vehicles.%u.keypoints_enu_m.%u", k, j);
      point(t, p, q->x, q->y, q->z);
    }
#undef FIELD
  }
  u(t, "removed_track_ids.length", a->removed_track_ids._length);
  for (unsigned k = 0; k < a->removed_track_ids._length; ++k) {
    snprintf(p, sizeof p, "removed_track_ids.%u", k);
    u(t, p, a->removed_track_ids._buffer[k]);
  }
}

static void printStatus(const vp_msgs_msg_dds__DroneStatus_* s) {
  const char* t = kNames[kStatus];
  header(t, "", &s->header);
  u(t, "drone_id", s->drone_id);
  geodetic(t, "position", &s->position);
  d(t, "attitude_frd_to_ned.x", s->attitude_frd_to_ned.x);
  d(t, "attitude_frd_to_ned.y", s->attitude_frd_to_ned.y);
  d(t, "attitude_frd_to_ned.z", s->attitude_frd_to_ned.z);
  d(t, "attitude_frd_to_ned.w", s->attitude_frd_to_ned.w);
  floats(t, "gimbal_euler_deg", s->gimbal_euler_deg, 3);
  f(t, "frame_rate_hz", s->frame_rate_hz);
  f(t, "latency_median_ms", s->latency_median_ms);
  f(t, "latency_p99_ms", s->latency_p99_ms);
  f(t, "inference_median_ms", s->inference_median_ms);
  u(t, "frames_processed", s->frames_processed);
  u(t, "frames_dropped", s->frames_dropped);
  u(t, "corrupt_frames", s->corrupt_frames);
  u(t, "stale_poses", s->stale_poses);
  u(t, "outside_dtm", s->outside_dtm);
  u(t, "publish_errors", s->publish_errors);
  u(t, "active_tracks", s->active_tracks);
  printf("%s.model_id=%s\n", t, s->model_id);
}

static void printOccupancy(const nav_msgs_msg_dds__OccupancyGrid_* g) {
  const char* t = kNames[kOccupancy];
  char p[64];
  header(t, "", &g->header);
  i(t, "info.map_load_time.sec", g->info.map_load_time.sec);
  u(t, "info.map_load_time.nanosec", g->info.map_load_time.nanosec);
  f(t, "info.resolution", g->info.resolution);
  u(t, "info.width", g->info.width);
  u(t, "info.height", g->info.height);
  point(t, "info.origin.position", g->info.origin.position.x, g->info.origin.position.y,
        g->info.origin.position.z);
  d(t, "info.origin.orientation.x", g->info.origin.orientation.x);
  d(t, "info.origin.orientation.y", g->info.origin.orientation.y);
  d(t, "info.origin.orientation.z", g->info.origin.orientation.z);
  d(t, "info.origin.orientation.w", g->info.origin.orientation.w);
  u(t, "data.length", g->data._length);
  for (unsigned k = 0; k < g->data._length; ++k) {
    snprintf(p, sizeof p, "data.%u", k);
    i(t, p, g->data._buffer[k]);
  }
}

static void printCovariance(const char* t, const char* name, const double* c) {
  doubles(t, name, c, 36);
}

static void printObjects(const autoware_perception_msgs_msg_dds__TrackedObjects_* o) {
  const char* t = kNames[kObjects];
  char p[160];
  header(t, "", &o->header);
  u(t, "objects.length", o->objects._length);
  for (unsigned k = 0; k < o->objects._length; ++k) {
    const autoware_perception_msgs_msg_dds__TrackedObject_* b = &o->objects._buffer[k];
    const autoware_perception_msgs_msg_dds__TrackedObjectKinematics_* m = &b->kinematics;
    for (unsigned j = 0; j < 16; ++j) {
      snprintf(p, sizeof p, "objects.%u.object_id.uuid.%u", k, j);
      u(t, p, b->object_id.uuid[j]);
    }
    snprintf(p, sizeof p, "objects.%u.existence_probability", k);
    f(t, p, b->existence_probability);
    snprintf(p, sizeof p, "objects.%u.classification.length", k);
    u(t, p, b->classification._length);
    for (unsigned j = 0; j < b->classification._length; ++j) {
      snprintf(p, sizeof p, "objects.%u.classification.%u.label", k, j);
      u(t, p, b->classification._buffer[j].label);
      snprintf(p, sizeof p, "objects.%u.classification.%u.probability", k, j);
      f(t, p, b->classification._buffer[j].probability);
    }
    const geometry_msgs_msg_dds__Pose_* pose = &m->pose_with_covariance.pose;
    snprintf(p, sizeof p, "objects.%u.kinematics.pose_with_covariance.pose.position", k);
    point(t, p, pose->position.x, pose->position.y, pose->position.z);
    snprintf(p, sizeof p, "objects.%u.kinematics.pose_with_covariance.pose.orientation", k);
    point(t, p, pose->orientation.x, pose->orientation.y, pose->orientation.z);
    snprintf(p, sizeof p, "objects.%u.kinematics.pose_with_covariance.pose.orientation.w", k);
    d(t, p, pose->orientation.w);
    snprintf(p, sizeof p, "objects.%u.kinematics.pose_with_covariance.covariance", k);
    printCovariance(t, p, m->pose_with_covariance.covariance);
    const geometry_msgs_msg_dds__Twist_* tw = &m->twist_with_covariance.twist;
    snprintf(p, sizeof p, "objects.%u.kinematics.twist_with_covariance.twist.linear", k);
    point(t, p, tw->linear.x, tw->linear.y, tw->linear.z);
    snprintf(p, sizeof p, "objects.%u.kinematics.twist_with_covariance.twist.angular", k);
    point(t, p, tw->angular.x, tw->angular.y, tw->angular.z);
    snprintf(p, sizeof p, "objects.%u.kinematics.twist_with_covariance.covariance", k);
    printCovariance(t, p, m->twist_with_covariance.covariance);
    const geometry_msgs_msg_dds__Accel_* ac = &m->acceleration_with_covariance.accel;
    snprintf(p, sizeof p, "objects.%u.kinematics.acceleration_with_covariance.accel.linear", k);
    point(t, p, ac->linear.x, ac->linear.y, ac->linear.z);
    snprintf(p, sizeof p, "objects.%u.kinematics.acceleration_with_covariance.accel.angular", k);
    point(t, p, ac->angular.x, ac->angular.y, ac->angular.z);
    snprintf(p, sizeof p, "objects.%u.kinematics.acceleration_with_covariance.covariance", k);
    printCovariance(t, p, m->acceleration_with_covariance.covariance);
    snprintf(p, sizeof p, "objects.%u.kinematics.orientation_availability", k);
    u(t, p, m->orientation_availability);
    snprintf(p, sizeof p, "objects.%u.kinematics.is_stationary", k);
    u(t, p, m->is_stationary ? 1U : 0U);
    snprintf(p, sizeof p, "objects.%u.shape.type", k);
    u(t, p, b->shape.type);
    snprintf(p, sizeof p, "objects.%u.shape.footprint.points.length", k);
    u(t, p, b->shape.footprint.points._length);
    for (unsigned j = 0; j < b->shape.footprint.points._length; ++j) {
      const geometry_msgs_msg_dds__Point32_* q = &b->shape.footprint.points._buffer[j];
      snprintf(p, sizeof p, "objects.%u.shape.footprint.points.%u", k, j);
      point(t, p, q->x, q->y, q->z);
    }
    snprintf(p, sizeof p, "objects.%u.shape.dimensions", k);
    point(t, p, b->shape.dimensions.x, b->shape.dimensions.y, b->shape.dimensions.z);
  }
}

static void usage(void) {
  fprintf(stderr,
          "usage: vp_test_ros2_reader --domain N --namespace NS --autoware-topic /T [--states K]"
          " [--status K] [--occupancy K] [--objects K] [--timeout-s S] [--until-writers-gone]\n");
  exit(2);
}

int main(int argc, char** argv) {
  long domain = -1;
  const char* ns = NULL;
  const char* autowareTopic = NULL;
  long want[kTopics] = {0, 0, 0, 0};
  double timeout_s = 30.0;
  int untilWritersGone = 0;
  for (int a = 1; a < argc; ++a) {
    const char* key = argv[a];
    if (strcmp(key, "--until-writers-gone") == 0) {
      untilWritersGone = 1;
      continue;
    }
    if (a + 1 >= argc) {
      usage();
    }
    const char* value = argv[++a];
    if (strcmp(key, "--domain") == 0) {
      domain = strtol(value, NULL, 10);
    } else if (strcmp(key, "--namespace") == 0) {
      ns = value;
    } else if (strcmp(key, "--autoware-topic") == 0) {
      autowareTopic = value;
    } else if (strcmp(key, "--states") == 0) {
      want[kStates] = strtol(value, NULL, 10);
    } else if (strcmp(key, "--status") == 0) {
      want[kStatus] = strtol(value, NULL, 10);
    } else if (strcmp(key, "--occupancy") == 0) {
      want[kOccupancy] = strtol(value, NULL, 10);
    } else if (strcmp(key, "--objects") == 0) {
      want[kObjects] = strtol(value, NULL, 10);
    } else if (strcmp(key, "--timeout-s") == 0) {
      timeout_s = strtod(value, NULL);
    } else {
      usage();
    }
  }
  if (domain < 0 || domain > 232 || ns == NULL || autowareTopic == NULL ||
      autowareTopic[0] != '/') {
    usage();
  }

  const dds_entity_t participant =
      check(dds_create_participant((dds_domainid_t)domain, NULL, NULL), "dds_create_participant");
  /* What rmw_cyclonedds asks for: plain CDR; no partition (the default one). */
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  const dds_data_representation_id_t xcdr1[] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos, 1, xcdr1);

  const dds_topic_descriptor_t* descriptors[kTopics] = {
      &vp_msgs_msg_dds__VehicleStateArray__desc, &vp_msgs_msg_dds__DroneStatus__desc,
      &nav_msgs_msg_dds__OccupancyGrid__desc,
      &autoware_perception_msgs_msg_dds__TrackedObjects__desc};
  dds_entity_t readers[kTopics];
  const dds_entity_t waitset = check(dds_create_waitset(participant), "dds_create_waitset");
  for (int k = 0; k < kTopics; ++k) {
    char name[256];
    if (k == kObjects) {
      snprintf(name, sizeof name, "rt%s", autowareTopic);
    } else {
      snprintf(name, sizeof name, "rt/%s/%s", ns, kNames[k]);
    }
    const dds_entity_t topic =
        check(dds_create_topic(participant, descriptors[k], name, NULL, NULL), "dds_create_topic");
    /* The grid is offered best effort and volatile (dds.qos.occupancy): ask for no more. */
    dds_qos_t* readerQos = dds_create_qos();
    dds_copy_qos(readerQos, qos);
    if (k == kOccupancy) {
      dds_qset_reliability(readerQos, DDS_RELIABILITY_BEST_EFFORT, 0);
      dds_qset_durability(readerQos, DDS_DURABILITY_VOLATILE);
    }
    readers[k] = check(dds_create_reader(participant, topic, readerQos, NULL), "dds_create_reader");
    dds_delete_qos(readerQos);
    const dds_entity_t condition =
        check(dds_create_readcondition(readers[k], DDS_ANY_STATE), "dds_create_readcondition");
    check(dds_waitset_attach(waitset, condition, k), "dds_waitset_attach");
  }
  dds_delete_qos(qos);
  fprintf(stderr, "vp_test_ros2_reader: ready\n");

  long got[kTopics] = {0, 0, 0, 0};
  const dds_time_t end = dds_time() + (dds_duration_t)(timeout_s * 1e9);
  int writersGone = 0; /* every writer matched so far has left (read before the take below) */
  for (;;) {
    int done = !untilWritersGone || writersGone;
    for (int k = 0; k < kTopics; ++k) {
      done = done && got[k] >= want[k];
    }
    if (done) {
      break;
    }
    if (dds_time() >= end) {
      fprintf(stderr,
              "vp_test_ros2_reader: timeout: %ld/%ld states, %ld/%ld status, "
              "%ld/%ld occupancy, %ld/%ld objects\n",
              got[0], want[0], got[1], want[1], got[2], want[2], got[3], want[3]);
      fflush(stdout);
      return 3;
    }
    check(dds_waitset_wait(waitset, NULL, 0, DDS_MSECS(100)), "dds_waitset_wait");
    if (untilWritersGone) {
      /* Checked before taking: what a writer wrote before it left is in the cache by now. */
      int matchedEver = 0;
      int present = 0;
      for (int k = 0; k < kTopics; ++k) {
        dds_subscription_matched_status_t matched;
        check(dds_get_subscription_matched_status(readers[k], &matched),
              "dds_get_subscription_matched_status");
        matchedEver += matched.total_count > 0;
        present += matched.current_count > 0;
      }
      writersGone = matchedEver > 0 && present == 0;
    }
    for (int k = 0; k < kTopics; ++k) {
      void* samples[1] = {NULL};
      dds_sample_info_t info;
      while (check(dds_take(readers[k], samples, &info, 1, 1), "dds_take") > 0) {
        if (info.valid_data) {
          printf("BEGIN %s\n", kNames[k]);
          switch (k) {
            case kStates:
              printStates(samples[0]);
              break;
            case kStatus:
              printStatus(samples[0]);
              break;
            case kOccupancy:
              printOccupancy(samples[0]);
              break;
            default:
              printObjects(samples[0]);
              break;
          }
          printf("END %s\n", kNames[k]);
          ++got[k];
        }
        check(dds_return_loan(readers[k], samples, 1), "dds_return_loan");
      }
    }
  }
  fflush(stdout);
  check(dds_delete(participant), "dds_delete");
  return 0;
}
