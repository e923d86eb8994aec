/* command_kernels.c — `idmr kernels [--device N] [--quiet]`: builds every kernel program variant
 * (passes/kernel_variants.h) on the device: one line per variant on stderr ("built", or "cached"
 * when the program cache had it; --quiet leaves them out), then a summary line. A kernel that does not compile fails with its build log and
 * options (exit 1). `make kernels` runs it, so a kernel error fails the build; it also warms the
 * program cache for later runs. */
#include <getopt.h>
#include <stdio.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "core/error.h"
#include "core/progress.h"
#include "device/device.h"
#include "device/program.h"
#include "passes/kernel_variants.h"

/* Builds every variant; 0, or -1 with the error set (the failing variant's build log). */
static int build_all(device *d, int quiet)
{
    kernel_variant *variants;
    size_t count = kernel_variants_list(d, &variants);
    int status = 0;
    double start = monotonic_seconds();
    for (size_t i = 0; i < count && !status; i++) {
        cl_program program;
        status = device_build_program(d, variants[i].file, variants[i].options, &program);
        if (status) {
            error_prefix("%s", variants[i].label);
            break;
        }
        clReleaseProgram(program);
        if (!quiet)
            fprintf(stderr, "idmr: kernels %2zu/%zu %-62s %s\n", i + 1, count, variants[i].label,
                    device_last_build_cached() ? "cached" : "built");
    }
    if (!status)
        fprintf(stderr, "idmr: %zu kernel programs compile on %s (%.1f s)\n", count, d->info.name,
                monotonic_seconds() - start);
    kernel_variants_free(variants, count);
    return status;
}

int command_kernels(int argc, char **argv)
{
    static const struct option table[] = {{"device", required_argument, NULL, OPT_DEVICE},
                                          {"quiet", no_argument, NULL, OPT_QUIET},
                                          {0, 0, 0, 0}};
    int device_index = -1, quiet = 0, c;
    unsigned int index;
    while ((c = getopt_long(argc, argv, ":", table, NULL)) != -1) {
        if (c == OPT_DEVICE) {
            if (parse_unsigned("--device", optarg, 0, 1000, &index))
                return fail();
            device_index = (int)index;
        } else if (c == OPT_QUIET) {
            quiet = 1;
        } else {
            return option_error("kernels", c, argv, table);
        }
    }
    if (optind != argc)
        return usage_error("kernels: takes no arguments");
    device d;
    if (device_open(&d, device_index))
        return fail();
    int status = build_all(&d, quiet);
    device_close(&d);
    return status ? fail() : 0;
}
