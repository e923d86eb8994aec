/* command_help.c — the help text of bin/idmr: the whole of it (idmr --help, idmr help) and one
 * command's part (idmr help COMMAND, idmr COMMAND --help). Each command's text is written once,
 * in COMMAND_HELP; the SPPM options, which importance, reduce and render share, once as well. */
#include <string.h>

#include "cli/commands.h"

static const char HEADER[] =
    "usage: idmr [-v] COMMAND [options]\n"
    "\n"
    "Illumination-driven mesh reduction: learn which triangles carry the light a camera\n"
    "sees, then decimate a Mitsuba scene to a vertex budget.\n";

/* One command's usage lines and options. `sppm`: it takes the SPPM options too. */
static const struct {
    const char *name;
    int sppm;
    const char *text;
} COMMAND_HELP[] = {
    {"devices", 0, "  devices [--json]          list OpenCL platforms and devices\n"},
    {"info", 0,
     "  info SCENE [--json]       meshes, materials, lights, camera, bounding box, feature\n"
     "                            bits and device memory of a Mitsuba scene\n"
     "      --no-bvh              skip the BVH build (memory then excludes the BVH)\n"},
    {"importance", 1,
     "  importance SCENE -o DIR   learn which triangles carry the light the camera sees;\n"
     "                            writes DIR/report.json, convergence.csv, importance.png,\n"
     "                            importance/<mesh>.ply and simulation.bin (the sums before\n"
     "                            any weight, for reduce --simulation); takes the SPPM options\n"
     "      --tolerance E         stop once the change per iteration stays below E\n"
     "      --gamma G             weight of camera paths against light paths (default 1)\n"
     "      --shadow-weight W     weight of the triangles that cast the shadows the camera\n"
     "                            sees (default 1; 0: no shadow rays)\n"},
    {"reduce", 1,
     "  reduce SCENE --target D -o OUTDIR   (or --memory-budget BYTES, or --max-error E)\n"
     "                            the reduced scene: OUTDIR/scene.xml and meshes/*.ply with\n"
     "                            about D of all vertices (scene.pbrt for a pbrt-v4 scene,\n"
     "                            scene.gltf/.glb for glTF); takes the options of importance\n"
     "      --method M            combined (default: importance budgets each mesh and\n"
     "                            weights its quadric error; open boundaries locked),\n"
     "                            importance (the paper's: importance orders collapses),\n"
     "                            quadric (uniform D, view-independent) or\n"
     "                            importance-quadric (importance budgets per mesh, plain\n"
     "                            quadric collapses within each)\n"
     "      --factor-tolerance F  stop the importance pass once, twice in a row between\n"
     "                            checkpoints 5 iterations apart, the plan of vertices per\n"
     "                            mesh moves less than F of the budget (default 0.01; 0: run\n"
     "                            all --iterations, which stay the cap) and, where collapses\n"
     "                            follow importance, the vertex ranks change less than R\n"
     "      --ranking-tolerance R 1 - Spearman's rho (default 0.05; 0: ranks not watched)\n"
     "      --simulation FILE     no importance pass: the simulation.bin of an earlier\n"
     "                            `idmr importance` on this scene, weighted by this run's\n"
     "                            --gamma and --shadow-weight\n"
     "      --initial D0          run the importance pass on the scene quadric-reduced to D0\n"
     "                            (meshes under 1024 vertices left whole) and copy its\n"
     "                            importance back to the originals along the collapse chains\n"
     "      --passes K            K importance passes (default 1), each on the last one's\n"
     "                            result, remapped to the originals again\n"
     "      --memory-budget BYTES the device memory (512M, 2G) the reduced scene may take\n"
     "                            when rendered (geometry, BVH, buffers at the scene's film\n"
     "                            and --photons); the target becomes what fits if\n"
     "                            smaller, an initial reduction is chosen when the importance\n"
     "                            pass would not fit, and no pass allocates more; on a\n"
     "                            device sharing the host's memory (a CPU) the whole run\n"
     "                            stays within it while simulating and decimating\n"
     "      --max-error E         instead of --target: the smallest D whose reduced scene's\n"
     "                            image changes by at most E (the reduction RMSE of\n"
     "                            `compare --paired`, plus its standard error), searched by\n"
     "                            rendering the original and each reduction with seeds 1\n"
     "                            and 2 (one importance pass for all); curve in report.json\n"
     "      --max-error-relative F  the same with E = F x the original's mean radiance\n"
     "      --max-error-step S    stop when the failing and passing D are within 1 + S\n"
     "                            (default 0.1)\n"
     "      --check-iterations N  SPPM iterations of each check render (default 16)\n"
     "      --check-resolution F  film scale of the check renders (default 0.25)\n"
     "      --check-photons N     photon paths per check iteration (default 50000)\n"
     "      --refine N            after the reduction, up to N rounds of error-driven\n"
     "                            refinement at the same D: where the check renders changed,\n"
     "                            traced back to the triangles that caused it, gets budget;\n"
     "                            the round with the smallest error is kept (with --target or\n"
     "                            --max-error; methods with importance)\n"
     "      --min-vertices N      meshes this small are not decimated (default 16)\n"
     "      --max-normal-angle A  no collapse turns a face more than A degrees (default 60)\n"
     "      --uv-weight W         combined: a texture-coordinate change of 1 costs as much as\n"
     "                            moving W times the mesh's extent (default 10; 0: free)\n"
     "      --normal-weight W     the same for a change of the shading normal (default 0.5)\n"
     "      --recompute-normals   a mesh file without normals is written without them, for\n"
     "                            the reader to compute from the reduced mesh (default: the\n"
     "                            smooth normals the original shades with are written)\n"
     "      --keep NAME           never decimate mesh NAME (repeatable; emitters never are)\n"
     "      --threads N           decimation threads (default: all cores)\n"
     "      --force               write into a non-empty OUTDIR\n"
     "      --bundle              copy every file the scene reads (textures, meshes kept,\n"
     "                            fragments) into OUTDIR, so OUTDIR can be moved alone;\n"
     "                            without it, OUTDIR/scene.xml names them relative to OUTDIR\n"},
    {"render", 1,
     "  render SCENE -o IMAGE     stochastic progressive photon mapping: IMAGE.exr (linear),\n"
     "                            IMAGE.png (sRGB) and IMAGE.json (timings, device memory);\n"
     "                            takes the SPPM options\n"
     "      --exposure EV         PNG brightness: linear values times 2^EV (default 0)\n"},
    {"compare", 0,
     "  compare A B [--diff D.png] [--json]\n"
     "                            RMSE, PSNR and relative MSE of image A against the\n"
     "                            reference B (linear RGB), and a false-colour error image\n"
     "      --diff-max E          top of the error image's ramp (default: the 99th\n"
     "                            percentile of the error)\n"
     "  compare --paired A1 A2 B1 B2 [--tile N] [--json]\n"
     "                            the change a reduction makes to the converged image, render\n"
     "                            noise cancelled: A = original, B = reduced scene, 1 and 2\n"
     "                            two seeds; reduction_rmse ± standard error (N-pixel tiles,\n"
     "                            default 16)\n"},
    {"convert", 0,
     "  convert SCENE -o OUT      the scene as idmr reads it, written in the format OUT's\n"
     "                            extension names: OUT.xml a Mitsuba 3 scene, OUT.pbrt a\n"
     "                            pbrt-v4 scene; meshes as world-space PLYs (and the\n"
     "                            environment map as an EXR) in the folder OUT's stem names\n"
     "      --force               replace OUT and files in that folder\n"
     "      --quiet               no progress on stderr while loading\n"},
    {"kernels", 0,
     "  kernels [--device N] [--quiet]\n"
     "                            build every kernel program variant on the device (a\n"
     "                            kernel error fails with its build log; warms the cache)\n"},
};

