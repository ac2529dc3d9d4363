/*
 * A VRPN tracker server in C: two sensors reported 100 times a second on a port of its own.
 *
 * Build against the static library (no run-time dependency on libvrpn.so):
 *   cc -Iinclude examples/c/tracker_server.c target/release/libvrpn.a \
 *      -lpthread -ldl -lm -lrt -lutil -o tracker_server
 * Run:
 *   ./tracker_server [PORT] [SECONDS]      (PORT 0 picks a free one; SECONDS 0 runs forever)
 * and read it with any VRPN client: `vrpn_print_devices Tracker0@localhost:PORT`.
 *
 * Sensor s at frame k is at (s + 1, -(s + 1), k / 1000) metres, turned about z by the
 * quaternion (0, 0, 0.6, 0.8).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "vrpn.h"

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(int argc, char **argv)
{
    int port = argc > 1 ? atoi(argv[1]) : 3883;
    double seconds = argc > 2 ? atof(argv[2]) : 0.0;
    if (port < 0 || port > 65535) {
        fprintf(stderr, "port %d is not 0..65535\n", port);
        return 2;
    }

    VrpnServer *server = vrpn_server_open((uint16_t)port, NULL);
    if (server == NULL) {
        fprintf(stderr, "cannot serve port %d: %s\n", port, vrpn_last_error());
        return 2;
    }
    VrpnTrackerServer *tracker = vrpn_tracker_server_new(server, "Tracker0", 2);
    if (tracker == NULL) {
        fprintf(stderr, "cannot make Tracker0: %s\n", vrpn_last_error());
        vrpn_server_free(server);
        return 2;
    }
    printf("listening on port %d\n", vrpn_server_port(server));
    fflush(stdout);

    const double quat[4] = {0.0, 0.0, 0.6, 0.8};
    double start = now_seconds(), next = start;
    for (long k = 0; seconds <= 0.0 || now_seconds() - start < seconds;) {
        if (now_seconds() >= next) {
            for (int s = 0; s < 2; s++) {
                double pos[3] = {s + 1.0, -(s + 1.0), k / 1000.0};
                /* NULL time: stamped with the current time. */
                if (vrpn_tracker_server_report_pose(tracker, s, NULL, pos, quat) != VRPN_STATUS_OK)
                    fprintf(stderr, "report: %s\n", vrpn_last_error());
            }
            k++;
            next += 0.01;
        }
        vrpn_server_mainloop(server);
        /* Sleeps until a client sends something or 1 ms passes: no busy loop. */
        vrpn_server_wait(server, 1);
    }

    vrpn_tracker_server_free(tracker);
    vrpn_server_free(server);
    return 0;
}
