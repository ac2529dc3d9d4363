/*
 * An imager client in C: learn the image's size from the description, copy every region of
 * channel 0 into an 8-bit image (converting 16-bit and float pixels), and print a checksum
 * of the image at the end of each frame.
 *
 * Build (after `cargo rustc --release --lib --no-default-features --features capi
 *        --crate-type cdylib,staticlib`):
 *   cc -Iinclude examples/c/imager_client.c -Ltarget/release -lvrpn \
 *      -Wl,-rpath,$PWD/target/release -o imager_client
 * Run against an imager server (`cargo run --example imager_server -- 3883`):
 *   ./imager_client TestImage@localhost [FRAMES] [SECONDS]
 *
 * Exits 0 once FRAMES frames ended (default 5), 1 if SECONDS (default 10) pass first, 2 on a
 * bad argument or a library error.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "vrpn.h"

struct image {
    unsigned char *pixels;
    size_t cols, rows;
    long frames, regions, bad;
};

static void on_description(void *userdata, const VrpnImagerDescription *d)
{
    struct image *img = (struct image *)userdata;
    printf("description %dx%dx%d channels=%d\n", d->cols, d->rows, d->depth, d->channels);
    free(img->pixels);
    img->cols = d->cols > 0 ? (size_t)d->cols : 0;
    img->rows = d->rows > 0 ? (size_t)d->rows : 0;
    img->pixels = calloc(img->cols * img->rows + 1, 1);
}

static void on_region(void *userdata, const VrpnImagerRegion *r)
{
    struct image *img = (struct image *)userdata;
    if (r->channel != 0 || img->pixels == NULL)
        return;
    VrpnImagerLayout layout = {1, img->cols, img->cols * img->rows, 0, 1};
    if (vrpn_imager_region_read_u8(r, img->pixels, img->cols * img->rows, &layout) == VRPN_STATUS_OK)
        img->regions++;
    else
        img->bad++;
}

static void on_end_frame(void *userdata, const VrpnImagerFrame *f)
{
    struct image *img = (struct image *)userdata;
    unsigned long sum = 0;
    for (size_t i = 0; i < img->cols * img->rows; i++)
        sum += img->pixels[i];
    img->frames++;
    printf("frame seq=%llu sum=%lu regions=%ld\n", (unsigned long long)f->seq, sum, img->regions);
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(int argc, char **argv)
{
    const char *name = argc > 1 ? argv[1] : "TestImage@localhost";
    long want = argc > 2 ? atol(argv[2]) : 5;
    double seconds = argc > 3 ? atof(argv[3]) : 10.0;
    struct image img = {NULL, 0, 0, 0, 0, 0};

    VrpnImager *imager = vrpn_imager_open(name);
    if (imager == NULL) {
        fprintf(stderr, "cannot open %s: %s\n", name, vrpn_last_error());
        return 2;
    }
    if (vrpn_imager_on_description(imager, on_description, &img, NULL) != VRPN_STATUS_OK ||
        vrpn_imager_on_region(imager, on_region, &img, NULL) != VRPN_STATUS_OK ||
        vrpn_imager_on_end_frame(imager, on_end_frame, &img, NULL) != VRPN_STATUS_OK) {
        fprintf(stderr, "cannot register callbacks: %s\n", vrpn_last_error());
        return 2;
    }
    double end = now_seconds() + seconds;
    while (img.frames < want && now_seconds() < end) {
        if (vrpn_imager_mainloop(imager) != VRPN_STATUS_OK) {
            fprintf(stderr, "mainloop: %s\n", vrpn_last_error());
            return 2;
        }
        struct timespec ts = {0, 1000000L};
        nanosleep(&ts, NULL);
    }
    VrpnImagerChannel ch;
    if (vrpn_imager_channel(imager, 0, &ch) == VRPN_STATUS_OK)
        printf("channel 0 name=%s units=%s scale=%g\n", ch.name, ch.units, ch.scale);
    printf("done frames=%ld bad=%ld\n", img.frames, img.bad);
    vrpn_imager_free(imager);
    free(img.pixels);
    return img.frames >= want ? 0 : 1;
}
