/* commands.h — the subcommands of bin/idmr, one entry point each, called by main() with the
 * command's own argc/argv (argv[0] is the command's name; getopt's optind reset to 1).
 * Each returns the process's exit code (core/error.h): 0, 1 runtime failure, 2 bad input or
 * usage, after printing one "idmr: ..." line for a failure. */
#ifndef IDMR_CLI_COMMANDS_H
#define IDMR_CLI_COMMANDS_H
#include <stdio.h>

/* idmr devices [--json]: the OpenCL platforms and devices. */
int command_devices(int argc, char **argv);

/* idmr info SCENE [--json] [--no-bvh]: what the scene holds and what it costs on a device. */
int command_info(int argc, char **argv);

/* idmr importance SCENE -o DIR [options]: the importance pass and its outputs. */
int command_importance(int argc, char **argv);

/* idmr reduce SCENE --target D -o OUTDIR [options]: the reduced scene. */
int command_reduce(int argc, char **argv);

/* idmr render SCENE -o IMAGE [options]: the SPPM render and its report. */
int command_render(int argc, char **argv);

/* idmr compare A B [--diff D.png] [--diff-max E] [--json]: image A against the reference B;
 * idmr compare --paired A1 A2 B1 B2 [--tile N] [--json]: the reduction error, noise cancelled. */
int command_compare(int argc, char **argv);

/* idmr convert SCENE -o OUT [--force] [--quiet]: the scene written as a Mitsuba 3 (.xml) or
 * pbrt-v4 (.pbrt) scene. */
int command_convert(int argc, char **argv);

/* idmr kernels [--device N] [--quiet]: builds every kernel program variant (make kernels). */
int command_kernels(int argc, char **argv);

/* The help text (idmr --help, idmr help) on `out`. */
void command_help(FILE *out);

/* One command's usage and options (idmr help COMMAND, idmr COMMAND --help) on `out`; -1 when
 * there is no such command. */
int command_help_one(const char *name, FILE *out);

#endif
