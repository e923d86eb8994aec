/* test_mitsuba_renders.c — idmr's output as another renderer sees it: Mitsuba 3 (the PyPI
 * package, variant scalar_rgb, through scripts/mitsuba-render, which installs it into .venv/)
 * renders the scenes `idmr reduce` writes.
 *   - Rewritten without a collapse (--target 1: every mesh that could be decimated becomes a
 *     world-space PLY with its texture coordinates and normals), the Cornell box (split OBJ
 *     normals written as face_normals) and the living room (65 OBJ meshes, bitmap textures,
 *     UV seams, normal creases) render as their inputs: the paired reduction error (two seeds
 *     each, image_compare.h) of the path-traced images, and of the texture coordinates and
 *     shading normals the camera sees first (Mitsuba's aov integrator: one seed samples the same
 *     positions in both scenes, so these differ only where the scenes do), is zero within four
 *     standard errors (plus float rounding). A texture turned upside down (uv images: paired
 *     mse 0.32 +- 0.0003 when OBJ coordinates are not turned), lost normals or a smoothed box
 *     would not be.
 *   - Reduced to 10 % (the default method) with --bundle and then moved one directory deeper
 *     (so that no path out of it would still resolve), the living room renders without one
 *     invalid (NaN) sample and with its mean per channel within 5 % of the input's: its
 *     textures and environment map are the bundled copies.
 *   - A smooth plastic floor (ρ = 0.58, η = 1.5) lit by an area light behind the camera and
 *     seen at grazing angles (cos_o below 0.4, the horizon in view): idmr's SPPM render and
 *     Mitsuba 3's path tracer agree within 3 % in the mean and in the bottom fifth of the image
 *     (measured: −0.3 %, −0.5 %). The light leaving the diffuse base through the coating,
 *     (1 - F(cos_o)) / (1 - F_dr), matters here: a base weighted by 1 - F(cos_i) alone rendered
 *     18 % brighter in the mean and 11 % in the bottom fifth.
 *   - A shapegroup placed three times (one instance mirroring), which idmr simulates as
 *     world-space copies and writes back as a shapegroup and its instances (each group shape's
 *     PLY once, in the group's space): rewritten, it renders as its input in the same paired
 *     test; reduced to half, it keeps the group and its three instances, and its mean per
 *     channel stays within 5 %.
 * Small films and sample counts keep it to about a minute on 2 cores; runs from the repository
 * root (as `make test` does), with ../shared/data beside it. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "command_common.h"
#include "core/error.h"
#include "io/image.h"
#include "io/image_compare.h"

#define SCENES "../shared/data/scenes"
#define CORNELL SCENES "/cbox-mitsuba/cbox.xml"
#define LIVING_ROOM SCENES "/living-room/scene.xml"

static char work[64];

static int make_work_dir(void **state)
{
    (void)state;
    make_temp_dir(work, "idmr-test-mitsuba");
    return 0;
}

static int remove_work_dir(void **state)
{
    (void)state;
    remove_tree(work);
    return 0;
}

/* Renders `scene` with Mitsuba 3 (integrator: path, uv or normals, scripts/mitsuba-render)
 * into work/name.exr; returns its stderr (caller frees). */
static char *mitsuba_render(const char *scene, const char *name, const char *integrator,
                            double resolution, int spp, int seed)
{
    run_result r = run("scripts/mitsuba-render %s -o %s/%s.exr --integrator %s --resolution %g "
                       "--spp %d --seed %d",
                       scene, work, name, integrator, resolution, spp, seed);
    assert_succeeded(&r);
    char *err = strdup(r.err);
    run_free(&r);
    return err;
}

/* `idmr reduce scene` into work/name with the given options. */
static void reduce(const char *scene, const char *name, const char *options)
{
    run_result r = run("bin/idmr reduce %s -o %s/%s --quiet %s", scene, work, name, options);
    assert_succeeded(&r);
    run_free(&r);
}

/* work/name.exr into path (160 bytes). */
static char *exr_path(char *path, const char *name)
{
    snprintf(path, 160, "%s/%s.exr", work, name);
    return path;
}

/* The scene rewritten at --target 1 renders as the input with `integrator`: the paired error
 * is zero within four standard errors, plus 1e-8 for float rounding (world-space positions
 * transformed once by idmr and once by Mitsuba give normals a few ulps apart: 1e-15). */