static const char SPPM_OPTIONS[] =
    "SPPM options (the photon-mapping core of importance, reduce and render):\n"
    "      --iterations N        iterations (default 100; render: 64)\n"
    "      --time-limit S        stop after the iteration in which S seconds pass\n"
    "      --radius R            first gather radius (default: 2.5 pixel footprints at the\n"
    "                            median distance of what the camera sees)\n"
    "      --photons P           photon paths per iteration (default 1,000,000 on a GPU,\n"
    "                            500,000 on a CPU)\n"
    "      --alpha A             SPPM radius reduction (default 0.7)\n"
    "      --resolution F        scale of the scene's film for hit points (default 1)\n"
    "      --max-depth D         surface interactions of a camera path, the emitter it sees\n"
    "                            last included, as Mitsuba's max_depth counts (default 16,\n"
    "                            the paper's; render: 64, with Russian roulette from 16)\n"
    "      --seed S              random seed (default 1)\n"
    "      --device N            OpenCL device (see `idmr devices`); importance and reduce\n"
    "                            also take a list (0,2) or all: the importance pass on those\n"
    "                            devices at once, the same result as on the first alone\n"
    "      --quiet               no progress on stderr\n"
    "      --generic             kernels with every feature, not only the scene's\n";

static const char GLOBAL_OPTIONS[] =
    "global options:\n"
    "  -v, --verbose             log progress, kernel build options and timings\n"
    "  -h, --help                this text (idmr COMMAND --help: that command's)\n"
    "      --version             print the version\n"
    "\n"
    "environment:\n"
    "  IDMR_DEVICE=N             default OpenCL device (see `idmr devices`)\n"
    "  IDMR_ROOT=DIR             directory holding kernels/ and include/\n"
    "  IDMR_CACHE_DIR=DIR        compiled kernel cache (default ~/.cache/idmr; off: none)\n";

void command_help(FILE *out)
{
    fprintf(out, "%s\ncommands:\n", HEADER);
    for (size_t i = 0; i < sizeof COMMAND_HELP / sizeof *COMMAND_HELP; i++)
        fputs(COMMAND_HELP[i].text, out);
    fprintf(out, "\n%s\n%s", SPPM_OPTIONS, GLOBAL_OPTIONS);
}

int command_help_one(const char *name, FILE *out)
{
    for (size_t i = 0; i < sizeof COMMAND_HELP / sizeof *COMMAND_HELP; i++) {
        if (strcmp(COMMAND_HELP[i].name, name))
            continue;
        fprintf(out, "usage: idmr [-v] %s ...\n\n%s", name, COMMAND_HELP[i].text);
        if (COMMAND_HELP[i].sppm)
            fprintf(out, "\n%s", SPPM_OPTIONS);
        fputs("\n(all commands: `idmr --help`)\n", out);
        return 0;
    }
    return -1;
}
