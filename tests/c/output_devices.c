/*
 * Analog_Output, Poser, ForceDevice and the text sender through the C ABI, both sides in one
 * program: a server on a free port serves them, remotes on 127.0.0.1 drive them, and every
 * request and report is checked field by field. Run by tests/capi.rs; prints
 * "output_devices: N checks passed" or the failed check.
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
    int ao_requests;
    VrpnAnalogOutputValues ao;
    int poses;
    VrpnPoserRequest pose;
    int fields;
    VrpnForceFieldRequest field;
    int forces, scps, errors, texts;
    VrpnForceReport force;
    VrpnScpReport scp;
    VrpnForceErrorReport error;
    VrpnTextMessage text;
};

static void on_ao(void *u, const VrpnAnalogOutputValues *v)
{
    struct seen *s = (struct seen *)u;
    s->ao_requests++;
    s->ao = *v;
}

static void on_pose(void *u, const VrpnPoserRequest *r)
{
    struct seen *s = (struct seen *)u;
    s->poses++;
    s->pose = *r;
}

static void on_field(void *u, const VrpnForceFieldRequest *f)
{
    struct seen *s = (struct seen *)u;
    /* The stop (all zero) may come before or after the field: keep the field. */
    if (f->radius != 0.0f) {
        s->fields++;
        s->field = *f;
    }
}

static void on_force(void *u, const VrpnForceReport *r)
{
    struct seen *s = (struct seen *)u;
    s->forces++;
    s->force = *r;
}

static void on_scp(void *u, const VrpnScpReport *r)
{
    struct seen *s = (struct seen *)u;
    s->scps++;
    s->scp = *r;
}

static void on_error(void *u, const VrpnForceErrorReport *r)
{
    struct seen *s = (struct seen *)u;
    s->errors++;
    s->error = *r;
}

static void on_text(void *u, const VrpnTextMessage *m)
{
    struct seen *s = (struct seen *)u;
    s->texts++;
    s->text = *m;
}

struct rig {
    VrpnServer *server;
    VrpnAnalogOutput *ao;
    VrpnPoser *poser;
    VrpnForceDevice *fd;
    VrpnText *text;
};

static void pass(struct rig *r)
{
    CHECK(vrpn_server_mainloop(r->server) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_output_mainloop(r->ao) == VRPN_STATUS_OK);
    CHECK(vrpn_poser_mainloop(r->poser) == VRPN_STATUS_OK);
    CHECK(vrpn_force_device_mainloop(r->fd) == VRPN_STATUS_OK);
    CHECK(vrpn_text_mainloop(r->text) == VRPN_STATUS_OK);
    struct timespec pause = {0, 500000};
    nanosleep(&pause, NULL);
}

/* Runs passes until `*flag` is non-zero, for at most 10 s. */
#define PUMP_UNTIL(rig, cond)                                                                \
    do {                                                                                     \
        double until = now_seconds() + 10.0;                                                 \
        while (!(cond) && now_seconds() < until)                                             \
            pass(rig);                                                                       \
        CHECK(cond);                                                                         \
    } while (0)

