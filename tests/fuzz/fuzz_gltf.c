/* fuzz_gltf.c — libFuzzer target: a glTF or GLB file through gltf_load (the document reader,
 * its checks, then Assimp on what they let through; fuzz_inputs.h says how an input becomes a
 * file). Built and run by `make fuzz`. */
#include <stdlib.h>
#include <unistd.h>

#include "core/progress.h"
#include "fuzz_inputs.h"

static char fuzz_dir[] = "/tmp/idmr-fuzz-gltf-XXXXXX";

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
    fuzz_gltf_input(data, size, fuzz_dir);
    return 0;
}
