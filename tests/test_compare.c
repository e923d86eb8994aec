/* test_compare.c — the paired reduction error (io/image_compare.h) on synthetic images whose
 * answer is known: renders are modelled as a converged image plus independent Gaussian noise
 * per seed, a reduction as a known change of the converged image.
 *
 *   known bias          B = A + β everywhere: the estimate recovers β within 3 standard errors,
 *                       while the plain RMSE of one noisy pair is dominated by the noise
 *   no change           B = A: the estimated MSE is 0 within 3 standard errors
 *   a changed region    β on a quarter of the image: MSE = β² / 4
 *   common seeds        A1 and B1 share their noise: the noise cancels exactly
 *   small images        a 16 x 16 image is cut into 4 x 4 tiles, not one
 *   standard error      over many independent repetitions, the spread of the estimate agrees
 *                       with the reported standard error (within 30 %): for a change spread
 *                       over the image, and for a strong change in a few pixels (glints), where
 *                       the spread of tile means overstated it eightyfold
 * The same through files and `idmr compare --paired` is in test_image.c. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "idmr/rng.h"
#include "io/image_compare.h"

#define WIDTH 128
#define HEIGHT 96
#define VALUES (3 * WIDTH * HEIGHT)

/* A standard normal draw (Box–Muller) from the shared generator. */
static double gaussian(idmr_rng *rng)
{
    double u1 = (idmr_rng_next(rng) + 0.5) / 4294967296.0;
    double u2 = idmr_rng_float(rng);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* A converged image: a smooth gradient with some structure, values in [0.1, 1.1]. */
static void converged(float *image)
{
    for (int y = 0; y < HEIGHT; y++)
        for (int x = 0; x < WIDTH; x++)
            for (int c = 0; c < 3; c++)
                image[3 * (y * WIDTH + x) + c] =
                    (float)(0.6 + 0.5 * sin(0.07 * x + 0.05 * y + c));
}

/* `truth` plus Gaussian noise of standard deviation sigma from stream `seed`. */
static void render(const float *truth, double sigma, unsigned int seed, float *out)
{
    idmr_rng rng = idmr_rng_init(seed, 0, IDMR_STREAM_TEST, 0);
    for (int i = 0; i < VALUES; i++)
        out[i] = (float)(truth[i] + sigma * gaussian(&rng));
}

typedef struct four_renders {
    float a1[VALUES], a2[VALUES], b1[VALUES], b2[VALUES];
} four_renders;

/* Renders of the original `a` and the reduced `b` with seeds 2k+1 and 2k+2 (independent noise
 * for A and B too, unless common_seeds). */
static void render_pairs(const float *a, const float *b, double sigma, unsigned int k,
                         int common_seeds, four_renders *r)
{
    render(a, sigma, 4 * k + 1, r->a1);
    render(a, sigma, 4 * k + 2, r->a2);
    render(b, sigma, common_seeds ? 4 * k + 1 : 4 * k + 3, r->b1);
    render(b, sigma, common_seeds ? 4 * k + 2 : 4 * k + 4, r->b2);
}

static image_paired_error paired(const four_renders *r)
{
    image_paired_error e;
    image_paired_error_of(r->a1, r->a2, r->b1, r->b2, WIDTH, HEIGHT, 16, &e);
    return e;
}

static float truth_a[VALUES], truth_b[VALUES];
static four_renders renders;

/* truth_a converged, truth_b the same plus `bias` everywhere. */
static void shifted_truths(double bias)
{
    converged(truth_a);
    for (int i = 0; i < VALUES; i++)
        truth_b[i] = truth_a[i] + (float)bias;
}

static void test_known_bias_is_recovered(void **state)
{
    const double bias = 0.02, sigma = 0.1;
    shifted_truths(bias);
    render_pairs(truth_a, truth_b, sigma, 0, 0, &renders);
    image_paired_error e = paired(&renders);
    printf("  bias %.3f under noise %.2f: reduction_rmse %.5f ± %.5f, noisy rmse %.4f\n", bias,
           sigma, e.rmse, e.rmse_standard_error, e.noisy_rmse);
    assert_int_equal(e.tiles, 8 * 6);
    assert_true(fabs(e.rmse - bias) < 3 * e.rmse_standard_error);
    assert_true(e.rmse_standard_error < 0.25 * bias); /* the test has the power to tell */
    /* One noisy pair sees sqrt(bias² + 2 sigma²): seven times the bias here. */
    assert_true(fabs(e.noisy_rmse - sqrt(bias * bias + 2 * sigma * sigma)) < 0.01);
}

static void test_no_change_gives_zero(void **state)
{
    converged(truth_a);
    render_pairs(truth_a, truth_a, 0.1, 1, 0, &renders);
    image_paired_error e = paired(&renders);
    printf("  no change: mse %.2e ± %.2e, reduction_rmse %.5f\n", e.mse, e.mse_standard_error,
           e.rmse);
    assert_true(fabs(e.mse) < 3 * e.mse_standard_error);
    assert_true(e.rmse < 0.01); /* against a noise of 0.1 */
    /* Within its noise the RMSE's error stays bounded (no 1 / rmse blow-up near zero). */
    assert_true(e.rmse_standard_error <= sqrt(e.mse_standard_error) + 1e-12);
}

/* An image of one default tile still gets a spread to estimate from: at least 4 x 4 tiles. */
static void test_small_image_has_tiles(void **state)
{
    shifted_truths(0.05);
    render_pairs(truth_a, truth_b, 0.05, 4, 0, &renders);
    image_paired_error e;
    image_paired_error_of(renders.a1, renders.a2, renders.b1, renders.b2, 16, 16, 16, &e);
    assert_int_equal(e.tiles, 16);
    assert_true(e.mse_standard_error > 0);
}

static void test_changed_region_gives_its_share(void **state)
{
    const double bias = 0.05;
    converged(truth_a);
    memcpy(truth_b, truth_a, sizeof truth_b);
    for (int y = 0; y < HEIGHT / 2; y++)
        for (int x = 0; x < WIDTH / 2; x++)
            for (int c = 0; c < 3; c++)
                truth_b[3 * (y * WIDTH + x) + c] -= (float)bias;
    render_pairs(truth_a, truth_b, 0.05, 2, 0, &renders);
    image_paired_error e = paired(&renders);
    double expected = bias * bias / 4;
    printf("  quarter changed by %.2f: mse %.3e ± %.1e, expected %.3e\n", bias, e.mse,
           e.mse_standard_error, expected);
    assert_true(fabs(e.mse - expected) < 3 * e.mse_standard_error);
}

static void test_common_seeds_cancel_noise(void **state)
{
    const double bias = 0.01;
    shifted_truths(bias);
    render_pairs(truth_a, truth_b, 0.2, 3, 1, &renders);
    image_paired_error e = paired(&renders);
    assert_float_equal(e.rmse, bias, 1e-5);
    assert_true(e.mse_standard_error < 1e-8);
}

/* Over independent repetitions (noise sigma) the estimates of the change truth_a -> truth_b
 * scatter as the reported standard error says, around the exact MSE. */
static void check_standard_error_against_spread(double sigma, unsigned int first_seed)
{
    enum { REPEATS = 40 };
    double sum = 0, sum2 = 0, reported = 0, exact = 0;
    for (int i = 0; i < VALUES; i++)
        exact += pow((double)truth_b[i] - truth_a[i], 2) / VALUES;
    for (unsigned int k = 0; k < REPEATS; k++) {
        render_pairs(truth_a, truth_b, sigma, first_seed + k, 0, &renders);
        image_paired_error e = paired(&renders);
        sum += e.mse;
        sum2 += e.mse * e.mse;
        reported += e.mse_standard_error / REPEATS;
    }
    double mean = sum / REPEATS;
    double spread = sqrt((sum2 - REPEATS * mean * mean) / (REPEATS - 1));
    printf("  mse %.4e (exact %.4e), spread %.2e, reported standard error %.2e\n", mean, exact,
           spread, reported);
    assert_true(fabs(mean - exact) < 3 * spread / sqrt(REPEATS));
    assert_true(reported > 0.7 * spread && reported < 1.3 * spread);
}

static void test_standard_error_matches_the_spread(void **state)
{
    converged(truth_a);
    for (int i = 0; i < VALUES; i++)
        truth_b[i] = truth_a[i] * 1.03f;
    check_standard_error_against_spread(0.08, 10);
}

/* 24 pixels change by 2 (glints that moved), the rest not at all, under noise 0.05. */
static void test_standard_error_of_a_few_glints(void **state)
{
    converged(truth_a);
    memcpy(truth_b, truth_a, sizeof truth_b);
    for (int k = 0; k < 24; k++) {
        int x = 40 + (k % 6) * 3, y = 30 + (k / 6) * 5;
        for (int c = 0; c < 3; c++)
            truth_b[3 * (y * WIDTH + x) + c] += 2.0f;
    }
    check_standard_error_against_spread(0.05, 100);
}

int main(void)
{
    const struct CMUnitTest estimator[] = {
        cmocka_unit_test(test_known_bias_is_recovered),
        cmocka_unit_test(test_no_change_gives_zero),
        cmocka_unit_test(test_changed_region_gives_its_share),
        cmocka_unit_test(test_common_seeds_cancel_noise),
        cmocka_unit_test(test_small_image_has_tiles),
        cmocka_unit_test(test_standard_error_matches_the_spread),
        cmocka_unit_test(test_standard_error_of_a_few_glints),
    };
    return cmocka_run_group_tests_name("paired estimator", estimator, NULL, NULL);
}
