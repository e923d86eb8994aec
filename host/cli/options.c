/* options.c — what the commands share of their command lines (see options.h): failure
 * messages, strict number parsing, the SPPM and importance options, the pass commands' getopt
 * loop. */
#include "cli/options.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"
#include "core/ranks.h"

int fail(void)
{
    /* Under mpirun, rank 0 prints the failure of the run, naming its rank (ranks_finish). */
    if (ranks_count() == 1)
        fprintf(stderr, "idmr: %s\n", error_message());
    return error_code();
}

int usage_error(const char *fmt, ...)
{
    if (ranks_rank() != 0) /* every rank parses the same command line: rank 0 says it */
        return IDMR_EXIT_INPUT;
    va_list args;
    va_start(args, fmt);
    fputs("idmr: ", stderr);
    vfprintf(stderr, fmt, args);
    fputs("\n(see `idmr --help`)\n", stderr);
    va_end(args);
    return IDMR_EXIT_INPUT;
}

/* Strict number parsing for options: the whole argument, finite, in range. */
int parse_unsigned(const char *option, const char *text, unsigned long min, unsigned long max,
                   unsigned int *out)
{
    char *end;
    errno = 0;
    unsigned long value = strtoul(text, &end, 10);
    if (errno || end == text || *end || text[0] == '-' || value < min || value > max)
        return error_set(IDMR_EXIT_INPUT, "%s: '%s' is not a whole number from %lu to %lu", option,
                         text, min, max);
    *out = (unsigned int)value;
    return 0;
}

int parse_double(const char *option, const char *text, double min, double max, double *out)
{
    char *end;
    errno = 0;
    double value = strtod(text, &end);
    if (errno || end == text || *end || !isfinite(value) || value < min || value > max)
        return error_set(IDMR_EXIT_INPUT, "%s: '%s' is not a number from %g to %g", option, text,
                         min, max);
    *out = value;
    return 0;
}

int parse_bytes(const char *option, const char *text, uint64_t *out)
{
    char *end;
    errno = 0;
    double value = strtod(text, &end);
    double unit = 1.0;
    if (end != text && end[0] && !end[1]) {
        const char *units = "KMGT";
        const char *at = strchr(units, end[0] == 'k' ? 'K' : end[0]);
        if (at) {
            unit = ldexp(1.0, 10 * (int)(at - units + 1));
            end++;
        }
    }
    double bytes = floor(value * unit);
    if (errno || end == text || *end || !isfinite(value) || text[0] == '-' || !(bytes >= 1) ||
        bytes > 0x1p63)
        return error_set(IDMR_EXIT_INPUT,
                         "%s: '%s' is not a size in bytes (a positive number, optionally "
                         "followed by K, M, G or T: 512M, 2G)",
                         option, text);
    *out = (uint64_t)bytes;
    return 0;
}

enum option_parse option_result(int status)
{
    return status ? OPTION_BAD_VALUE : OPTION_TAKEN;
}

/* parse_double() into a float. */
static int parse_float(const char *option, const char *text, double min, double max, float *out)
{
    double value;
    if (parse_double(option, text, min, max, &value))
        return -1;
    *out = (float)value;
    return 0;
}

int device_choice_several(const device_choice *c)
{
    return c->all || c->count > 1;
}

int parse_device_choice(const char *text, device_choice *c)
{
    memset(c, 0, sizeof *c);
    c->index = -1;
    if (strcmp(text, "all") == 0) {
        c->all = 1;
        return 0;
    }
    const char *at = text;
    unsigned int count = 0;
    for (;;) {
        size_t length = strcspn(at, ",");
        char number[32];
        unsigned int index;
        if (length == 0 || length >= sizeof number)
            return error_set(IDMR_EXIT_INPUT,
                             "--device: '%s' is not a device number, a list of them (0,2) or "
                             "'all' (idmr devices lists them)",
                             text);
        memcpy(number, at, length);
        number[length] = '\0';
        if (parse_unsigned("--device", number, 0, 1000, &index))
            return -1;
        for (unsigned int k = 0; k < count; k++)
            if (c->list[k] == (int)index)
                return error_set(IDMR_EXIT_INPUT, "--device: device %u is listed twice in '%s'",
                                 index, text);
        if (count == SPPM_MAX_DEVICES)
            return error_set(IDMR_EXIT_INPUT, "--device: '%s' lists more than %d devices", text,
                             SPPM_MAX_DEVICES);
        c->list[count++] = (int)index;
        at += length;
        if (!*at)
            break;
        at++; /* the comma */
    }
    c->count = count;
    c->index = c->list[0];
    return 0;
}

