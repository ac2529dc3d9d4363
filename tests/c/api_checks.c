/*
 * Checks the C ABI from C, in one process: a server with a tracker, button, analog and dial
 * on a free port of 127.0.0.1, remotes reading them, exact values through callbacks and
 * polling, error codes and texts, a call from the wrong thread, a callback that frees its own
 * handle. Run by tests/capi.rs; prints "api_checks: N checks passed" or the failed check.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "vrpn.h"

static int checks = 0;

#define CHECK(cond)                                                                          \
    do {                                                                                     \
        checks++;                                                                            \
        if (!(cond)) {                                                                       \
            fprintf(stderr, "%s:%d: check failed: %s (last error: %d %s)\n", __FILE__,     \
                    __LINE__, #cond, (int)vrpn_last_error_status(), vrpn_last_error());      \
            exit(1);                                                                         \
        }                                                                                    \
    } while (0)

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double seconds_of(VrpnTimeVal t)
{
    return (double)t.sec + t.usec * 1e-6;
}

/* What the callbacks saw, reached through their userdata. */
struct seen {
    int poses, velocities, changes, reports, updates;
    VrpnTrackerPose pose;
    VrpnTrackerVelocity velocity;
    VrpnButtonChange change;
    VrpnAnalogReport report;
    double dial_sum;
};

static void on_pose(void *u, const VrpnTrackerPose *p)
{
    struct seen *s = (struct seen *)u;
    if (p->sensor == 1) {
        s->poses++;
        s->pose = *p;
    }
}
static void on_velocity(void *u, const VrpnTrackerVelocity *v)
{
    struct seen *s = (struct seen *)u;
    s->velocities++;
    s->velocity = *v;
}
static void on_change(void *u, const VrpnButtonChange *c)
{
    struct seen *s = (struct seen *)u;
    if (c->button == 2) {
        s->changes++;
        s->change = *c;
    }
}
static void on_report(void *u, const VrpnAnalogReport *r)
{
    struct seen *s = (struct seen *)u;
    s->reports++;
    s->report = *r;
}
static void on_update(void *u, const VrpnDialUpdate *d)
{
    struct seen *s = (struct seen *)u;
    s->updates++;
    s->dial_sum += d->change;
}

/* A callback that frees the remote whose mainloop is running it. */
struct self_free {
    VrpnTracker *tracker;
    int calls;
    VrpnStatus status;
};
static void free_self(void *u, const VrpnTrackerPose *p)
{
    struct self_free *f = (struct self_free *)u;
    (void)p;
    if (f->calls++ == 0)
        f->status = vrpn_tracker_free(f->tracker);
}

/* Another thread's view of a handle. */
struct other_thread {
    VrpnTracker *tracker;
    VrpnStatus status;
    VrpnStatus last_status;
    char text[256];
};
static void *use_from_other_thread(void *u)
{
    struct other_thread *o = (struct other_thread *)u;
    o->status = vrpn_tracker_mainloop(o->tracker);
    o->last_status = vrpn_last_error_status();
    snprintf(o->text, sizeof o->text, "%s", vrpn_last_error());
    return NULL;
}

