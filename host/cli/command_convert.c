/* command_convert.c — `idmr convert SCENE -o OUT [--force] [--quiet]`: the scene as idmr reads
 * it (Mitsuba XML or glTF), written in the format OUT's extension names: .xml a Mitsuba 3 scene,
 * .pbrt a pbrt-v4 scene, with the meshes as world-space PLYs in the folder OUT's stem names
 * (io/scene_export.h); then one summary line on stdout. */
#include <getopt.h>
#include <stdio.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/scene_export.h"
#include "io/scene_load.h"

int command_convert(int argc, char **argv)
{
    static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                            {"force", no_argument, NULL, 'f'},
                                            {"quiet", no_argument, NULL, 'q'},
                                            {0, 0, 0, 0}};
    const char *output = NULL;
    int force = 0, c;
    while ((c = getopt_long(argc, argv, ":o:", options, NULL)) != -1) {
        if (c == 'o')
            output = optarg;
        else if (c == 'f')
            force = 1;
        else if (c == 'q')
            progress_set_quiet(1);
        else
            return option_error("convert", c, argv, options);
    }
    int code = expect_one_scene("convert", argc);
    if (code)
        return code;
    if (!output)
        return usage_error("convert: -o OUT is required (OUT.xml: Mitsuba 3, OUT.pbrt: pbrt-v4)");
    scene_export_format format;
    if (scene_export_format_of(output, &format))
        return fail(); /* before the scene is read: a wrong name costs no load */
    scene *s = scene_load(argv[optind]);
    if (!s)
        return fail();
    if (scene_export(s, output, force)) {
        scene_free(s);
        return fail();
    }
    printf("%s: %s scene, %zu meshes (%llu triangles), %zu materials, %zu lights\n", output,
           format == SCENE_EXPORT_MITSUBA ? "Mitsuba 3" : "pbrt-v4", s->mesh_count,
           (unsigned long long)s->rendered_triangle_count, s->material_count, s->light_count);
    scene_free(s);
    return 0;
}