enum option_parse parse_sppm_option(int c, sppm_options *o, device_choice *devices)
{
    unsigned int whole;
    switch (c) {
    case OPT_ITERATIONS:
        return option_result(parse_unsigned("--iterations", optarg, 1, 1000000, &o->iterations));
    case OPT_PHOTONS:
        return option_result(parse_unsigned("--photons", optarg, 1, 1u << 26, &o->photons));
    case OPT_ALPHA:
        return option_result(parse_float("--alpha", optarg, 1e-3, 1, &o->alpha));
    case OPT_RESOLUTION:
        return option_result(parse_float("--resolution", optarg, 1e-3, 16, &o->resolution));
    case OPT_MAX_DEPTH:
        return option_result(parse_unsigned("--max-depth", optarg, 1, 1024, &o->max_depth));
    case OPT_SEED:
        return option_result(parse_unsigned("--seed", optarg, 0, 0xffffffffu, &o->seed));
    case OPT_TIME_LIMIT:
        return option_result(parse_double("--time-limit", optarg, 0, 1e9, &o->time_limit));
    case OPT_RADIUS:
        return option_result(parse_double("--radius", optarg, 1e-30, 1e30, &o->radius));
    case OPT_DEVICE:
        return option_result(parse_device_choice(optarg, devices));
    case OPT_QUIET:
        o->progress = 0;
        progress_set_quiet(1); /* also for loading the scene */
        return OPTION_TAKEN;
    case OPT_LOCAL_SIZE:
        if (parse_unsigned("--local-size", optarg, 0, 4096, &whole))
            return OPTION_BAD_VALUE;
        o->local_size = whole;
        return OPTION_TAKEN;
    case OPT_GENERIC:
        o->generic = 1;
        return OPTION_TAKEN;
    default:
        return OPTION_UNKNOWN;
    }
}

enum option_parse parse_importance_option(int c, importance_options *o, device_choice *devices)
{
    switch (c) {
    case OPT_TOLERANCE:
        return option_result(parse_double("--tolerance", optarg, 0, 1e30, &o->tolerance));
    case OPT_GAMMA:
        return option_result(parse_float("--gamma", optarg, 0, 1e6, &o->gamma));
    case OPT_SHADOW_WEIGHT:
        return option_result(parse_float("--shadow-weight", optarg, 0, 1e6, &o->shadow_weight));
    default:
        return parse_sppm_option(c, &o->sppm, devices);
    }
}

/* The long option of `table` that `name` (without "--", up to a '=') names exactly, or else the
 * only one it abbreviates; NULL when none, or several (*ambiguous set). */
static const struct option *long_option_named(const struct option *table, const char *name,
                                              int *ambiguous)
{
    size_t length = strcspn(name, "=");
    const struct option *found = NULL;
    int matches = 0;
    *ambiguous = 0;
    for (const struct option *o = table; o->name; o++) {
        if (strncmp(o->name, name, length))
            continue;
        if (strlen(o->name) == length)
            return o;
        found = o, matches++;
    }
    *ambiguous = matches > 1;
    return matches == 1 ? found : NULL;
}

int option_error(const char *command, int c, char **argv, const struct option *table)
{
    const char *arg = argv[optind - 1];
    int is_long = !strncmp(arg, "--", 2) && arg[2];
    if (c == ':')
        return usage_error("%s: %s needs a value", command, arg);
    if (!is_long) {
        if (optopt && optopt < 256)
            return usage_error("%s: unknown option -%c", command, optopt);
        return usage_error("%s: unknown option %s", command, arg);
    }
    int ambiguous;
    const struct option *o = long_option_named(table, arg + 2, &ambiguous);
    int length = (int)strcspn(arg, "=");
    if (o && o->has_arg == no_argument && strchr(arg, '='))
        return usage_error("%s: --%s takes no value (given '%s')", command, o->name,
                           strchr(arg, '=') + 1);
    if (ambiguous) {
        char names[512] = "";
        size_t used = 0;
        for (const struct option *each = table; each->name && used < sizeof names; each++)
            if (!strncmp(each->name, arg + 2, (size_t)length - 2))
                used += (size_t)snprintf(names + used, sizeof names - used, "%s--%s",
                                         used ? ", " : "", each->name);
        return usage_error("%s: %.*s is ambiguous (%s)", command, length, arg, names);
    }
    return usage_error("%s: unknown option %.*s", command, length, arg);
}

int expect_one_scene(const char *command, int argc)
{
    if (optind != argc - 1)
        return usage_error("%s: expected one SCENE argument", command);
    return 0;
}

int parse_pass_arguments(int argc, char **argv, const struct option *table,
                         pass_option_parser parse, void *context, pass_arguments *arguments)
{
    arguments->output = NULL;
    memset(&arguments->devices, 0, sizeof arguments->devices);
    arguments->devices.index = -1;
    int c;
    while ((c = getopt_long(argc, argv, ":o:", table, NULL)) != -1) {
        if (c == 'o') {
            arguments->output = optarg;
            continue;
        }
        switch (parse(c, context, arguments)) {
        case OPTION_TAKEN:
            break;
        case OPTION_BAD_VALUE:
            return fail();
        case OPTION_IMPORTANCE_ONLY:
            return usage_error("%s: --%s is an importance pass option", arguments->command,
                               c == OPT_GAMMA           ? "gamma"
                               : c == OPT_SHADOW_WEIGHT ? "shadow-weight"
                                                        : "tolerance");
        case OPTION_UNKNOWN:
            return option_error(arguments->command, c, argv, table);
        }
    }
    int code = expect_one_scene(arguments->command, argc);
    if (!code)
        arguments->scene = argv[optind];
    return code;
}
