/* bench_common.h — shared by the benchmarks: the paper's DRAGON CORNELL BOX, written on the fly
 * (the Cornell box of data/cornell with the full Stanford dragon from ../shared/data in place
 * of the knot). Header-only. */
#ifndef IDMR_TESTS_BENCH_COMMON_H
#define IDMR_TESTS_BENCH_COMMON_H

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>


/* Writes DIR/dragon-box.xml into a new temporary directory; returns its path (static buffer)
 * or NULL. The dragon (0.2 units wide in its file) is scaled by 8 and stands on the floor. */
static inline const char *bench_write_dragon_box(void)
{
    static char dir[] = "/tmp/idmr-bench-XXXXXX";
    static char path[PATH_MAX];
    char dragon[PATH_MAX];
    if (!realpath("../shared/data/models/dragon_vrip.ply", dragon)) {
        fprintf(stderr, "bench: ../shared/data/models/dragon_vrip.ply is missing\n");
        return NULL;
    }
    if (!mkdtemp(dir))
        return NULL;
    snprintf(path, sizeof path, "%s/dragon-box.xml", dir);
    FILE *f = fopen(path, "w");
    if (!f)
        return NULL;
    fprintf(f,
            "<scene version=\"3.0.0\">\n"
            "  <sensor type=\"perspective\">\n"
            "    <float name=\"fov\" value=\"39.3077\"/>\n"
            "    <string name=\"fov_axis\" value=\"smaller\"/>\n"
            "    <transform name=\"to_world\"><lookat origin=\"0, 0, 3.9\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\n"
            "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"256\"/><integer name=\"height\" value=\"256\"/></film>\n"
            "  </sensor>\n"
            "  <bsdf type=\"diffuse\" id=\"white\"><rgb name=\"reflectance\" value=\"0.725, 0.71, 0.68\"/></bsdf>\n"
            "  <bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" value=\"0.63, 0.065, 0.05\"/></bsdf>\n"
            "  <bsdf type=\"diffuse\" id=\"green\"><rgb name=\"reflectance\" value=\"0.14, 0.45, 0.091\"/></bsdf>\n"
            "  <shape type=\"rectangle\" id=\"floor\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"-90\"/><translate y=\"-1\"/></transform><ref id=\"white\"/></shape>\n"
            "  <shape type=\"rectangle\" id=\"ceiling\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"90\"/><translate y=\"1\"/></transform><ref id=\"white\"/></shape>\n"
            "  <shape type=\"rectangle\" id=\"back\"><transform name=\"to_world\"><translate z=\"-1\"/></transform><ref id=\"white\"/></shape>\n"
            "  <shape type=\"rectangle\" id=\"red_wall\"><transform name=\"to_world\"><rotate y=\"1\" angle=\"90\"/><translate x=\"-1\"/></transform><ref id=\"red\"/></shape>\n"
            "  <shape type=\"rectangle\" id=\"green_wall\"><transform name=\"to_world\"><rotate y=\"1\" angle=\"-90\"/><translate x=\"1\"/></transform><ref id=\"green\"/></shape>\n"
            "  <shape type=\"rectangle\" id=\"light\">\n"
            "    <transform name=\"to_world\"><scale x=\"0.25\" y=\"0.25\"/><rotate x=\"1\" angle=\"90\"/><translate y=\"0.99\"/></transform>\n"
            "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0, 0, 0\"/></bsdf>\n"
            "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"17, 12, 4\"/></emitter>\n"
            "  </shape>\n"
            "  <shape type=\"ply\" id=\"dragon\">\n"
            "    <string name=\"filename\" value=\"%s\"/>\n"
            "    <transform name=\"to_world\"><translate x=\"0.0059\" y=\"-0.0527\" z=\"0.0046\"/><scale value=\"8\"/><rotate y=\"1\" angle=\"-25\"/><translate y=\"-1\"/></transform>\n"
            "    <ref id=\"white\"/>\n"
            "  </shape>\n"
            "</scene>\n",
            dragon);
    fclose(f);
    return path;
}

static inline void bench_remove_dragon_box(const char *path)
{
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    unlink(path);
    if (slash) {
        *slash = '\0';
        rmdir(dir);
    }
}

#endif
