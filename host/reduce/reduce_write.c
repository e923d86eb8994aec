/* reduce_write.c — the write stage of `idmr reduce` (see reduce.h, reduce_stages.h): the
 * reduced scene in the staging directory. A Mitsuba scene: meshes/NAME.ply for every mesh the
 * plan decimated, a shapegroup's shape once, in the group's space (each read back and checked:
 * io/mesh/ply_check.h), and scene.xml, the input's XML with those shapes pointing to them and its
 * shapegroups and instances kept (io/mitsuba/mitsuba_write.h, reduce_instances.c); a glTF scene:
 * scene.gltf (.glb) with the decimated meshes in it, a mesh that nodes share still shared
 * (io/gltf/gltf.h); a pbrt-v4 scene: meshes/NAME.ply in each shape's own space and scene.pbrt, the
 * input's text with those Shape statements naming them, an object's shape once (io/pbrt/pbrt.h). */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"
#include "core/progress.h"
#include "io/gltf/gltf.h"
#include "io/mesh/mesh_io.h"
#include "io/mitsuba/mitsuba_write.h"
#include "io/pbrt/pbrt.h"
#include "io/mesh/ply_check.h"
#include "io/scene_load.h"
#include "passes/importance_outputs.h"
#include "reduce/reduce_stages.h"

/* Whether an earlier mesh's PLY has the name mesh m's would get. */
static int ply_name_taken(const reduce_state *st, size_t m)
{
    for (size_t k = 0; k < m; k++)
        if (st->ply[k] && strcmp(st->ply[k], st->ply[m]) == 0)
            return 1;
    return 0;
}

/* st->ply[m] = "meshes/NAME.ply"; two mesh names can make the same file name ("a/b", "a_b"):
 * the later ones are numbered ("meshes/NAME.2.ply"). A shapegroup's shape is named as in its
 * group: without the "INSTANCE/" its first copy's name begins with (io/mitsuba/mitsuba_shape.c). */
static void name_ply(reduce_state *st, size_t m)
{
    char name[256];
    const scene_mesh *mesh = &st->scene->meshes[m];
    const char *in_group = mesh->instanced ? strchr(mesh->name, '/') : NULL;
    importance_file_name(in_group ? in_group + 1 : mesh->name, name, sizeof name);
    size_t length = strlen(name) + 32;
    st->ply[m] = xmalloc(length);
    snprintf(st->ply[m], length, "meshes/%s.ply", name);
    for (unsigned int suffix = 2; ply_name_taken(st, m); suffix++)
        snprintf(st->ply[m], length, "meshes/%s.%u.ply", name, suffix);
}

/* A glTF scene: OUTDIR/scene.gltf or scene.glb with the decimated meshes in it (io/gltf/gltf.h). */
static int write_reduced_gltf(reduce_state *st)
{
    const scene *s = st->scene;
    gltf_replacement *replacements = xcalloc(st->count + 1, sizeof *replacements);
    size_t replaced = 0;
    for (size_t m = 0; m < st->count; m++) {
        /* A copy of a primitive that several nodes name shares its first copy's reduction
         * (reduce_instances.c): its node keeps naming the same mesh. */
        size_t first = reduce_instance_representative(st, m);
        int shared = first != m;
        if (!st->plan.decimate[first])
            continue;
        replacements[replaced++] =
            (gltf_replacement){s->meshes[m].xml_line, &st->output[first].mesh, shared};
        st->meshes_written += !shared;
    }
    int status =
        gltf_write_reduced(s->file, st->staging, replacements, replaced, st->options->bundle);
    free(replacements);
    return status;
}

/* A pbrt-v4 scene: OUTDIR/meshes/NAME.ply for every decimated mesh, in the space its Shape
 * statement gives points in (io/pbrt/pbrt.h: pbrt_mesh_to_object_space), then OUTDIR/scene.pbrt,
 * the input's text with those statements naming them. */