static void check_renders_alike(const char *scene, const char *rewritten, const char *name,
                                const char *integrator, double resolution, int spp)
{
    char a[2][64], b[2][64], path[4][160];
    for (int seed = 0; seed < 2; seed++) {
        snprintf(a[seed], sizeof a[seed], "%s-%s-in-%d", name, integrator, seed + 1);
        snprintf(b[seed], sizeof b[seed], "%s-%s-out-%d", name, integrator, seed + 1);
        free(mitsuba_render(scene, a[seed], integrator, resolution, spp, seed + 1));
        free(mitsuba_render(rewritten, b[seed], integrator, resolution, spp, seed + 1));
    }
    image_paired_error e;
    if (image_compare_paired(exr_path(path[0], a[0]), exr_path(path[1], a[1]),
                             exr_path(path[2], b[0]), exr_path(path[3], b[1]), 0, &e))
        fail_msg("%s", error_message());
    print_message("%s rewritten, Mitsuba 3 %s (%dx%d, %d spp): paired mse %.3g +- %.3g, "
                  "noisy rmse %.3g\n",
                  name, integrator, e.width, e.height, spp, e.mse, e.mse_standard_error,
                  e.noisy_rmse);
    assert_true(e.mse <= 4.0 * e.mse_standard_error + 1e-8);
}

static void check_rewrite_renders_as_input(const char *scene, const char *name, double resolution,
                                           int spp)
{
    char rewritten[128];
    reduce(scene, name, "--target 1 --method quadric");
    snprintf(rewritten, sizeof rewritten, "%s/%s/scene.xml", work, name);
    check_renders_alike(scene, rewritten, name, "path", resolution, spp);
    check_renders_alike(scene, rewritten, name, "uv", resolution, 4);
    check_renders_alike(scene, rewritten, name, "normals", resolution, 4);
}

static void test_cornell_rewritten_renders_as_input(void **state)
{
    (void)state;
    check_rewrite_renders_as_input(CORNELL, "cornell", 0.25, 64);
}

static void test_living_room_rewritten_renders_as_input(void **state)
{
    (void)state;
    check_rewrite_renders_as_input(LIVING_ROOM, "living-room", 0.1, 16);
}

/* Mean per channel of an image. */
static void channel_means(const char *path, double mean[3])
{
    int width, height;
    float *rgb;
    if (image_read_rgb(path, &width, &height, &rgb))
        fail_msg("%s", error_message());
    mean[0] = mean[1] = mean[2] = 0;
    size_t n = (size_t)width * height;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            mean[k] += rgb[3 * i + k] / (double)n;
    free(rgb);
}

static void test_living_room_reduced_renders_clean(void **state)
{
    (void)state;
    reduce(LIVING_ROOM, "living-room-10",
           "--target 0.1 --iterations 4 --resolution 0.1 --photons 100000 --bundle");
    char from[128], to[128], out[160];
    snprintf(from, sizeof from, "%s/living-room-10", work);
    snprintf(to, sizeof to, "%s/moved", work);
    assert_int_equal(mkdir(to, 0755), 0);
    snprintf(to, sizeof to, "%s/moved/living-room-10", work);
    assert_int_equal(rename(from, to), 0);
    snprintf(out, sizeof out, "%s/scene.xml", to);
    free(mitsuba_render(LIVING_ROOM, "living-room-10-in", "path", 0.1, 16, 1));
    char *err = mitsuba_render(out, "living-room-10-out", "path", 0.1, 16, 1);
    if (strstr(err, "Invalid sample"))
        fail_msg("Mitsuba 3 found invalid samples in the reduced living room:\n%s", err);
    free(err);
    double in[3], reduced[3];
    char path[160];
    channel_means(exr_path(path, "living-room-10-in"), in);
    channel_means(exr_path(path, "living-room-10-out"), reduced);
    for (int k = 0; k < 3; k++) {
        print_message("channel %d: input %.4f, reduced %.4f (%+.1f %%)\n", k, in[k], reduced[k],
                      100.0 * (reduced[k] / in[k] - 1.0));
        assert_true(fabs(reduced[k] / in[k] - 1.0) < 0.05);
    }
}

/* Mean of an image's rows from `from` (a fraction of the height, from the top) to the bottom,
 * over its three channels. */
static double rows_mean(const char *path, double from)
{
    int width, height;
    float *rgb;
    if (image_read_rgb(path, &width, &height, &rgb))
        fail_msg("%s", error_message());
    int first = (int)(from * height);
    double sum = 0;
    size_t n = (size_t)(height - first) * width * 3;
    for (size_t i = (size_t)first * width * 3; i < (size_t)height * width * 3; i++)
        sum += rgb[i];
    free(rgb);
    return sum / (double)n;
}

