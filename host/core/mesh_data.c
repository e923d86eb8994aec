/* mesh_data.c — freeing the neutral mesh record (see mesh_data.h). */
#include "core/mesh_data.h"

#include <stdlib.h>
#include <string.h>

void mesh_data_free(mesh_data *mesh)
{
    if (!mesh)
        return;
    free(mesh->positions);
    free(mesh->indices);
    free(mesh->texcoords);
    free(mesh->normals);
    memset(mesh, 0, sizeof *mesh);
}