int main(void)
{
    /* Version and ABI. */
    CHECK(strlen(vrpn_version()) > 0);
    CHECK(vrpn_abi_version() == VRPN_ABI_VERSION);
    CHECK(strcmp(vrpn_last_error(), "") == 0);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_OK);
    CHECK(strcmp(vrpn_status_name(VRPN_STATUS_WRONG_THREAD), "WRONG_THREAD") == 0);
    CHECK(strcmp(vrpn_status_name(VRPN_STATUS_NO_DATA), "NO_DATA") == 0);
    CHECK(strcmp(vrpn_status_name(12345), "UNKNOWN") == 0);

    /* Errors: codes and texts. */
    CHECK(vrpn_tracker_open(NULL) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(strstr(vrpn_last_error(), "device name is NULL") != NULL);
    CHECK(vrpn_tracker_open("Tracker0@") == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_NAME);
    CHECK(strstr(vrpn_last_error(), "Tracker0@") != NULL);
    CHECK(vrpn_analog_open("\xff@localhost") == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_tracker_mainloop(NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_set_default_printer(7) == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_tracker_free(NULL) == VRPN_STATUS_OK);
    CHECK(vrpn_server_open(0, "not-an-address") == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_INVALID_ARGUMENT);

    /* The server and its devices. */
    VrpnServer *server = vrpn_server_open(0, "127.0.0.1");
    CHECK(server != NULL);
    int port = vrpn_server_port(server);
    CHECK(port > 0);
    CHECK(vrpn_server_open((uint16_t)port, "127.0.0.1") == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_IO);
    CHECK(vrpn_server_connection_state(server) == VRPN_CONNECTION_STATE_LISTENING);
    CHECK(vrpn_tracker_server_new(server, "Dev0", 0) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_INVALID_ARGUMENT);
    /* The bounds vrpn.cfg applies, a name clients can open, one device per interface/name. */
    CHECK(vrpn_tracker_server_new(server, "Dev0", 1025) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(strstr(vrpn_last_error(), "1 to 1024 sensors") != NULL);
    CHECK(vrpn_tracker_server_new(server, "Dev0", -5) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_button_server_new(server, "Dev0", 257) == NULL);
    CHECK(strstr(vrpn_last_error(), "1 to 256 buttons") != NULL);
    CHECK(vrpn_analog_server_new(server, "Dev0", 129) == NULL);
    CHECK(vrpn_dial_server_new(server, "Dev0", 0) == NULL);
    CHECK(vrpn_tracker_server_new(server, "Dev0@host", 1) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_NAME);
    CHECK(strstr(vrpn_last_error(), "must not contain '@'") != NULL);
    CHECK(vrpn_tracker_server_new(server, "", 1) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_NAME);
    VrpnTrackerServer *big = vrpn_tracker_server_new(server, "Big", 1024);
    CHECK(big != NULL);
    CHECK(vrpn_tracker_server_new(server, "Big", 1) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(strstr(vrpn_last_error(), "a tracker named \"Big\" already exists") != NULL);
    VrpnButtonServer *big_buttons = vrpn_button_server_new(server, "Big", 1);
    CHECK(big_buttons != NULL); /* another interface under the same name is fine */
    CHECK(vrpn_button_server_free(big_buttons) == VRPN_STATUS_OK);
    CHECK(vrpn_tracker_server_free(big) == VRPN_STATUS_OK);
    big = vrpn_tracker_server_new(server, "Big", 1); /* the name is free again */
    CHECK(big != NULL);
    CHECK(vrpn_tracker_server_free(big) == VRPN_STATUS_OK);
    VrpnTrackerServer *ts = vrpn_tracker_server_new(server, "Dev0", 2);
    VrpnButtonServer *bs = vrpn_button_server_new(server, "Dev0", 4);
    VrpnAnalogServer *as = vrpn_analog_server_new(server, "Dev0", 3);
    VrpnDialServer *ds = vrpn_dial_server_new(server, "Dev0", 2);
    CHECK(ts && bs && as && ds);
    CHECK(vrpn_button_server_set(bs, 4, 1) == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_analog_server_set(as, -1, 0.0) == VRPN_STATUS_INVALID_ARGUMENT);
    const double pos[3] = {1.5, -2.5, 3.25}, quat[4] = {0.0, 0.6, 0.0, 0.8};
    CHECK(vrpn_tracker_server_report_pose(ts, 1, NULL, NULL, quat) ==
          VRPN_STATUS_NULL_ARGUMENT);
    const VrpnTimeVal bad_usec = {1700000000, 5000000}, negative_usec = {1700000000, -1};
    CHECK(vrpn_tracker_server_report_pose(ts, 1, &bad_usec, pos, quat) ==
          VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(strstr(vrpn_last_error(), "usec must be between 0 and 999999") != NULL);
    CHECK(vrpn_tracker_server_report_pose(ts, 1, &negative_usec, pos, quat) ==
          VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_button_server_report_changes(bs, &bad_usec) == VRPN_STATUS_INVALID_ARGUMENT);
    vrpn_set_default_printer(2); /* the next call sends a text the remote would print */
    CHECK(vrpn_tracker_server_report_pose(ts, 5, NULL, pos, quat) == VRPN_STATUS_UNSUPPORTED);

    /* Remotes, before anything arrived. */
    char name[64];
    snprintf(name, sizeof name, "Dev0@127.0.0.1:%d", port);
    VrpnTracker *tracker = vrpn_tracker_open(name);
    VrpnButton *button = vrpn_button_open(name);
    VrpnAnalog *analog = vrpn_analog_open(name);
    VrpnDial *dial = vrpn_dial_open(name);
    CHECK(tracker && button && analog && dial);
    VrpnTrackerPose pose;
    VrpnAnalogReport report;
    double revolutions = 0.0;
    CHECK(vrpn_tracker_pose(tracker, 0, &pose) == VRPN_STATUS_NO_DATA);
    CHECK(vrpn_tracker_pose(tracker, -1, &pose) == VRPN_STATUS_INVALID_ARGUMENT);
    /* Arguments are checked first: a NULL output is refused before data arrived too. */
    CHECK(vrpn_tracker_pose(tracker, 0, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_tracker_velocity(tracker, 0, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_tracker_acceleration(tracker, 0, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_analog_latest(analog, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_analog_channels(analog, NULL, 4) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_analog_channels(analog, NULL, 0) == 0);
    CHECK(vrpn_button_states(button, NULL, 4) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_button_states(button, NULL, 0) == 0);
    CHECK(vrpn_dial_rotation(dial, 0, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_analog_latest(analog, &report) == VRPN_STATUS_NO_DATA);
    CHECK(vrpn_analog_channels(analog, report.channel, VRPN_ANALOG_MAX_CHANNELS) == 0);
    CHECK(vrpn_button_count(button) == 0);
    CHECK(vrpn_dial_rotation(dial, 0, &revolutions) == VRPN_STATUS_NO_DATA);
    int state = vrpn_tracker_connection_state(tracker);
    CHECK(state == VRPN_CONNECTION_STATE_CONNECTING);
    /* A handle of another kind is refused. */
    CHECK(vrpn_button_mainloop((VrpnButton *)tracker) == VRPN_STATUS_INVALID_HANDLE);

    struct seen seen;
    memset(&seen, 0, sizeof seen);
    uint64_t pose_id = 0, other_id = 0;
    CHECK(vrpn_tracker_on_pose(tracker, on_pose, &seen, &pose_id) == VRPN_STATUS_OK);
    CHECK(pose_id != 0);
    CHECK(vrpn_tracker_on_velocity(tracker, on_velocity, &seen, &other_id) == VRPN_STATUS_OK);
    CHECK(other_id != pose_id);
    CHECK(vrpn_tracker_on_pose(tracker, NULL, &seen, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_button_on_change(button, on_change, &seen, NULL) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_on_report(analog, on_report, &seen, NULL) == VRPN_STATUS_OK);
    CHECK(vrpn_dial_on_update(dial, on_update, &seen, NULL) == VRPN_STATUS_OK);

    /* Report until every callback saw its value (5 s at most). */
    const VrpnTimeVal stamp = {1700000000, 250000};
    const double vel[3] = {0.1, 0.2, 0.3}, vquat[4] = {0.0, 0.0, 0.0, 1.0};
    CHECK(vrpn_analog_server_set(as, 0, 0.5) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_server_set(as, 1, -1.0) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_server_set(as, 2, 42.0) == VRPN_STATUS_OK);
    CHECK(vrpn_button_server_set(bs, 2, 1) == VRPN_STATUS_OK);
    int dial_turns = 0;
    double deadline = now_seconds() + 5.0;
    while ((seen.poses == 0 || seen.velocities == 0 || seen.changes == 0 || seen.reports == 0 ||
            seen.updates < 2) &&
           now_seconds() < deadline) {
        if (vrpn_server_connected_clients(server) > 0) {
            CHECK(vrpn_tracker_server_report_pose(ts, 1, &stamp, pos, quat) == VRPN_STATUS_OK);
            CHECK(vrpn_tracker_server_report_velocity(ts, 0, NULL, vel, vquat, 0.01) ==
                  VRPN_STATUS_OK);
            CHECK(vrpn_button_server_report_changes(bs, NULL) == VRPN_STATUS_OK);
            CHECK(vrpn_analog_server_report(as, NULL) == VRPN_STATUS_OK);
            if (dial_turns < 2) {
                CHECK(vrpn_dial_server_add(ds, 1, 0.25) == VRPN_STATUS_OK);
                CHECK(vrpn_dial_server_report_changes(ds, NULL) == VRPN_STATUS_OK);
                dial_turns++;
            }
        }
        CHECK(vrpn_server_mainloop(server) == VRPN_STATUS_OK);
        CHECK(vrpn_tracker_mainloop(tracker) == VRPN_STATUS_OK);
        CHECK(vrpn_button_mainloop(button) == VRPN_STATUS_OK);
        CHECK(vrpn_analog_mainloop(analog) == VRPN_STATUS_OK);
        CHECK(vrpn_dial_mainloop(dial) == VRPN_STATUS_OK);
        vrpn_server_wait(server, 1);
    }

    /* Callbacks: exact values, userdata passed back. */
    CHECK(seen.poses > 0);
    CHECK(seen.pose.sensor == 1);
    CHECK(seen.pose.pos[0] == 1.5 && seen.pose.pos[1] == -2.5 && seen.pose.pos[2] == 3.25);
    CHECK(seen.pose.quat[0] == 0.0 && seen.pose.quat[1] == 0.6 && seen.pose.quat[2] == 0.0 &&
          seen.pose.quat[3] == 0.8);
    /* The stamp, translated by the estimate of the server's clock (the same clock here). */
    CHECK(fabs(seconds_of(seen.pose.time) - seconds_of(stamp)) < 0.1);
    CHECK(seen.velocities > 0);
    CHECK(seen.velocity.sensor == 0 && seen.velocity.vel[2] == 0.3);
    CHECK(seen.velocity.vel_quat[3] == 1.0 && seen.velocity.vel_quat_dt == 0.01);
    CHECK(seen.changes == 1);
    CHECK(seen.change.button == 2 && seen.change.state == 1);
    CHECK(seen.reports > 0);
    CHECK(seen.report.num_channel == 3);
    CHECK(seen.report.channel[0] == 0.5 && seen.report.channel[1] == -1.0 &&
          seen.report.channel[2] == 42.0 && seen.report.channel[3] == 0.0);
    CHECK(seen.updates == 2 && seen.dial_sum == 0.5);

    /* Polling: the same values copied into our structs. */
    CHECK(vrpn_tracker_pose(tracker, 1, &pose) == VRPN_STATUS_OK);
    CHECK(pose.pos[1] == -2.5 && pose.quat[3] == 0.8);
    CHECK(fabs(seconds_of(pose.time) - seconds_of(stamp)) < 0.1);
    CHECK(vrpn_tracker_pose(tracker, 1, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_tracker_pose(tracker, 0, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_button_states(button, NULL, 4) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_analog_channels(analog, NULL, 4) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_analog_latest(analog, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_dial_rotation(dial, 1, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_tracker_sensor_count(tracker) == 2);
    VrpnTrackerVelocity velocity;
    CHECK(vrpn_tracker_velocity(tracker, 0, &velocity) == VRPN_STATUS_OK);
    CHECK(velocity.vel[0] == 0.1);
    CHECK(vrpn_button_count(button) == 4);
    CHECK(vrpn_button_state(button, 2) == 1 && vrpn_button_state(button, 1) == 0);
    CHECK(vrpn_button_state(button, 256) == VRPN_STATUS_INVALID_ARGUMENT);
    int32_t states[8] = {9, 9, 9, 9, 9, 9, 9, 9};
    CHECK(vrpn_button_states(button, states, 8) == 4);
    CHECK(states[0] == 0 && states[1] == 0 && states[2] == 1 && states[3] == 0 && states[4] == 9);
    CHECK(vrpn_button_states(button, states, 2) == 2);
    CHECK(vrpn_analog_latest(analog, &report) == VRPN_STATUS_OK);
    CHECK(report.num_channel == 3 && report.channel[2] == 42.0);
    double values[2] = {0.0, 0.0};
    CHECK(vrpn_analog_channels(analog, values, 2) == 2);
    CHECK(values[0] == 0.5 && values[1] == -1.0);
    CHECK(vrpn_dial_rotation(dial, 1, &revolutions) == VRPN_STATUS_OK && revolutions == 0.5);
    CHECK(vrpn_dial_rotation(dial, 0, &revolutions) == VRPN_STATUS_NO_DATA);
    CHECK(vrpn_analog_server_report_changes(as, NULL) == VRPN_STATUS_NO_DATA);

    /* Connection state. */
    CHECK(vrpn_tracker_connection_state(tracker) == VRPN_CONNECTION_STATE_CONNECTED);
    CHECK(vrpn_server_connection_state(server) == VRPN_CONNECTION_STATE_CONNECTED);
    CHECK(vrpn_server_connected_clients(server) == 1);

    /* A removed callback is not called again; its id is gone. */
    CHECK(vrpn_tracker_remove_callback(tracker, pose_id) == VRPN_STATUS_OK);
    CHECK(vrpn_tracker_remove_callback(tracker, pose_id) == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_tracker_remove_callback(tracker, 0) == VRPN_STATUS_INVALID_ARGUMENT);
    int before = seen.poses, velocities_before = seen.velocities;
    deadline = now_seconds() + 0.3;
    while (now_seconds() < deadline) {
        vrpn_tracker_server_report_pose(ts, 1, NULL, pos, quat);
        vrpn_tracker_server_report_velocity(ts, 0, NULL, vel, vquat, 0.01);
        vrpn_server_mainloop(server);
        vrpn_tracker_mainloop(tracker);
        vrpn_server_wait(server, 1);
    }
    CHECK(seen.poses == before);
    CHECK(seen.velocities > velocities_before);

    /* Another thread may not touch the handle: refused, and the error is that thread's. */
    struct other_thread other;
    memset(&other, 0, sizeof other);
    other.tracker = tracker;
    VrpnStatus mine = vrpn_last_error_status();
    pthread_t thread;
    CHECK(pthread_create(&thread, NULL, use_from_other_thread, &other) == 0);
    CHECK(pthread_join(thread, NULL) == 0);
    CHECK(other.status == VRPN_STATUS_WRONG_THREAD);
    CHECK(other.last_status == VRPN_STATUS_WRONG_THREAD);
    CHECK(strstr(other.text, "thread") != NULL);
    CHECK(vrpn_last_error_status() == mine);

    /* A callback may free the remote whose mainloop runs it. */
    struct self_free sf = {NULL, 0, VRPN_STATUS_INTERNAL};
    sf.tracker = vrpn_tracker_open(name);
    CHECK(sf.tracker != NULL);
    CHECK(vrpn_tracker_on_pose(sf.tracker, free_self, &sf, NULL) == VRPN_STATUS_OK);
    deadline = now_seconds() + 5.0;
    VrpnStatus last = VRPN_STATUS_OK;
    while (sf.calls == 0 && now_seconds() < deadline) {
        vrpn_tracker_server_report_pose(ts, 0, NULL, pos, quat);
        vrpn_server_mainloop(server);
        last = vrpn_tracker_mainloop(sf.tracker);
        CHECK(last == VRPN_STATUS_OK);
        vrpn_server_wait(server, 1);
    }
    CHECK(sf.calls == 1 && sf.status == VRPN_STATUS_OK);

    /* Handles may be freed in any order: the server first. */
    CHECK(vrpn_server_free(server) == VRPN_STATUS_OK);
    CHECK(vrpn_tracker_server_report_pose(ts, 1, NULL, pos, quat) == VRPN_STATUS_OK);
    CHECK(vrpn_tracker_server_free(ts) == VRPN_STATUS_OK);
    CHECK(vrpn_button_server_free(bs) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_server_free(as) == VRPN_STATUS_OK);
    CHECK(vrpn_dial_server_free(ds) == VRPN_STATUS_OK);
    CHECK(vrpn_dial_free(dial) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_free(analog) == VRPN_STATUS_OK);
    CHECK(vrpn_button_free(button) == VRPN_STATUS_OK);
    CHECK(vrpn_tracker_free(tracker) == VRPN_STATUS_OK);

    printf("api_checks: %d checks passed\n", checks);
    return 0;
}
