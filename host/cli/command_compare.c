/* command_compare.c — two ways to compare images (io/image_compare.h), as one line or a JSON
 * object:
 *   idmr compare A B [--diff D.png] [--diff-max E] [--json]
 *       RMSE, PSNR, relative MSE and the largest error of image A against the reference B, and
 *       optionally a false-colour error image;
 *   idmr compare --paired A1 A2 B1 B2 [--tile N] [--json]
 *       the reduction error with render noise cancelled: A1, A2 the original scene rendered
 *       with two seeds, B1, B2 the reduced scene with the same two seeds. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "core/json.h"
#include "io/image_compare.h"

static cJSON *comparison_json(const char *a, const char *b, const image_comparison *result)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "a", a);
    cJSON_AddStringToObject(root, "b", b);
    cJSON_AddNumberToObject(root, "width", result->width);
    cJSON_AddNumberToObject(root, "height", result->height);
    cJSON_AddNumberToObject(root, "rmse", result->rmse);
    if (isfinite(result->psnr))
        cJSON_AddNumberToObject(root, "psnr", result->psnr);
    else
        cJSON_AddNullToObject(root, "psnr"); /* identical images: infinite */
    cJSON_AddNumberToObject(root, "relative_mse", result->relative_mse);
    cJSON_AddNumberToObject(root, "max_error", result->max_error);
    cJSON_AddNumberToObject(root, "error_p99", result->error_p99);
    return root;
}

static int compare_pair(char **images, const char *diff, double diff_max, int json)
{
    image_comparison result;
    if (image_compare(images[0], images[1], diff, diff_max, &result))
        return fail();
    if (json) {
        cJSON *root = comparison_json(images[0], images[1], &result);
        json_print(root);
        cJSON_Delete(root);
    } else {
        printf("rmse %.6g  psnr %.2f dB  relative_mse %.6g  max_error %.6g  (%dx%d)\n", result.rmse,
               result.psnr, result.relative_mse, result.max_error, result.width, result.height);
    }
    return 0;
}

static cJSON *paired_json(char **images, const image_paired_error *e)
{
    cJSON *root = cJSON_CreateObject();
    const char *names[4] = {"a1", "a2", "b1", "b2"};
    for (int i = 0; i < 4; i++)
        cJSON_AddStringToObject(root, names[i], images[i]);
    cJSON_AddNumberToObject(root, "width", e->width);
    cJSON_AddNumberToObject(root, "height", e->height);
    cJSON_AddNumberToObject(root, "tiles", e->tiles);
    cJSON_AddNumberToObject(root, "reduction_rmse", e->rmse);
    cJSON_AddNumberToObject(root, "reduction_rmse_standard_error", e->rmse_standard_error);
    cJSON_AddNumberToObject(root, "reduction_mse", e->mse);
    cJSON_AddNumberToObject(root, "reduction_mse_standard_error", e->mse_standard_error);
    cJSON_AddNumberToObject(root, "noisy_rmse", e->noisy_rmse);
    return root;
}

static int compare_paired(char **images, int tile, int json)
{
    image_paired_error e;
    if (image_compare_paired(images[0], images[1], images[2], images[3], tile, &e))
        return fail();
    if (json) {
        cJSON *root = paired_json(images, &e);
        json_print(root);
        cJSON_Delete(root);
    } else {
        printf("reduction_rmse %.6g ± %.2g  (mse %.6g ± %.2g; noisy rmse %.6g; %u tiles, %dx%d)\n",
               e.rmse, e.rmse_standard_error, e.mse, e.mse_standard_error, e.noisy_rmse, e.tiles,
               e.width, e.height);
    }
    return 0;
}

int command_compare(int argc, char **argv)
{
    static const struct option options[] = {{"diff", required_argument, NULL, 'd'},
                                            {"diff-max", required_argument, NULL, 'm'},
                                            {"json", no_argument, NULL, 'j'},
                                            {"paired", no_argument, NULL, 'p'},
                                            {"tile", required_argument, NULL, 't'},
                                            {0, 0, 0, 0}};
    const char *diff = NULL;
    double diff_max = 0;
    unsigned int tile = IMAGE_PAIRED_TILE;
    int json = 0, paired = 0, tile_given = 0, c;
    while ((c = getopt_long(argc, argv, ":", options, NULL)) != -1) {
        if (c == 'd') {
            diff = optarg;
        } else if (c == 'm') {
            if (parse_double("--diff-max", optarg, 1e-30, 1e30, &diff_max))
                return fail();
        } else if (c == 't') {
            if (parse_unsigned("--tile", optarg, 1, 4096, &tile))
                return fail();
            tile_given = 1;
        } else if (c == 'j') {
            json = 1;
        } else if (c == 'p') {
            paired = 1;
        } else {
            return option_error("compare", c, argv, options);
        }
    }
    if (paired) {
        if (optind != argc - 4)
            return usage_error("compare --paired: expected four images, A1 A2 B1 B2");
        if (diff || diff_max > 0)
            return usage_error("compare --paired: --diff and --diff-max are for a comparison of "
                               "two images");
        return compare_paired(argv + optind, (int)tile, json);
    }
    if (tile_given)
        return usage_error("compare: --tile is for --paired");
    if (optind != argc - 2)
        return usage_error("compare: expected two images, A and the reference B");
    return compare_pair(argv + optind, diff, diff_max, json);
}
