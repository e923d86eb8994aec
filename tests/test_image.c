/* test_image.c — the OpenImageIO bridge (host/io/image.cc): writing PNG, writing and reading
 * back EXR, and image comparison (host/io/image_compare.c) against hand-computed RMSE, PSNR and
 * relative MSE, the paired reduction error through files, images with NaN or infinite values
 * refused; plus `idmr compare` and `idmr compare --paired` from the command line. (The paired
 * estimator's statistics are tested in test_compare.c.) Writes that fail part-way (a file size
 * limit, as a full disk) fail the call and leave no file. */
#include <math.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "io/image.h"
#include "io/image_compare.h"
#include "test_support.h"

static char dir[] = "/tmp/idmr-test-image-XXXXXX";
static const char *self_path; /* this program, run again for the writes under a size limit */

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

/* EXR keeps linear values exactly, 32-bit floats: a third, and a light's 1e6 (far above the
 * 65504 where half floats end in inf, which compare would then refuse). */
static void test_exr_round_trip(void **state)
{
    float *rgb = flat(8, 4, 0.5f, 0.25f, 2.0f);
    rgb[3 * 5] = 7.0f;
    rgb[3 * 6 + 1] = 1.0f / 3.0f;
    rgb[3 * 7 + 2] = 1.0e6f;
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

/* Runs `command`; its stdout into out (size bytes); returns the exit status. */
static int run_command(const char *command, char *out, size_t size)
{
    FILE *p = popen(command, "r");
    size_t n = fread(out, 1, size - 1, p);
    out[n] = '\0';
    int status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* Four renders whose noise cancels exactly (the same noise in A1 and B1, in A2 and B2), B a
 * constant 0.125 above A: the paired error is 0.125 exactly. */
static void write_paired_renders(void)
{
    float *a = flat(16, 16, 0.5f, 0.5f, 0.5f), *b = flat(16, 16, 0.625f, 0.625f, 0.625f);
    const char *names[2][2] = {{"a1.exr", "b1.exr"}, {"a2.exr", "b2.exr"}};
    for (int seed = 0; seed < 2; seed++) {
        float *noisy_a = flat(16, 16, 0, 0, 0), *noisy_b = flat(16, 16, 0, 0, 0);
        for (int i = 0; i < 3 * 256; i++) {
            float noise = (float)((i * 7 + seed * 3) % 5) * 0.0625f;
            noisy_a[i] = a[i] + noise;
            noisy_b[i] = b[i] + noise;
        }
        write_pair(path_of(names[seed][0]), noisy_a, path_of(names[seed][1]), noisy_b, 16, 16);
        free(noisy_a);
        free(noisy_b);
    }
    free(a);
    free(b);
}

static void test_paired_through_files(void **state)
{
    write_paired_renders();
    image_paired_error e;
    assert_int_equal(image_compare_paired(path_of("a1.exr"), path_of("a2.exr"), path_of("b1.exr"),
                                          path_of("b2.exr"), 4, &e),
                     0);
    assert_int_equal(e.width, 16);
    assert_int_equal(e.tiles, 16);
    assert_float_equal(e.rmse, 0.125, 1e-7);
    assert_float_equal(e.mse_standard_error, 0, 1e-12);
    char command[2048], out[4096];
    snprintf(command, sizeof command, "bin/idmr compare --paired %s %s %s %s --json",
             path_of("a1.exr"), path_of("a2.exr"), path_of("b1.exr"), path_of("b2.exr"));
    assert_int_equal(run_command(command, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"reduction_rmse\":\t0.125"));
    snprintf(command, sizeof command, "bin/idmr compare --paired %s %s %s 2>/dev/null",
             path_of("a1.exr"), path_of("a2.exr"), path_of("b1.exr"));
    assert_int_equal(run_command(command, out, sizeof out), 2);
}

static void test_paired_size_mismatch_names_both_files(void **state)
{
    float *small = flat(4, 5, 0.5f, 0.5f, 0.5f), *large = flat(16, 16, 0.5f, 0.5f, 0.5f);
    assert_int_equal(image_write_rgb_float(path_of("large.exr"), 16, 16, large), 0);
    assert_int_equal(image_write_rgb_float(path_of("small.exr"), 4, 5, small), 0);
    image_paired_error e;
    assert_int_equal(image_compare_paired(path_of("large.exr"), path_of("large.exr"),
                                          path_of("small.exr"), path_of("large.exr"), 0, &e),
                     -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), "small.exr"));
    assert_non_null(strstr(error_message(), "large.exr"));
    free(small);
    free(large);
}