static const char plastic_floor_xml[] =
    "<scene version=\"3.0.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"40\"/>\n"
    "    <transform name=\"to_world\">\n"
    "      <lookat origin=\"0, -1, 0.5\" target=\"0, 3, 0\" up=\"0, 0, 1\"/>\n"
    "    </transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"128\"/>"
    "<integer name=\"height\" value=\"96\"/></film>\n"
    "  </sensor>\n"
    "  <bsdf type=\"plastic\" id=\"floor\">\n"
    "    <rgb name=\"diffuse_reflectance\" value=\"0.58\"/>\n"
    "    <float name=\"int_ior\" value=\"1.5\"/>\n"
    "  </bsdf>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"to_world\"><scale value=\"6\"/></transform>\n"
    "    <ref id=\"floor\"/>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"to_world\"><rotate x=\"1\" angle=\"180\"/>"
    "<translate value=\"0, -2, 2\"/></transform>\n"
    "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"3\"/></emitter>\n"
    "  </shape>\n"
    "</scene>\n";

static void test_plastic_floor_at_grazing_view_renders_as_in_mitsuba(void **state)
{
    (void)state;
    char scene[128], path[160];
    snprintf(scene, sizeof scene, "%s/plastic-floor.xml", work);
    FILE *f = fopen(scene, "w");
    assert_non_null(f);
    fputs(plastic_floor_xml, f);
    assert_int_equal(fclose(f), 0);
    free(mitsuba_render(scene, "plastic-floor-mitsuba", "path", 1, 128, 1));
    run_result r = run("bin/idmr render %s -o %s --iterations 16 --quiet", scene,
                       exr_path(path, "plastic-floor-idmr"));
    assert_succeeded(&r);
    run_free(&r);
    const double from[2] = {0.0, 0.8};
    for (int k = 0; k < 2; k++) {
        double mitsuba = rows_mean(exr_path(path, "plastic-floor-mitsuba"), from[k]);
        double idmr = rows_mean(exr_path(path, "plastic-floor-idmr"), from[k]);
        print_message("plastic floor, %s: Mitsuba 3 %.4f, idmr %.4f (%+.1f %%)\n",
                      k ? "bottom fifth" : "whole image", mitsuba, idmr,
                      100.0 * (idmr / mitsuba - 1.0));
        assert_true(fabs(idmr / mitsuba - 1.0) < 0.03);
    }
}

/* A shapegroup (a tetrahedron OBJ without normals, a red rectangle, a bumped patch OBJ with
 * texture coordinates: mesh files and a built-in shape, each under a to_world of its own)
 * placed three times (moved; turned and scaled; mirrored in x, which turns the OBJs' winding)
 * over a floor lit by an area light. */
static const char instanced_xml[] =
    "<scene version=\"3.0.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"45\"/>\n"
    "    <transform name=\"to_world\">\n"
    "      <lookat origin=\"0, 3, 9\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/>\n"
    "    </transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"96\"/>"
    "<integer name=\"height\" value=\"64\"/></film>\n"
    "  </sensor>\n"
    "  <bsdf type=\"diffuse\" id=\"grey\"/>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"to_world\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale value=\"6\"/></transform>\n"
    "    <ref id=\"grey\"/>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"to_world\"><rotate x=\"1\" angle=\"90\"/>"
    "<translate value=\"1, 5, 2\"/></transform>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"4\"/></emitter>\n"
    "  </shape>\n"
    "  <shape type=\"shapegroup\" id=\"G\">\n"
    "    <shape type=\"obj\">\n"
    "      <string name=\"filename\" value=\"tet.obj\"/>\n"
    "      <transform name=\"to_world\"><translate x=\"0.3\"/></transform>\n"
    "      <ref id=\"grey\"/>\n"
    "    </shape>\n"
    "    <shape type=\"rectangle\">\n"
    "      <transform name=\"to_world\"><scale value=\"0.4\"/>"
    "<rotate y=\"1\" angle=\"30\"/><translate value=\"-0.5, 0.6, 0\"/></transform>\n"
    "      <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.2, 0.2\"/></bsdf>\n"
    "    </shape>\n"
    "    <shape type=\"obj\">\n"
    "      <string name=\"filename\" value=\"bump.obj\"/>\n"
    "      <transform name=\"to_world\"><translate value=\"-0.5, 0, -0.5\"/>"
    "<rotate z=\"1\" angle=\"20\"/><translate y=\"1.3\"/></transform>\n"
    "      <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.2, 0.6, 0.3\"/></bsdf>\n"
    "    </shape>\n"
    "  </shape>\n"
    "  <shape type=\"instance\" id=\"left\">\n"
    "    <ref id=\"G\"/>\n"
    "    <transform name=\"to_world\"><translate x=\"-2.5\"/></transform>\n"
    "  </shape>\n"
    "  <shape type=\"instance\">\n"
    "    <ref name=\"shapegroup\" id=\"G\"/>\n"
    "    <transform name=\"to_world\"><scale value=\"1.3\"/>"
    "<rotate y=\"1\" angle=\"40\"/></transform>\n"
    "  </shape>\n"
    "  <shape type=\"instance\" id=\"mirrored\">\n"
    "    <ref id=\"G\"/>\n"
    "    <transform name=\"to_world\"><scale x=\"-1\"/><translate x=\"2.5\"/></transform>\n"
    "  </shape>\n"
    "</scene>\n";