static int write_reduced_pbrt(reduce_state *st, const char *meshes)
{
    const scene *s = st->scene;
    if (st->options->bundle)
        warn("--bundle is not applied to a pbrt scene: its paths are written relative to %s "
             "(or absolute)",
             st->outdir);
    int status = files_make_directory(meshes);
    st->ply = xcalloc(st->count + 1, sizeof *st->ply);
    pbrt_replacement *replacements = xcalloc(st->count + 1, sizeof *replacements);
    for (size_t m = 0; m < st->count && !status; m++) {
        if (!st->plan.decimate[m])
            continue;
        char path[PATH_MAX];
        mesh_data object;
        name_ply(st, m);
        snprintf(path, sizeof path, "%s/%s", st->staging, st->ply[m]);
        status = pbrt_mesh_to_object_space(&s->meshes[m], &st->output[m].mesh, &object) ||
                 mesh_io_write_ply(path, &object, NULL, NULL, NULL) || ply_check_written(path);
        mesh_data_free(&object);
        replacements[st->meshes_written++] = (pbrt_replacement){
            s->meshes[m].xml_file, s->meshes[m].source_offset, s->meshes[m].xml_line, st->ply[m]};
    }
    if (!status)
        status = pbrt_write_reduced(s->file, st->staging, replacements, st->meshes_written);
    free(replacements);
    return status;
}

/* OUTDIR/meshes/NAME.ply for every decimated mesh, then OUTDIR/scene.xml pointing to them; or,
 * for a glTF scene, OUTDIR/scene.gltf (.glb); for a pbrt-v4 scene, OUTDIR/scene.pbrt. */
int reduce_write(reduce_state *st)
{
    const scene *s = st->scene;
    double start = monotonic_seconds();
    if (scene_is_gltf(s)) {
        int status = write_reduced_gltf(st);
        st->seconds_write = monotonic_seconds() - start;
        return status;
    }
    char meshes[PATH_MAX];
    snprintf(meshes, sizeof meshes, "%s/meshes", st->staging);
    if (scene_is_pbrt(s)) {
        int status = write_reduced_pbrt(st, meshes);
        st->seconds_write = monotonic_seconds() - start;
        return status;
    }
    int status = files_make_directory(meshes);
    st->ply = xcalloc(st->count + 1, sizeof *st->ply);
    mitsuba_replacement *replacements = xcalloc(st->count + 1, sizeof *replacements);
    size_t replaced = 0;
    for (size_t m = 0; m < st->count && !status; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        /* Instances stay: a shapegroup's shape is written once, from its first copy, in the
         * group's own space (reduce_instances.c), and the group and its instances as they are. */
        if (!st->plan.decimate[m] || reduce_instance_follower(st, m))
            continue;
        char path[PATH_MAX];
        name_ply(st, m);
        snprintf(path, sizeof path, "%s/%s", st->staging, st->ply[m]);
        if (mesh->instanced) {
            mesh_data prototype;
            status = reduce_instance_prototype_mesh(st, m, &prototype) ||
                     mesh_io_write_ply(path, &prototype, NULL, NULL, NULL);
            mesh_data_free(&prototype);
        } else {
            status = mesh_io_write_ply(path, &st->output[m].mesh, NULL, NULL, NULL);
        }
        status = status || ply_check_written(path);
        st->meshes_written++;
        replacements[replaced++] =
            (mitsuba_replacement){mesh->xml_file, mesh->xml_line, st->ply[m], mesh->flat_normals};
    }
    if (!status)
        status = mitsuba_write_reduced(s->file, st->staging, replacements, replaced,
                                       st->options->bundle);
    free(replacements);
    st->seconds_write = monotonic_seconds() - start;
    return status;
}

void reduce_write_free(reduce_state *st)
{
    for (size_t m = 0; st->ply && m < st->count; m++)
        free(st->ply[m]);
    free(st->ply);
    st->ply = NULL;
}
