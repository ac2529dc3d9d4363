/*
 * Counts heap allocations made through the C ABI in steady state: a server with a tracker,
 * button, analog and dial, remotes with callbacks and polling, all in this process on
 * 127.0.0.1. The allocation functions are interposed here, so every malloc of the library
 * (shared or static) comes through them. Run by tests/capi.rs; exits 1 if any pass after
 * the warm-up allocated.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "vrpn.h"

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void *__libc_memalign(size_t, size_t);
extern void __libc_free(void *);

/* counting 0: set-up and warm-up (counted too, to prove the interposition works); 1: steady. */
static int counting = 0;
static long allocations = 0, setup_allocations = 0;

void *malloc(size_t n)
{
    allocations += counting;
    setup_allocations += !counting;
    return __libc_malloc(n);
}
void *calloc(size_t n, size_t m)
{
    allocations += counting;
    setup_allocations += !counting;
    return __libc_calloc(n, m);
}
void *realloc(void *p, size_t n)
{
    allocations += counting;
    setup_allocations += !counting;
    return __libc_realloc(p, n);
}
void *memalign(size_t a, size_t n)
{
    allocations += counting;
    setup_allocations += !counting;
    return __libc_memalign(a, n);
}
void *aligned_alloc(size_t a, size_t n)
{
    allocations += counting;
    setup_allocations += !counting;
    return __libc_memalign(a, n);
}
int posix_memalign(void **out, size_t a, size_t n)
{
    allocations += counting;
    setup_allocations += !counting;
    void *p = __libc_memalign(a, n);
    if (p == NULL)
        return ENOMEM;
    *out = p;
    return 0;
}
void free(void *p)
{
    __libc_free(p);
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static long received[4];
static void on_pose(void *u, const VrpnTrackerPose *p) { (void)u, (void)p, received[0]++; }
static void on_change(void *u, const VrpnButtonChange *c) { (void)u, (void)c, received[1]++; }
static void on_report(void *u, const VrpnAnalogReport *r) { (void)u, (void)r, received[2]++; }
static void on_update(void *u, const VrpnDialUpdate *d) { (void)u, (void)d, received[3]++; }

#define OK(call)                                                                             \
    do {                                                                                     \
        if ((call) < 0) {                                                                    \
            fprintf(stderr, "%s:%d: %s: %s\n", __FILE__, __LINE__, #call, vrpn_last_error()); \
            exit(2);                                                                         \
        }                                                                                    \
    } while (0)

int main(int argc, char **argv)
{
    double warmup = argc > 1 ? atof(argv[1]) : 1.5, measure = argc > 2 ? atof(argv[2]) : 3.0;
    VrpnServer *server = vrpn_server_open(0, "127.0.0.1");
    if (server == NULL) {
        fprintf(stderr, "server: %s\n", vrpn_last_error());
        return 2;
    }
    VrpnTrackerServer *ts = vrpn_tracker_server_new(server, "Dev0", 2);
    VrpnButtonServer *bs = vrpn_button_server_new(server, "Dev0", 4);
    VrpnAnalogServer *as = vrpn_analog_server_new(server, "Dev0", 3);
    VrpnDialServer *ds = vrpn_dial_server_new(server, "Dev0", 1);
    char name[64];
    snprintf(name, sizeof name, "Dev0@127.0.0.1:%d", vrpn_server_port(server));
    VrpnTracker *t = vrpn_tracker_open(name);
    VrpnButton *b = vrpn_button_open(name);
    VrpnAnalog *a = vrpn_analog_open(name);
    VrpnDial *d = vrpn_dial_open(name);
    if (!(ts && bs && as && ds && t && b && a && d)) {
        fprintf(stderr, "setup: %s\n", vrpn_last_error());
        return 2;
    }
    OK(vrpn_tracker_on_pose(t, on_pose, NULL, NULL));
    OK(vrpn_button_on_change(b, on_change, NULL, NULL));
    OK(vrpn_analog_on_report(a, on_report, NULL, NULL));
    OK(vrpn_dial_on_update(d, on_update, NULL, NULL));

    const double quat[4] = {0.0, 0.0, 0.0, 1.0};
    VrpnTrackerPose pose;
    VrpnAnalogReport report;
    double revolutions;
    int32_t states[4];
    long passes = 0, k = 0, at_start[4] = {0, 0, 0, 0};
    double start = now_seconds();
    while (now_seconds() - start < warmup + measure) {
        if (!counting && now_seconds() - start >= warmup) {
            memcpy(at_start, received, sizeof at_start);
            counting = 1;
        }
        if (vrpn_server_connected_clients(server) > 0) {
            double pos[3] = {k * 0.001, 0.0, 0.0};
            OK(vrpn_tracker_server_report_pose(ts, (int)(k % 2), NULL, pos, quat));
            OK(vrpn_button_server_set(bs, (int)(k % 4), (int)(k / 4 % 2)));
            OK(vrpn_button_server_report_changes(bs, NULL));
            OK(vrpn_analog_server_set(as, 0, (double)k));
            OK(vrpn_analog_server_report(as, NULL));
            OK(vrpn_dial_server_add(ds, 0, 0.01));
            OK(vrpn_dial_server_report_changes(ds, NULL));
            k++;
        }
        OK(vrpn_server_mainloop(server));
        OK(vrpn_tracker_mainloop(t));
        OK(vrpn_button_mainloop(b));
        OK(vrpn_analog_mainloop(a));
        OK(vrpn_dial_mainloop(d));
        vrpn_tracker_pose(t, 0, &pose);
        vrpn_analog_latest(a, &report);
        vrpn_button_states(b, states, 4);
        vrpn_dial_rotation(d, 0, &revolutions);
        vrpn_tracker_connection_state(t);
        passes += counting;
        OK(vrpn_server_wait(server, 1));
    }
    counting = 0;
    long got[4];
    for (int i = 0; i < 4; i++)
        got[i] = received[i] - at_start[i];
    printf("steady_alloc: %ld allocations in set-up and warm-up, %ld in %ld passes; received %ld poses, %ld changes, "
           "%ld analog reports, %ld dial updates\n",
           setup_allocations, allocations, passes, got[0], got[1], got[2], got[3]);

    vrpn_tracker_free(t);
    vrpn_button_free(b);
    vrpn_analog_free(a);
    vrpn_dial_free(d);
    vrpn_tracker_server_free(ts);
    vrpn_button_server_free(bs);
    vrpn_analog_server_free(as);
    vrpn_dial_server_free(ds);
    vrpn_server_free(server);
    if (got[0] == 0 || got[1] == 0 || got[2] == 0 || got[3] == 0 || setup_allocations == 0)
        return 2; /* nothing flowed or nothing was seen: the count would prove nothing */
    return allocations == 0 ? 0 : 1;
}
