/* reduce_write.c — the write stage of `idmr reduce` (see reduce.h, reduce_stages.h): the
 * reduced scene in the staging directory. A Mitsuba scene: meshes/NAME.ply for every mesh the
 * plan decimated and every copy an instance placed (each read back and checked:
 * io/ply_check.h) and scene.xml, the input's XML with those shapes pointing to them and its
 * instances flattened (io/mitsuba_write.h); a glTF scene: scene.gltf (.glb) with the decimated
 * meshes in it (io/gltf.h); a pbrt-v4 scene: meshes/NAME.ply in each shape's own
 * space and scene.pbrt, the input's text with those Shape statements naming them (io/pbrt.h). */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"
#include "core/progress.h"
#include "io/gltf.h"
#include "io/mesh_io.h"
#include "io/mitsuba_write.h"
#include "io/pbrt.h"
#include "io/ply_check.h"
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
 * the later ones are numbered ("meshes/NAME.2.ply"). */
static void name_ply(reduce_state *st, size_t m)
{
    char name[256];
    importance_file_name(st->scene->meshes[m].name, name, sizeof name);
    size_t length = strlen(name) + 32;
    st->ply[m] = xmalloc(length);
    snprintf(st->ply[m], length, "meshes/%s.ply", name);
    for (unsigned int suffix = 2; ply_name_taken(st, m); suffix++)
        snprintf(st->ply[m], length, "meshes/%s.%u.ply", name, suffix);
}

/* Mesh m as loaded (read again if it was released: streaming) into the PLY at path. */
static int write_whole_mesh(scene *s, size_t m, const char *path)
{
    int released = s->meshes[m].released;
    if (scene_mesh_restore(s, m))
        return -1;
    const scene_mesh *mesh = &s->meshes[m];
    mesh_data data = {mesh->vertex_count, mesh->triangle_count, mesh->positions, mesh->indices,
                      mesh->texcoords,    mesh->normals,        0};
    int status = mesh_io_write_ply(path, &data, NULL, NULL, NULL);
    if (released)
        scene_mesh_release(s, m);
    return status;
}

/* A glTF scene: OUTDIR/scene.gltf or scene.glb with the decimated meshes in it (io/gltf.h). */
static int write_reduced_gltf(reduce_state *st)
{
    const scene *s = st->scene;
    gltf_replacement *replacements = xcalloc(st->count + 1, sizeof *replacements);
    for (size_t m = 0; m < st->count; m++)
        if (st->plan.decimate[m])
            replacements[st->meshes_written++] =
                (gltf_replacement){s->meshes[m].xml_line, &st->output[m].mesh};
    int status = gltf_write_reduced(s->file, st->staging, replacements, st->meshes_written,
                                    st->options->bundle);
    free(replacements);
    return status;
}

/* A pbrt-v4 scene: OUTDIR/meshes/NAME.ply for every decimated mesh, in the space its Shape
 * statement gives points in (io/pbrt.h: pbrt_mesh_to_object_space), then OUTDIR/scene.pbrt, the
 * input's text with those statements naming them. */
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
        /* An instance's copy is written whole where the plan left it so: the writer flattens
         * every instance (io/mitsuba_write.h). */
        if (!st->plan.decimate[m] && !mesh->instance_xml_file)
            continue;
        char path[PATH_MAX];
        name_ply(st, m);
        snprintf(path, sizeof path, "%s/%s", st->staging, st->ply[m]);
        status = (st->plan.decimate[m] ? mesh_io_write_ply(path, &st->output[m].mesh, NULL, NULL,
                                                           NULL)
                                       : write_whole_mesh(st->scene, m, path)) ||
                 ply_check_written(path);
        st->meshes_written += st->plan.decimate[m] != 0;
        replacements[replaced++] = (mitsuba_replacement){
            mesh->xml_file,     mesh->xml_line,          st->ply[m],
            mesh->flat_normals, mesh->instance_xml_file, mesh->instance_xml_line};
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
