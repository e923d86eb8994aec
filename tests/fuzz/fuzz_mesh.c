/* fuzz_mesh.c — libFuzzer target: one mesh reader, chosen by FUZZ_MESH_EXTENSION (".obj" and
 * ".off": host/io/mesh/mesh_text.c; ".ply": host/io/mesh/ply_check.c; ".stl":
 * host/io/mesh/mesh_stl.c; all idmr's own, behind mesh_io_read_oriented()). `make fuzz` builds
 * it once per extension. */
#include <stdlib.h>
#include <unistd.h>

#include "fuzz_inputs.h"

#ifndef FUZZ_MESH_EXTENSION
#error "build with -DFUZZ_MESH_EXTENSION='\".obj\"' (or .off, .ply)"
#endif

static char fuzz_dir[] = "/tmp/idmr-fuzz-mesh-XXXXXX";

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    if (!mkdtemp(fuzz_dir))
        abort();
    warn_silence(1);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_mesh_input(data, size, fuzz_dir, FUZZ_MESH_EXTENSION);
    return 0;
}
