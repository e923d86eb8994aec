/* test_image.c — the OpenImageIO bridge (host/io/image.cc): writing PNG, writing and reading
 * back EXR, and image comparison against hand-computed RMSE, PSNR and relative MSE; plus
 * `idmr compare` from the command line. */
#include <math.h>
#include <sys/wait.h>

#include "io/image.h"
#include "io/image_compare.h"
#include "test_support.h"

static char dir[] = "/tmp/idmr-test-image-XXXXXX";

static int group_setup(void **state) { return mkdtemp(dir) ? 0 : -1; }

static int group_teardown(void **state) { return test_remove_directory(dir); }

static const char *path_of(const char *name)
{
    static char paths[8][256];
    static int next;
    char *p = paths[next++ % 8];
    snprintf(p, 256, "%s/%s", dir, name);
    return p;
}

/* A w x h image of one colour. */
static float *flat(int w, int h, float r, float g, float b)
{
    float *rgb = malloc(3 * sizeof(float) * (size_t)w * (size_t)h);
    for (int i = 0; i < w * h; i++) {
        rgb[3 * i] = r;
        rgb[3 * i + 1] = g;
        rgb[3 * i + 2] = b;
    }
    return rgb;
}

/* Writes two w x h EXR images, a at pa and b at pb. */
static void write_pair(const char *pa, const float *a, const char *pb, const float *b, int w, int h)
{
    assert_int_equal(image_write_rgb_float(pa, w, h, a), 0);
    assert_int_equal(image_write_rgb_float(pb, w, h, b), 0);
}

/* EXR keeps linear values (half floats: 0.5 and 0.25 exactly). */
static void test_exr_round_trip(void **state)
{
    float *rgb = flat(8, 4, 0.5f, 0.25f, 2.0f);
    rgb[3 * 5] = 7.0f;
    const char *path = path_of("round.exr");
    assert_int_equal(image_write_rgb_float(path, 8, 4, rgb), 0);
    int w, h, c;
    assert_int_equal(image_info(path, &w, &h, &c), 0);
    assert_int_equal(w, 8);
    assert_int_equal(h, 4);
    assert_int_equal(c, 3);
    float *back;
    assert_int_equal(image_read_rgb(path, &w, &h, &back), 0);
    assert_memory_equal(back, rgb, 3 * sizeof(float) * 32);
    free(back);
    free(rgb);
}

/* A = 0.5 everywhere, B = 0.25: RMSE 0.25, PSNR 20 log10(1 / 0.25) = 12.0412 dB (peak 1),
 * relative MSE 0.0625 / (0.0625 + 0.01) = 0.862069; identical images: RMSE 0, PSNR infinite. */
static void test_compare_against_formulas(void **state)
{
    float *a = flat(16, 8, 0.5f, 0.5f, 0.5f), *b = flat(16, 8, 0.25f, 0.25f, 0.25f);
    const char *pa = path_of("a.exr"), *pb = path_of("b.exr"), *diff = path_of("diff.png");
    write_pair(pa, a, pb, b, 16, 8);
    image_comparison r;
    assert_int_equal(image_compare(pa, pb, diff, 0, &r), 0);
    assert_float_equal(r.rmse, 0.25, 1e-9);
    assert_float_equal(r.psnr, 20.0 * log10(1.0 / 0.25), 1e-9);
    assert_float_equal(r.relative_mse, 0.0625 / 0.0725, 1e-9);
    assert_float_equal(r.max_error, 0.25, 1e-9);
    int w, h, c;
    assert_int_equal(image_info(diff, &w, &h, &c), 0);
    assert_int_equal(w, 16);
    assert_int_equal(image_compare(pa, pa, NULL, 0, &r), 0);
    assert_true(r.rmse == 0.0 && isinf(r.psnr) && r.relative_mse == 0.0);
    /* One pixel off by 1 in one channel of 16 x 8 x 3 values: RMSE sqrt(1 / 384). */
    a[0] = 1.5f;
    memcpy(b, a, 3 * sizeof(float) * 128);
    b[0] = 0.5f;
    write_pair(pa, a, pb, b, 16, 8);
    assert_int_equal(image_compare(pa, pb, NULL, 0, &r), 0);
    assert_float_equal(r.rmse, sqrt(1.0 / 384.0), 1e-9);
    free(a);
    free(b);
}

static void test_compare_size_mismatch(void **state)
{
    float *a = flat(4, 4, 1, 1, 1), *b = flat(4, 5, 1, 1, 1);
    const char *pa = path_of("small.exr"), *pb = path_of("tall.exr");
    assert_int_equal(image_write_rgb_float(pa, 4, 4, a), 0);
    assert_int_equal(image_write_rgb_float(pb, 4, 5, b), 0);
    image_comparison r;
    assert_int_equal(image_compare(pa, pb, NULL, 0, &r), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), "small.exr"));
    assert_non_null(strstr(error_message(), "4x5"));
    assert_int_equal(image_compare(pa, path_of("absent.exr"), NULL, 0, &r), -1);
    assert_non_null(strstr(error_message(), "absent.exr"));
    free(a);
    free(b);
}

static void test_compare_command(void **state)
{
    float *a = flat(4, 4, 0.5f, 0.5f, 0.5f), *b = flat(4, 4, 0.25f, 0.25f, 0.25f);
    const char *pa = path_of("cli-a.exr"), *pb = path_of("cli-b.exr");
    write_pair(pa, a, pb, b, 4, 4);
    char command[1024];
    snprintf(command, sizeof command, "bin/idmr compare %s %s --json", pa, pb);
    FILE *p = popen(command, "r");
    char out[2048] = "";
    size_t n = fread(out, 1, sizeof out - 1, p);
    out[n] = '\0';
    assert_int_equal(pclose(p), 0);
    assert_non_null(strstr(out, "\"rmse\":\t0.25"));
    snprintf(command, sizeof command, "bin/idmr compare %s %s 2>/dev/null", pa,
             path_of("missing.exr"));
    int status = system(command);
    assert_int_equal(WEXITSTATUS(status), 2);
    free(a);
    free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exr_round_trip),
        cmocka_unit_test(test_compare_against_formulas),
        cmocka_unit_test(test_compare_size_mismatch),
        cmocka_unit_test(test_compare_command),
    };
    return cmocka_run_group_tests_name("image", tests, group_setup, group_teardown);
}
