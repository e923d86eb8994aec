/* options.h — what the commands share of their command lines: strict number parsing, the ids
 * and long-option tables of the SPPM core's options (importance, reduce, render) and of the
 * importance pass's (importance, reduce), the parsers that apply them, the getopt loop of the
 * pass commands, and the two ways a command fails.
 *
 * Failures: fail() prints the recorded error (core/error.h) as one "idmr: ..." line and returns
 * its exit code; usage_error() prints "idmr: <message>" and a pointer to `idmr --help`, and
 * returns 2 (IDMR_EXIT_INPUT). */
#ifndef IDMR_CLI_OPTIONS_H
#define IDMR_CLI_OPTIONS_H
#include <getopt.h>

#include "passes/importance.h"
#include "passes/sppm.h"

/* getopt_long values of the long options that have no short form. */
enum option_id {
    OPT_ITERATIONS = 256,
    OPT_TOLERANCE,
    OPT_PHOTONS,
    OPT_GAMMA,
    OPT_SHADOW_WEIGHT,
    OPT_ALPHA,
    OPT_RESOLUTION,
    OPT_SEED,
    OPT_DEVICE,
    OPT_QUIET,
    OPT_LOCAL_SIZE,
    OPT_GENERIC,
    OPT_TARGET,
    OPT_METHOD,
    OPT_MIN_VERTICES,
    OPT_MAX_NORMAL_ANGLE,
    OPT_UV_WEIGHT,
    OPT_NORMAL_WEIGHT,
    OPT_KEEP,
    OPT_FORCE,
    OPT_THREADS,
    OPT_TIME_LIMIT,
    OPT_RADIUS,
    OPT_EXPOSURE,
    OPT_MAX_DEPTH,
    OPT_BUNDLE,
    OPT_RECOMPUTE_NORMALS,
    OPT_FACTOR_TOLERANCE,
    OPT_RANKING_TOLERANCE,
    OPT_SIMULATION,
    OPT_INITIAL,
    OPT_PASSES,
    OPT_MEMORY_BUDGET,
    OPT_MAX_ERROR,
    OPT_MAX_ERROR_RELATIVE,
    OPT_MAX_ERROR_STEP,
    OPT_CHECK_ITERATIONS,
    OPT_CHECK_RESOLUTION,
    OPT_CHECK_PHOTONS,
    OPT_REFINE,
};

/* Options of the SPPM core, shared by `importance`, `reduce` and `render` (-o among them). */
#define SPPM_LONG_OPTIONS                                                                   \
    {"output", required_argument, NULL, 'o'},                                               \
        {"iterations", required_argument, NULL, OPT_ITERATIONS},                            \
        {"photons", required_argument, NULL, OPT_PHOTONS},                                  \
        {"alpha", required_argument, NULL, OPT_ALPHA},                                      \
        {"resolution", required_argument, NULL, OPT_RESOLUTION},                            \
        {"max-depth", required_argument, NULL, OPT_MAX_DEPTH},                              \
        {"seed", required_argument, NULL, OPT_SEED},                                        \
        {"time-limit", required_argument, NULL, OPT_TIME_LIMIT},                            \
        {"radius", required_argument, NULL, OPT_RADIUS},                                    \
        {"device", required_argument, NULL, OPT_DEVICE},                                    \
        {"quiet", no_argument, NULL, OPT_QUIET},                                            \
        {"local-size", required_argument, NULL, OPT_LOCAL_SIZE},                            \
        {"generic", no_argument, NULL, OPT_GENERIC}

/* Options of the importance pass, shared by `importance` and `reduce`. */
#define IMPORTANCE_LONG_OPTIONS                                                             \
    SPPM_LONG_OPTIONS, {"tolerance", required_argument, NULL, OPT_TOLERANCE},               \
        {"gamma", required_argument, NULL, OPT_GAMMA},                                      \
        {"shadow-weight", required_argument, NULL, OPT_SHADOW_WEIGHT}

/* Prints the recorded error as "idmr: <message>"; returns its exit code. */
int fail(void);

