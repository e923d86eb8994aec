/* fuzz_simulation.c — libFuzzer target: the simulation-file reader of `idmr reduce --simulation`
 * (host/passes/importance_file.c), for the shipped Cornell box without its knot
 * (fuzz_inputs.h: fuzz_simulation_input, fuzz_simulation_scene). Its seeds are files
 * `idmr importance` wrote for that scene (tests/fuzz/corpus/simulation). */
#include <stdlib.h>
#include <unistd.h>

#include "fuzz_inputs.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif

static char fuzz_dir[] = "/tmp/idmr-fuzz-simulation-XXXXXX";
static scene *fuzz_scene;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    if (!mkdtemp(fuzz_dir))
        abort();
    warn_silence(1);
    fuzz_scene = fuzz_simulation_scene(IDMR_ROOT, fuzz_dir);
    if (!fuzz_scene)
        abort();
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_simulation_input(data, size, fuzz_dir, fuzz_scene);
    return 0;
}
