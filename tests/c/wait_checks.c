/*
 * Waiting without spinning through the C ABI: a tracker read with vrpn_tracker_wait, then
 * with the program's own poll() on vrpn_tracker_fd. Prints the poses received and the
 * thread's voluntary context switches (wake-ups) for each way; tests/capi.rs judges them.
 * Usage: wait_checks DEVICE@HOST:PORT SECONDS
 */
#define _GNU_SOURCE
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>

#include "vrpn.h"

static long poses = 0;

static void on_pose(void *userdata, const VrpnTrackerPose *p)
{
    (void)userdata;
    (void)p;
    poses++;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec / 1e9;
}

static long wakeups(void)
{
    struct rusage r;
    getrusage(RUSAGE_THREAD, &r);
    return r.ru_nvcsw;
}

#define CHECK(cond, ...)                                                                  \
    do {                                                                                  \
        if (!(cond)) {                                                                    \
            fprintf(stderr, "check failed at line %d: ", __LINE__);                       \
            fprintf(stderr, __VA_ARGS__);                                                 \
            fprintf(stderr, " (%s)\n", vrpn_last_error());                                \
            exit(1);                                                                      \
        }                                                                                 \
    } while (0)

int main(int argc, char **argv)
{
    CHECK(argc == 3, "usage: wait_checks DEVICE@HOST:PORT SECONDS");
    double seconds = atof(argv[2]);
    VrpnTracker *t = vrpn_tracker_open(argv[1]);
    CHECK(t != NULL, "open");
    CHECK(vrpn_tracker_on_pose(t, on_pose, NULL, NULL) == VRPN_STATUS_OK, "on_pose");

    /* Errors: a NULL handle. */
    CHECK(vrpn_tracker_wait(NULL, 0) == VRPN_STATUS_NULL_ARGUMENT
              || vrpn_tracker_wait(NULL, 0) == VRPN_STATUS_INVALID_HANDLE,
          "wait(NULL)");
    CHECK(vrpn_tracker_fd(NULL) < 0, "fd(NULL)");

    /* Connect and see the first poses. */
    double end = now() + 10;
    while (poses < 10) {
        CHECK(now() < end, "no poses within 10 s");
        int s = vrpn_tracker_wait(t, 100);
        CHECK(s == VRPN_STATUS_OK || s == VRPN_STATUS_NO_DATA, "wait returned %d", s);
        vrpn_tracker_mainloop(t);
    }

    /* 1. The library's blocking wait. */
    long p0 = poses, w0 = wakeups();
    double t0 = now();
    while (now() - t0 < seconds) {
        vrpn_tracker_wait(t, 100);
        vrpn_tracker_mainloop(t);
    }
    printf("wait poses=%ld wakeups=%ld\n", poses - p0, wakeups() - w0);

    /* 2. The program's own poll() on the descriptor. */
    int fd = vrpn_tracker_fd(t);
    CHECK(fd >= 0, "fd %d", fd);
    VrpnButton *b = vrpn_button_open(argv[1]); /* same location: same connection */
    CHECK(b != NULL && vrpn_button_fd(b) == fd, "a remote on the same connection has another fd");
    p0 = poses;
    w0 = wakeups();
    t0 = now();
    while (now() - t0 < seconds) {
        struct pollfd pfd = {.fd = fd, .events = POLLIN};
        poll(&pfd, 1, 100);
        vrpn_tracker_mainloop(t);
    }
    printf("fd poses=%ld wakeups=%ld\n", poses - p0, wakeups() - w0);

    /* An idle connection (nothing listens on port 9: only its retry deadlines) does not
     * spin: over half a second, a handful of waits at most. */
    VrpnTracker *idle = vrpn_tracker_open("Nothing@127.0.0.1:9");
    int rounds = 0;
    t0 = now();
    while (now() - t0 < 0.5) {
        int s = vrpn_tracker_wait(idle, 200);
        CHECK(s == VRPN_STATUS_OK || s == VRPN_STATUS_NO_DATA, "idle wait returned %d", s);
        vrpn_tracker_mainloop(idle);
        rounds++;
    }
    CHECK(rounds < 25, "%d waits in 0.5 s on an idle connection", rounds);

    VrpnServer *server = vrpn_server_open(0, NULL);
    CHECK(server != NULL && vrpn_server_fd(server) >= 0, "server fd");
    vrpn_server_free(server);
    vrpn_tracker_free(idle);
    vrpn_button_free(b);
    vrpn_tracker_free(t);
    printf("wait checks passed\n");
    return 0;
}
