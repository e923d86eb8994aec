/* main.c — the idmr command line: global options, then dispatch to one command.
 *
 *   idmr [-v] devices [--json]
 *   idmr [-v] info SCENE [--json] [--no-bvh]
 *   idmr [-v] importance SCENE -o DIR [options]
 *   idmr [-v] reduce SCENE --target D -o OUTDIR [options]
 *   idmr [-v] render SCENE -o IMAGE [options]
 *   idmr compare A B [--diff DIFF.png] [--diff-max E] [--json]
 *   idmr convert SCENE -o OUT.xml|OUT.pbrt [--force]
 *   idmr help [COMMAND], idmr COMMAND --help   (command_help.c)
 *
 * Each command lives in command_<name>.c (commands.h); what they share of their options, in
 * options.c. Exit codes (core/error.h): 0 success, 1 runtime failure, 2 bad input or usage.
 * Every failure prints one "idmr: ..." message naming the file, element or call that failed.
 * Under mpirun (core/ranks.h) every rank runs the command; rank 0 prints the run's one failure
 * message, naming the rank that failed, once all ranks have met in ranks_finish(). */
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "core/error.h"
#include "core/ranks.h"

#define IDMR_VERSION "0.1.0"

static const struct {
    const char *name;
    int (*run)(int argc, char **argv);
} COMMANDS[] = {
    {"devices", command_devices}, {"info", command_info},     {"importance", command_importance},
    {"reduce", command_reduce},   {"render", command_render}, {"compare", command_compare},
    {"kernels", command_kernels}, {"convert", command_convert},
};

/* Whether a command's arguments (argv[0] its name) hold -h or --help, before any "--". */
static int asks_for_help(int argc, char **argv)
{
    for (int i = 1; i < argc && strcmp(argv[i], "--"); i++)
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help"))
            return 1;
    return 0;
}

/* The global options, then the command; its exit code. */
static int dispatch(int argc, char **argv)
{
    int first = 1;
    for (; first < argc && argv[first][0] == '-'; first++) {
        const char *arg = argv[first];
        if (!strcmp(arg, "-v") || !strcmp(arg, "--verbose")) {
            log_set_verbose(1);
        } else if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
            command_help(stdout);
            return 0;
        } else if (!strcmp(arg, "--version")) {
            printf("idmr %s\n", IDMR_VERSION);
            return 0;
        } else {
            return usage_error("unknown option %s", arg);
        }
    }
    if (first >= argc) {
        command_help(stderr);
        return IDMR_EXIT_INPUT;
    }
    const char *command = argv[first];
    if (!strcmp(command, "help")) {
        if (first + 1 >= argc) {
            command_help(stdout);
            return 0;
        }
        if (first + 2 < argc)
            return usage_error("help: expected at most one COMMAND");
        if (command_help_one(argv[first + 1], stdout))
            return usage_error("help: unknown command '%s'", argv[first + 1]);
        return 0;
    }
    optind = 1;
    opterr = 0; /* option_error() says what is wrong, once */
    for (size_t i = 0; i < sizeof COMMANDS / sizeof *COMMANDS; i++) {
        if (strcmp(command, COMMANDS[i].name))
            continue;
        if (asks_for_help(argc - first, argv + first))
            return command_help_one(command, stdout) ? IDMR_EXIT_INPUT : 0;
        return COMMANDS[i].run(argc - first, argv + first);
    }
    return usage_error("unknown command '%s'", command);
}

/* What the command printed on stdout reaches it, or the run fails: `info --json > FILE` on a
 * full disk must not end with exit 0 and half a JSON object. */
int main(int argc, char **argv)
{
    ranks_init(&argc, &argv);
    int code = dispatch(argc, argv);
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "idmr: cannot write standard output: %s\n",
                errno ? strerror(errno) : "write error");
        code = code ? code : IDMR_EXIT_FAILURE;
    }
    return ranks_finish(code);
}