/* A unit patch in x and z bulging up to y = 0.3, n × n quads with texture coordinates, wound to
 * face +y, as an OBJ at path. */
static void write_bump_obj(const char *path, int n)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++) {
            double x = (double)i / n, z = (double)j / n;
            fprintf(f, "v %.6f %.6f %.6f\nvt %.6f %.6f\n", x, 0.3 * sin(M_PI * x) * sin(M_PI * z),
                    z, x, z);
        }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            int a = i * (n + 1) + j + 1, b = a + 1, c = a + n + 1, d = c + 1;
            fprintf(f, "f %d/%d %d/%d %d/%d\nf %d/%d %d/%d %d/%d\n", a, a, b, b, c, c, c, c, b,
                    b, d, d);
        }
    assert_int_equal(fclose(f), 0);
}

/* How often `needle` occurs in the file at path. */
static int occurrences_in_file(const char *path, const char *needle)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char *text = slurp(f);
    fclose(f);
    int count = 0;
    for (const char *at = text; (at = strstr(at, needle)); at += strlen(needle))
        count++;
    free(text);
    return count;
}

/* Instances are kept: rewritten (--target 1), the scene renders as the input, the mirrored
 * copy's sides included; reduced to half, it still holds the shapegroup and its three
 * instances, each group shape written once (no PLY named after an instance), and its mean per
 * channel stays within 5 %. */
static void test_instances_kept_render_as_input(void **state)
{
    (void)state;
    char scene[128], obj[128], reduced[128], path[160];
    snprintf(scene, sizeof scene, "%s/instances.xml", work);
    snprintf(obj, sizeof obj, "%s/tet.obj", work);
    FILE *f = fopen(scene, "w");
    FILE *g = fopen(obj, "w");
    assert_true(f && g);
    fputs(instanced_xml, f);
    /* With texture coordinates: without, Mitsuba's are a triangle's barycentrics, which the
     * winding a mirroring instance turns swaps (the one thing a flattened copy cannot keep). */
    fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
          "f 1/1 3/3 2/2\nf 1/1 2/2 4/4\nf 1/1 4/4 3/3\nf 2/2 3/3 4/4\n",
          g);
    assert_int_equal(fclose(f), 0);
    assert_int_equal(fclose(g), 0);
    snprintf(obj, sizeof obj, "%s/bump.obj", work);
    write_bump_obj(obj, 16);
    check_rewrite_renders_as_input(scene, "instances", 1, 32);
    reduce(scene, "instances-half", "--target 0.5 --iterations 4 --photons 100000");
    snprintf(reduced, sizeof reduced, "%s/instances-half/scene.xml", work);
    assert_int_equal(occurrences_in_file(reduced, "type=\"shapegroup\""), 1);
    assert_int_equal(occurrences_in_file(reduced, "type=\"instance\""), 3);
    int plys = occurrences_in_file(reduced, "value=\"meshes/");
    assert_true(plys >= 1 && plys <= 3);
    assert_int_equal(occurrences_in_file(reduced, "meshes/left"), 0);
    assert_int_equal(occurrences_in_file(reduced, "meshes/mirrored"), 0);
    free(mitsuba_render(reduced, "instances-half-out", "path", 1, 32, 1));
    double in[3], out[3];
    channel_means(exr_path(path, "instances-path-in-1"), in);
    channel_means(exr_path(path, "instances-half-out"), out);
    for (int k = 0; k < 3; k++) {
        print_message("instances, channel %d: input %.4f, reduced %.4f (%+.1f %%)\n", k, in[k],
                      out[k], 100.0 * (out[k] / in[k] - 1.0));
        assert_true(fabs(out[k] / in[k] - 1.0) < 0.05);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_rewritten_renders_as_input),
        cmocka_unit_test(test_living_room_rewritten_renders_as_input),
        cmocka_unit_test(test_living_room_reduced_renders_clean),
        cmocka_unit_test(test_plastic_floor_at_grazing_view_renders_as_in_mitsuba),
        cmocka_unit_test(test_instances_kept_render_as_input),
    };
    return cmocka_run_group_tests(tests, make_work_dir, remove_work_dir);
}