/* Prints "idmr: " and the printf-style message, then "(see `idmr --help`)"; returns
 * IDMR_EXIT_INPUT. */
int usage_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* The whole of `text` as a number from min to max into *out; 0, or -1 with an error naming
 * `option` set (exit code 2). */
int parse_unsigned(const char *option, const char *text, unsigned long min, unsigned long max,
                   unsigned int *out);
int parse_double(const char *option, const char *text, double min, double max, double *out);
/* A size in bytes: a positive number, optionally followed by K, M, G or T (powers of 1024),
 * such as 512M or 1.5G; 0, or -1 with an error naming `option` set (exit code 2). */
int parse_bytes(const char *option, const char *text, uint64_t *out);

/* What a parser made of option `c` (its argument in optarg). */
enum option_parse {
    OPTION_TAKEN = 1,
    OPTION_UNKNOWN = 0,          /* not one of the parser's */
    OPTION_BAD_VALUE = -1,       /* a bad argument: the error is set */
    OPTION_IMPORTANCE_ONLY = -2, /* an importance pass option the command does not take */
};

/* OPTION_TAKEN when `status` (of a parse_*() call) is 0, else OPTION_BAD_VALUE. */
enum option_parse option_result(int status);

/* What --device chose: one device (its number, or -1 for the default: $IDMR_DEVICE, else the
 * first GPU, else device 0), every device (`all`), or a list of numbers (`0,2`; a list of one
 * is one device). */
typedef struct device_choice {
    int index;            /* one device */
    int all;              /* --device all */
    unsigned int count;   /* > 1: the list below */
    int list[SPPM_MAX_DEVICES];
} device_choice;

/* More than one device may be meant (all, or a list): for commands that take one. */
int device_choice_several(const device_choice *c);

/* --device's value `text` into *c: N, N,M,... (distinct, at most SPPM_MAX_DEVICES) or all. 0,
 * or -1 with the error set (exit code 2). */
int parse_device_choice(const char *text, device_choice *c);

/* Applies SPPM option `c` (--device into *devices). */
enum option_parse parse_sppm_option(int c, sppm_options *o, device_choice *devices);

/* Applies importance option `c`, the SPPM ones included. */
enum option_parse parse_importance_option(int c, importance_options *o, device_choice *devices);

/* The command line of a pass command (importance, reduce, render) as far as they share it. */
typedef struct pass_arguments {
    const char *command; /* the command's name, for messages */
    const char *scene;   /* the one SCENE argument */
    const char *output;  /* -o, --output; NULL if not given */
    device_choice devices; /* --device; by default one: IDMR_DEVICE, else the first GPU */
} pass_arguments;

/* A command's options besides -o: applies option `c` to the command's `context` (its options). */
typedef enum option_parse (*pass_option_parser)(int c, void *context,
                                                pass_arguments *arguments);

/* Walks argv with getopt_long over `table`: -o into arguments->output, every other option to
 * parse(c, context, arguments); one getopt or the parser does not take is option_error()'s,
 * one it calls OPTION_IMPORTANCE_ONLY "<command>: X is an importance pass option"; then the
 * one SCENE argument. Stops at the first failure; returns 0, or the exit code of the failure
 * it printed. */
int parse_pass_arguments(int argc, char **argv, const struct option *table,
                         pass_option_parser parse, void *context, pass_arguments *arguments);

/* The usage error for what getopt_long() returned as `c` when it took no option of `table`
 * (the option strings start with ':', and main() sets opterr to 0, so that getopt prints
 * nothing of its own): ':' an option without its value ("<command>: --target needs a value"),
 * '?' an unknown option, an ambiguous abbreviation (with the options it may mean), or a value
 * given to an option that takes none. Returns IDMR_EXIT_INPUT. */
int option_error(const char *command, int c, char **argv, const struct option *table);

/* The "<command>: expected one SCENE argument" check shared by the commands that load a
 * scene: 0, or the usage error's exit code. */
int expect_one_scene(const char *command, int argc);

#endif