int main(void)
{
    struct seen s;
    memset(&s, 0, sizeof s);
    struct rig r;
    r.server = vrpn_server_open(0, "127.0.0.1");
    CHECK(r.server != NULL);
    int port = vrpn_server_port(r.server);
    CHECK(port > 0);

    VrpnAnalogOutputServer *aos = vrpn_analog_output_server_new(r.server, "Out0", 3);
    CHECK(aos != NULL);
    CHECK(vrpn_analog_output_server_new(r.server, "Out1", 129) == NULL);
    CHECK(vrpn_last_error_status() == VRPN_STATUS_INVALID_ARGUMENT);
    VrpnPoserServer *ps = vrpn_poser_server_new(r.server, "Poser0");
    CHECK(ps != NULL);
    VrpnForceDeviceServer *fds = vrpn_force_device_server_new(r.server, "Phantom0");
    CHECK(fds != NULL);
    VrpnTextSender *ts = vrpn_text_sender_new(r.server, "Phantom0");
    CHECK(ts != NULL);
    uint64_t id = 0;
    CHECK(vrpn_analog_output_server_on_request(aos, on_ao, &s, &id) == VRPN_STATUS_OK);
    CHECK(id == 1);
    CHECK(vrpn_poser_server_on_request(ps, on_pose, &s, &id) == VRPN_STATUS_OK);
    CHECK(vrpn_force_device_server_on_force_field(fds, on_field, &s, &id) == VRPN_STATUS_OK);

    char name[64];
    snprintf(name, sizeof name, "Out0@127.0.0.1:%d", port);
    r.ao = vrpn_analog_output_open(name);
    snprintf(name, sizeof name, "Poser0@127.0.0.1:%d", port);
    r.poser = vrpn_poser_open(name);
    snprintf(name, sizeof name, "Phantom0@127.0.0.1:%d", port);
    r.fd = vrpn_force_device_open(name);
    r.text = vrpn_text_open(name);
    CHECK(r.ao && r.poser && r.fd && r.text);
    CHECK(vrpn_force_device_on_force(r.fd, on_force, &s, NULL) == VRPN_STATUS_OK);
    CHECK(vrpn_force_device_on_scp(r.fd, on_scp, &s, NULL) == VRPN_STATUS_OK);
    CHECK(vrpn_force_device_on_error(r.fd, on_error, &s, NULL) == VRPN_STATUS_OK);
    CHECK(vrpn_text_on_message(r.text, on_text, &s, NULL) == VRPN_STATUS_OK);

    PUMP_UNTIL(&r, vrpn_analog_output_connection_state(r.ao) == VRPN_CONNECTION_STATE_CONNECTED
                       && vrpn_poser_connection_state(r.poser) == VRPN_CONNECTION_STATE_CONNECTED
                       && vrpn_force_device_connection_state(r.fd)
                              == VRPN_CONNECTION_STATE_CONNECTED);
    PUMP_UNTIL(&r, vrpn_analog_output_num_channels(r.ao) == 3);

    /* Analog output: a request sets the server's values. */
    const double values[2] = {0.25, -0.5};
    CHECK(vrpn_analog_output_request_channels(r.ao, values, 2) == VRPN_STATUS_OK);
    PUMP_UNTIL(&r, s.ao_requests == 1);
    CHECK(s.ao.num_channels == 3 && s.ao.channels[0] == 0.25 && s.ao.channels[1] == -0.5);
    CHECK(vrpn_analog_output_request_channel(r.ao, 2, 7.0) == VRPN_STATUS_OK);
    PUMP_UNTIL(&r, s.ao_requests == 2);
    double out[8];
    CHECK(vrpn_analog_output_server_values(aos, out, 8) == 3);
    CHECK(out[0] == 0.25 && out[1] == -0.5 && out[2] == 7.0);
    CHECK(vrpn_analog_output_request_channels(r.ao, NULL, 2) == VRPN_STATUS_NULL_ARGUMENT);

    /* Poser: absolute, then relative. */
    const double pos[3] = {0.5, 0.25, -0.125}, quat[4] = {0.0, 0.0, 0.0, 1.0};
    CHECK(vrpn_poser_request_pose(r.poser, NULL, pos, quat, 0) == VRPN_STATUS_OK);
    PUMP_UNTIL(&r, s.poses == 1);
    CHECK(s.pose.relative == 0 && s.pose.pos[0] == 0.5 && s.pose.pos[2] == -0.125);
    const double step[3] = {0.125, 0.0, 0.0};
    CHECK(vrpn_poser_request_pose(r.poser, NULL, step, quat, 1) == VRPN_STATUS_OK);
    PUMP_UNTIL(&r, s.poses == 2);
    CHECK(s.pose.relative == 1 && s.pose.pos[0] == 0.625);

    /* Force device: a field up, then reports down. */
    const float origin[3] = {0.0f, 0.1f, 0.0f}, force[3] = {1.0f, 0.0f, 0.0f};
    const float jac[9] = {-1, 0, 0, 0, -1, 0, 0, 0, -2};
    CHECK(vrpn_force_device_send_force_field(r.fd, origin, force, jac, 0.5f) == VRPN_STATUS_OK);
    PUMP_UNTIL(&r, s.fields == 1);
    CHECK(s.field.origin[1] == 0.1f && s.field.jacobian[8] == -2.0f && s.field.radius == 0.5f);
    const double f3[3] = {0.5, -1.0, 2.0}, p3[3] = {0.1, 0.2, 0.3};
    CHECK(vrpn_force_device_server_report_force(fds, NULL, f3) == VRPN_STATUS_OK);
    CHECK(vrpn_force_device_server_report_scp(fds, NULL, p3, quat) == VRPN_STATUS_OK);
    CHECK(vrpn_force_device_server_send_error(fds, 3) == VRPN_STATUS_OK);
    CHECK(vrpn_text_sender_send(ts, "contact lost", 1, 7, NULL) == VRPN_STATUS_OK);
    PUMP_UNTIL(&r, s.forces >= 1 && s.scps >= 1 && s.errors >= 1 && s.texts >= 1);
    CHECK(s.force.force[0] == 0.5 && s.force.force[2] == 2.0);
    CHECK(s.scp.pos[1] == 0.2 && s.scp.quat[3] == 1.0);
    CHECK(s.error.code == 3);
    CHECK(s.text.severity == 1 && s.text.level == 7 && strcmp(s.text.text, "contact lost") == 0);

    CHECK(vrpn_force_device_free(r.fd) == VRPN_STATUS_OK);
    CHECK(vrpn_poser_free(r.poser) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_output_free(r.ao) == VRPN_STATUS_OK);
    CHECK(vrpn_text_free(r.text) == VRPN_STATUS_OK);
    CHECK(vrpn_text_sender_free(ts) == VRPN_STATUS_OK);
    CHECK(vrpn_force_device_server_free(fds) == VRPN_STATUS_OK);
    CHECK(vrpn_poser_server_free(ps) == VRPN_STATUS_OK);
    CHECK(vrpn_analog_output_server_free(aos) == VRPN_STATUS_OK);
    CHECK(vrpn_server_free(r.server) == VRPN_STATUS_OK);
    printf("output_devices: %d checks passed\n", checks);
    return 0;
}
