/* fuzz_pbrt.c — libFuzzer target: a pbrt-v4 scene (with an included file and a PLY) through
 * pbrt_load (fuzz_inputs.h says how an input becomes files). Built and run by `make fuzz`. */
#include <stdlib.h>
#include <unistd.h>

#include "core/progress.h"
#include "fuzz_inputs.h"

static char fuzz_dir[] = "/tmp/idmr-fuzz-pbrt-XXXXXX";

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    if (!mkdtemp(fuzz_dir))
        abort();
    warn_silence(1);
    progress_set_quiet(1);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_pbrt_input(data, size, fuzz_dir);
    return 0;
}
