/* test_support.h — what the test programs share, written once: loading and finishing scenes,
 * building BVHs and running the two passes on the device under test, each failing the running
 * test with the error message when it fails; the small options of the device tests; scratch
 * directories. Header-only (static inline functions); the scenes named here are the shipped
 * Cornell box and Bitterli's glass of water from ../shared/data (a missing file fails). */
#ifndef IDMR_TESTS_TEST_SUPPORT_H
#define IDMR_TESTS_TEST_SUPPORT_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/scene.h"
#include "device/bvh.h"
#include "device/program.h"
#include "device_test.h"
#include "io/mitsuba/mitsuba.h"
#include "passes/importance.h"
#include "passes/render.h"

#define CORNELL_SCENE "data/cornell/scene.xml"
#define GLASS_OF_WATER_SCENE "../shared/data/scenes/glass-of-water/scene-without-mesh000.xml"

/* A Mitsuba scene (its warnings silenced); fails the test if it does not load. */
static inline scene *test_load_scene(const char *path)
{
    error_clear();
    warn_silence(1);
    scene *s = mitsuba_load(path);
    warn_silence(0);
    if (!s)
        fail_msg("loading %s failed: %s", path, error_message());
    return s;
}

/* The mesh named `name`; fails the test if the scene has none. */
static inline const scene_mesh *test_find_mesh(const scene *s, const char *name)
{
    for (size_t m = 0; m < s->mesh_count; m++)
        if (strcmp(s->meshes[m].name, name) == 0)
            return &s->meshes[m];
    fail_msg("scene %s: no mesh '%s'", s->file, name);
    return NULL;
}

/* scene_finalize() on a scene built in code; returns s. */
static inline scene *test_finalize_scene(scene *s)
{
    if (scene_finalize(s))
        fail_msg("scene_finalize: %s", error_message());
    return s;
}

static inline void test_build_bvh(const scene *s, bvh *b)
{
    if (bvh_build(s, b))
        fail_msg("bvh_build: %s", error_message());
}

/* The options of a small run: `iterations` of `photons` paths each, the rest at its default. */
static inline void test_importance_options(importance_options *o, unsigned int iterations,
                                           unsigned int photons)
{
    importance_options_default(o);
    o->sppm.iterations = iterations;
    o->sppm.photons = photons;
}

static inline void test_render_options(render_options *o, unsigned int iterations,
                                       unsigned int photons)
{
    render_options_default(o);
    o->sppm.iterations = iterations;
    o->sppm.photons = photons;
}

/* b, or when b is NULL a BVH of s built into *own (free *own with bvh_free() either way). */
static inline const bvh *test_bvh_of(const scene *s, const bvh *b, bvh *own)
{
    memset(own, 0, sizeof *own);
    if (!b)
        test_build_bvh(s, own);
    return b ? b : own;
}

/* Runs the importance pass / the renderer on the device under test, on BVH b (NULL: one built
 * here). */
static inline void test_run_importance(const scene *s, const bvh *b, const importance_options *o,
                                       importance_result *r)
{
    bvh own;
    int status = importance_run(device_test_device(), s, test_bvh_of(s, b, &own), o, r);
    bvh_free(&own);
    if (status)
        fail_msg("importance_run: %s", error_message());
}

static inline void test_run_render(const scene *s, const bvh *b, const render_options *o,
                                   render_result *r)
{
    bvh own;
    int status = render_run(device_test_device(), s, test_bvh_of(s, b, &own), o, r);
    bvh_free(&own);
    if (status)
        fail_msg("render_run: %s", error_message());
}

/* Runs the importance pass with `io` (render = 0) or the renderer with `ro` on scene s and BVH b
 * on the device under test, the error cleared first, and frees the result; returns the run's
 * status, with the device bytes it allocated (geometry, BVH and buffers) in *allocated. */
static inline int test_run_either(int render, const scene *s, const bvh *b,
                                  const importance_options *io, const render_options *ro,
                                  uint64_t *allocated)
{
    importance_result ir;
    render_result rr;
    error_clear();
    int status = render ? render_run(device_test_device(), s, b, ro, &rr)
                        : importance_run(device_test_device(), s, b, io, &ir);
    const sppm_summary *run = render ? &rr.sppm : &ir.sppm;
    *allocated = run->geometry_bytes + run->bvh_bytes + run->buffer_bytes;
    if (render)
        render_result_free(&rr);
    else
        importance_result_free(&ir);
    return status;
}

/* The importance pass (render = 0) or the renderer (one iteration of 1000 paths, should it
 * run) refuses scene s (finalized and freed here) as bad input: IDMR_EXIT_INPUT, with
 * `message` in the error. */
static inline void test_expect_refused(scene *s, int render, const char *message)
{
    test_finalize_scene(s);
    bvh b;
    test_build_bvh(s, &b);
    importance_options io;
    render_options ro;
    test_importance_options(&io, 1, 1000);
    test_render_options(&ro, 1, 1000);
    uint64_t allocated;
    int status = test_run_either(render, s, &b, &io, &ro, &allocated);
    print_message("  %s\n", error_message());
    bvh_free(&b);
    scene_free(s);
    assert_int_equal(status, -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), message));
}

/* A new directory from a mkdtemp() template such as "/tmp/idmr-test-XXXXXX" (filled in). */
static inline void test_make_directory(char *template_path)
{
    if (!mkdtemp(template_path))
        fail_msg("mkdtemp %s failed", template_path);
}

/* Removes a directory made by test_make_directory() with everything in it. */
static inline int test_remove_directory(const char *path)
{
    char command[512];
    snprintf(command, sizeof command, "rm -rf '%s'", path);
    return system(command) == 0 ? 0 : -1;
}

#endif
