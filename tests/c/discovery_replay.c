/*
 * Checks the connection-level C calls: sender discovery and text messages from a vrpn_server
 * (argv[1] = "127.0.0.1:PORT", serving Tracker0 and Text0 saying "hello from the server"),
 * and the replay controls on a log of Tracker0 (argv[2]: 20 poses 25 ms apart, x = 0 .. 19).
 * Run by tests/capi.rs; prints "discovery_replay: N checks passed" or the failed check.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
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

struct seen {
    int texts;
    VrpnTextMessage text;
    int names;
    int tracker_named, text_named;
    int poses;
    double last_x;
};

static void on_text(void *u, const VrpnTextMessage *m)
{
    struct seen *s = (struct seen *)u;
    s->texts++;
    s->text = *m;
}

static void on_name(void *u, const char *name)
{
    struct seen *s = (struct seen *)u;
    s->names++;
    if (strcmp(name, "Tracker0") == 0)
        s->tracker_named = 1;
    if (strcmp(name, "Text0") == 0)
        s->text_named = 1;
}

static void on_pose(void *u, const VrpnTrackerPose *p)
{
    struct seen *s = (struct seen *)u;
    s->poses++;
    s->last_x = p->pos[0];
}

int main(int argc, char **argv)
{
    CHECK(argc == 3);
    vrpn_set_default_printer(2);
    struct seen seen;
    memset(&seen, 0, sizeof seen);

    /* ---- a live server: its device names and a device's texts */
    char name[256];
    snprintf(name, sizeof name, "Text0@%s", argv[1]);
    VrpnText *text = vrpn_text_open(name);
    VrpnConnection *conn = vrpn_connection_open(name); /* shared with the text receiver */
    CHECK(text != NULL && conn != NULL);
    CHECK(vrpn_connection_open(NULL) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_NULL_ARGUMENT);
    uint64_t text_id = 0, name_id = 0;
    CHECK(vrpn_text_on_message(text, on_text, &seen, &text_id) == VRPN_STATUS_OK);
    CHECK(vrpn_connection_on_peer_sender(conn, on_name, &seen, &name_id) == VRPN_STATUS_OK);
    CHECK(vrpn_connection_on_peer_sender(conn, NULL, &seen, NULL) == VRPN_STATUS_NULL_ARGUMENT);
    CHECK(vrpn_connection_is_replay(conn) == 0);
    CHECK(vrpn_connection_replay_reset(conn) == VRPN_STATUS_UNSUPPORTED);
    CHECK(strstr(vrpn_last_error(), "not a replay") != NULL);
    double deadline = now_seconds() + 10.0;
    while ((seen.texts == 0 || !seen.tracker_named || !seen.text_named) &&
           now_seconds() < deadline) {
        CHECK(vrpn_connection_mainloop(conn) == VRPN_STATUS_OK);
        struct timespec nap = {0, 1000000};
        nanosleep(&nap, NULL);
    }
    CHECK(seen.texts > 0);
    CHECK(strcmp(seen.text.text, "hello from the server") == 0);
    CHECK(seen.text.severity == 0 && seen.text.level == 0 && seen.text.time.sec > 0);
    CHECK(vrpn_text_received(text) >= 1);
    CHECK(seen.tracker_named && seen.text_named);
    CHECK(vrpn_connection_state(conn) == VRPN_CONNECTION_STATE_CONNECTED);

    /* The names again, by polling. */
    int n = vrpn_connection_peer_sender_count(conn);
    CHECK(n >= 2);
    int tracker_listed = 0, text_listed = 0;
    for (int i = 0; i < n; i++) {
        char sender[VRPN_NAME_CAPACITY];
        int len = vrpn_connection_peer_sender(conn, i, sender, sizeof sender);
        CHECK(len > 0 && (size_t)len == strlen(sender));
        tracker_listed |= strcmp(sender, "Tracker0") == 0;
        text_listed |= strcmp(sender, "Text0") == 0;
    }
    CHECK(tracker_listed && text_listed);
    char tiny[3] = {'x', 'y', 'z'};
    CHECK(vrpn_connection_peer_sender(conn, 0, tiny, sizeof tiny) == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(tiny[0] == 'x');
    CHECK(vrpn_connection_peer_sender(conn, n, tiny, sizeof tiny) == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_connection_peer_sender(conn, 0, NULL, 64) == VRPN_STATUS_NULL_ARGUMENT);

    /* Removed callbacks are not called again; freeing the connection handle leaves the
     * remote working (and never calls a freed handle's callbacks). */
    CHECK(vrpn_text_remove_callback(text, text_id) == VRPN_STATUS_OK);
    CHECK(vrpn_connection_remove_callback(conn, name_id) == VRPN_STATUS_OK);
    CHECK(vrpn_connection_remove_callback(conn, name_id) == VRPN_STATUS_INVALID_ARGUMENT);
    int texts = seen.texts;
    CHECK(vrpn_connection_free(conn) == VRPN_STATUS_OK);
    deadline = now_seconds() + 0.3;
    while (now_seconds() < deadline)
        CHECK(vrpn_text_mainloop(text) == VRPN_STATUS_OK);
    CHECK(seen.texts == texts);
    CHECK(vrpn_text_received(text) > texts); /* still receiving, no callback */
    CHECK(vrpn_text_free(text) == VRPN_STATUS_OK);

    /* ---- a replay: rate, seek, play-to, play-one, reset, end */
    snprintf(name, sizeof name, "Tracker0@file:%s", argv[2]);
    VrpnTracker *tracker = vrpn_tracker_open(name);
    VrpnConnection *log = vrpn_connection_open(name);
    CHECK(tracker != NULL && log != NULL);
    CHECK(vrpn_tracker_on_pose(tracker, on_pose, &seen, NULL) == VRPN_STATUS_OK);
    CHECK(vrpn_connection_is_replay(log) == 1);
    double rate = 0.0, length = 0.0, position = -1.0;
    CHECK(vrpn_connection_replay_rate(log, &rate) == VRPN_STATUS_OK && rate == 1.0);
    CHECK(vrpn_connection_replay_set_rate(log, 0.0) == VRPN_STATUS_OK);
    CHECK(vrpn_connection_replay_set_rate(log, -1.0) == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_connection_replay_set_rate(log, NAN) == VRPN_STATUS_INVALID_ARGUMENT);
    for (int i = 0; i < 50; i++)
        CHECK(vrpn_connection_mainloop(log) == VRPN_STATUS_OK);
    CHECK(seen.poses == 0); /* paused */
    CHECK(vrpn_connection_replay_length(log, &length) == VRPN_STATUS_OK);
    CHECK(fabs(length - 0.475) < 0.01);
    VrpnTimeVal start;
    CHECK(vrpn_connection_replay_start_time(log, &start) == VRPN_STATUS_OK && start.sec > 0);
    CHECK(vrpn_connection_replay_start_time(log, NULL) == VRPN_STATUS_NULL_ARGUMENT);

    CHECK(vrpn_connection_replay_seek(log, 0.25) == VRPN_STATUS_OK);
    CHECK(seen.poses == 0); /* a seek delivers nothing in between */
    CHECK(vrpn_connection_replay_play_to(log, 0.3) == VRPN_STATUS_OK);
    CHECK(seen.poses >= 2 && seen.last_x >= 11.0 && seen.last_x <= 12.0);
    CHECK(vrpn_connection_replay_position(log, &position) == VRPN_STATUS_OK);
    CHECK(fabs(position - 0.3) < 0.03);
    CHECK(vrpn_connection_replay_eof(log) == 0);
    CHECK(vrpn_connection_replay_play_to(log, length) == VRPN_STATUS_OK);
    CHECK(seen.last_x == 19.0);
    CHECK(vrpn_connection_replay_seek(log, 1000.0) == VRPN_STATUS_NO_DATA);
    CHECK(vrpn_connection_replay_seek(log, -1.0) == VRPN_STATUS_INVALID_ARGUMENT);
    CHECK(vrpn_connection_replay_play_to(log, INFINITY) == VRPN_STATUS_INVALID_ARGUMENT);

    CHECK(vrpn_connection_replay_reset(log) == VRPN_STATUS_OK);
    seen.poses = 0;
    while (seen.poses == 0)
        CHECK(vrpn_connection_replay_play_one(log) == VRPN_STATUS_OK);
    CHECK(seen.poses == 1 && seen.last_x == 0.0);
    int plays = 0;
    VrpnStatus s;
    while ((s = vrpn_connection_replay_play_one(log)) == VRPN_STATUS_OK)
        plays++;
    CHECK(s == VRPN_STATUS_NO_DATA && plays >= 19);
    CHECK(seen.poses == 20 && vrpn_connection_replay_eof(log) == 1);

    CHECK(vrpn_connection_free(log) == VRPN_STATUS_OK);
    CHECK(vrpn_tracker_free(tracker) == VRPN_STATUS_OK);
    printf("discovery_replay: %d checks passed\n", checks);
    return 0;
}
