/* fuzz_scene.c — libFuzzer target: the Mitsuba scene loader with its includes and the meshes
 * it reads (fuzz_inputs.h says how an input becomes files). Built and run by `make fuzz`. */
#include <stdlib.h>
#include <unistd.h>

#include "fuzz_inputs.h"

static char fuzz_dir[] = "/tmp/idmr-fuzz-scene-XXXXXX";

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    if (!mkdtemp(fuzz_dir))
        abort();
    warn_silence(1); /* warnings would flood the fuzzer's output */
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_scene_input(data, size, fuzz_dir);
    return 0;
}
