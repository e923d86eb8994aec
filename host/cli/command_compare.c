/* command_compare.c — `idmr compare A B [--diff D.png] [--diff-max E] [--json]`: RMSE, PSNR,
 * relative MSE and the largest error of image A against the reference B (io/image_compare.h), as one
 * line or as a JSON object; optionally a false-colour error image. */
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

int command_compare(int argc, char **argv)
{
    static const struct option options[] = {{"diff", required_argument, NULL, 'd'},
                                            {"diff-max", required_argument, NULL, 'm'},
                                            {"json", no_argument, NULL, 'j'},
                                            {0, 0, 0, 0}};
    const char *diff = NULL;
    double diff_max = 0;
    int json = 0, c;
    while ((c = getopt_long(argc, argv, "", options, NULL)) != -1) {
        if (c == 'd')
            diff = optarg;
        else if (c == 'm') {
            if (parse_double("--diff-max", optarg, 1e-30, 1e30, &diff_max))
                return fail();
        } else if (c == 'j')
            json = 1;
        else
            return usage_error("compare: unknown option %s", argv[optind - 1]);
    }
    if (optind != argc - 2)
        return usage_error("compare: expected two images, A and the reference B");
    const char *a = argv[optind], *b = argv[optind + 1];
    image_comparison result;
    if (image_compare(a, b, diff, diff_max, &result))
        return fail();
    if (json) {
        cJSON *root = comparison_json(a, b, &result);
        json_print(root);
        cJSON_Delete(root);
    } else {
        printf("rmse %.6g  psnr %.2f dB  relative_mse %.6g  max_error %.6g  (%dx%d)\n", result.rmse,
               result.psnr, result.relative_mse, result.max_error, result.width, result.height);
    }
    return 0;
}
