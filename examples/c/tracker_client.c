/*
 * The complete VRPN client in C: open a tracker, register a pose callback, call mainloop
 * once per frame, and read the latest pose by polling as well.
 *
 * Build (after `cargo rustc --release --lib --no-default-features --features capi
 *        --crate-type cdylib,staticlib`):
 *   cc -Iinclude examples/c/tracker_client.c -Ltarget/release -lvrpn \
 *      -Wl,-rpath,$PWD/target/release -o tracker_client
 * Run against a server (`vrpn_server -f vrpn.cfg.sample`):
 *   ./tracker_client Tracker0@localhost [REPORTS] [SECONDS]
 *
 * Prints one line per pose received; exits 0 once REPORTS poses arrived (default 10), 1 if
 * SECONDS (default 10) pass first, 2 on a bad argument or a library error.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "vrpn.h"

/* What the callback updates, reached through its userdata pointer. */
struct counts {
    long poses;
    long per_sensor[2];
};

static void on_pose(void *userdata, const VrpnTrackerPose *p)
{
    struct counts *c = (struct counts *)userdata;
    c->poses++;
    if (p->sensor >= 0 && p->sensor < 2)
        c->per_sensor[p->sensor]++;
    printf("pose sensor=%d time=%lld.%06lld pos=%.6f,%.6f,%.6f quat=%.6f,%.6f,%.6f,%.6f\n",
           p->sensor, (long long)p->time.sec, (long long)p->time.usec, p->pos[0], p->pos[1],
           p->pos[2], p->quat[0], p->quat[1], p->quat[2], p->quat[3]);
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void sleep_ms(long ms)
{
    struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

int main(int argc, char **argv)
{
    const char *name = argc > 1 ? argv[1] : "Tracker0@localhost";
    long want = argc > 2 ? atol(argv[2]) : 10;
    double seconds = argc > 3 ? atof(argv[3]) : 10.0;
    struct counts counts = {0, {0, 0}};

    printf("vrpn %s (ABI %d)\n", vrpn_version(), vrpn_abi_version());
    VrpnTracker *tracker = vrpn_tracker_open(name);
    if (tracker == NULL) {
        fprintf(stderr, "cannot open %s: %s\n", name, vrpn_last_error());
        return 2;
    }
    if (vrpn_tracker_on_pose(tracker, on_pose, &counts, NULL) != VRPN_STATUS_OK) {
        fprintf(stderr, "on_pose: %s\n", vrpn_last_error());
        vrpn_tracker_free(tracker);
        return 2;
    }

    double deadline = now_seconds() + seconds;
    while (counts.poses < want && now_seconds() < deadline) {
        if (vrpn_tracker_mainloop(tracker) != VRPN_STATUS_OK) {
            fprintf(stderr, "mainloop: %s\n", vrpn_last_error());
            vrpn_tracker_free(tracker);
            return 2;
        }
        /* A renderer draws its frame here. */
        sleep_ms(5);
    }

    /* Polling: the latest pose of sensor 0, copied into our own struct. */
    VrpnTrackerPose latest;
    if (vrpn_tracker_pose(tracker, 0, &latest) == VRPN_STATUS_OK)
        printf("latest sensor=0 pos=%.6f,%.6f,%.6f quat=%.6f,%.6f,%.6f,%.6f\n", latest.pos[0],
               latest.pos[1], latest.pos[2], latest.quat[0], latest.quat[1], latest.quat[2],
               latest.quat[3]);
    printf("state=%d sensors=%d poses=%ld\n", vrpn_tracker_connection_state(tracker),
           vrpn_tracker_sensor_count(tracker), counts.poses);

    vrpn_tracker_free(tracker);
    return counts.poses >= want ? 0 : 1;
}