/* NaN and infinity make a comparison meaningless: an error naming the file, the count and the
 * first pixel, not "psnr inf" and "max_error 0". */
static void test_non_finite_images_are_refused(void **state)
{
    float *bad = flat(8, 8, 0.5f, 0.5f, 0.5f), *good = flat(8, 8, 0.5f, 0.5f, 0.5f);
    bad[3 * (5 * 8 + 7) + 1] = NAN;
    bad[3 * (6 * 8 + 2)] = INFINITY;
    write_pair(path_of("nan.exr"), bad, path_of("clean.exr"), good, 8, 8);
    image_comparison c;
    assert_int_equal(image_compare(path_of("nan.exr"), path_of("clean.exr"), NULL, 0, &c), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), "nan.exr"));
    assert_non_null(strstr(error_message(), "2 values"));
    assert_non_null(strstr(error_message(), "pixel (7, 5)"));
    image_paired_error e;
    assert_int_equal(image_compare_paired(path_of("clean.exr"), path_of("clean.exr"),
                                          path_of("nan.exr"), path_of("clean.exr"), 0, &e),
                     -1);
    assert_non_null(strstr(error_message(), "nan.exr"));
    free(bad);
    free(good);
}


/* `test_image --write-limited PATH png|exr`, run by test_image_write_cut_short_fails in a
 * process of its own (a fork of this one would inherit OpenEXR's thread pool half-held): with
 * files of at most 2 KiB and SIGXFSZ ignored (a write past the limit fails with EFBIG, as one on
 * a full disk fails with ENOSPC), writes a 64x64 image of noise (which no format compresses below
 * the limit) as 8-bit (PNG) or float (EXR). Exit status: 0 written, 1 refused. */
static int write_limited_main(const char *path, const char *format)
{
    struct rlimit file_size = {2048, 2048};
    signal(SIGXFSZ, SIG_IGN);
    if (setrlimit(RLIMIT_FSIZE, &file_size))
        return 3;
    int w = 64, h = 64;
    float *rgb = flat(w, h, 0, 0, 0);
    unsigned char *bytes = malloc(3 * (size_t)w * h);
    unsigned int seed = 1;
    for (int i = 0; i < 3 * w * h; i++) {
        seed = seed * 1103515245u + 12345u;
        bytes[i] = (unsigned char)(seed >> 16);
        rgb[i] = (float)(seed >> 8) / 16777216.0f;
    }
    int status = strcmp(format, "exr") ? image_write_rgb8(path, w, h, bytes)
                                       : image_write_rgb_float(path, w, h, rgb);
    if (status)
        fprintf(stderr, "(as expected) %s\n", error_message());
    free(rgb);
    free(bytes);
    return status ? 1 : 0;
}

/* A PNG or an EXR cut short by a full disk is an error, and no file is left (OpenImageIO alone
 * reported a 0-byte PNG as written). */
static void test_image_write_cut_short_fails(void **state)
{
    const char *names[2] = {"limited.png", "limited.exr"};
    for (int as_float = 0; as_float < 2; as_float++) {
        char command[512];
        snprintf(command, sizeof command, "%s --write-limited %s %s", self_path,
                 path_of(names[as_float]), as_float ? "exr" : "png");
        int status = system(command);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 1)
            fail_msg("%s: written (status %d), though no file may hold more than 2 KiB",
                     names[as_float], status);
        struct stat info;
        assert_int_not_equal(stat(path_of(names[as_float]), &info), 0);
        snprintf(command, sizeof command, "ls %s | grep -q tmp", dir);
        if (system(command) == 0)
            fail_msg("%s: a temporary file was left in %s", names[as_float], dir);
    }
}

int main(int argc, char **argv)
{
    if (argc == 4 && !strcmp(argv[1], "--write-limited"))
        return write_limited_main(argv[2], argv[3]);
    self_path = argv[0];
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exr_round_trip),
        cmocka_unit_test(test_compare_against_formulas),
        cmocka_unit_test(test_compare_size_mismatch),
        cmocka_unit_test(test_compare_command),
        cmocka_unit_test(test_paired_through_files),
        cmocka_unit_test(test_paired_size_mismatch_names_both_files),
        cmocka_unit_test(test_non_finite_images_are_refused),
        cmocka_unit_test(test_image_write_cut_short_fails),
    };
    return cmocka_run_group_tests_name("image", tests, group_setup, group_teardown);
}
