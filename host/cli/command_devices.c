/* command_devices.c — `idmr devices [--json]`: the OpenCL platforms and devices, as a table
 * with the default device named and whether this build has MPI (core/ranks.h), or as a JSON
 * array of objects (one per device). */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "core/json.h"
#include "core/ranks.h"
#include "device/device.h"

static cJSON *devices_json(const device_info *list, size_t count)
{
    cJSON *root = cJSON_CreateArray();
    for (size_t i = 0; i < count; i++) {
        cJSON *d = cJSON_CreateObject();
        cJSON_AddNumberToObject(d, "index", list[i].index);
        cJSON_AddStringToObject(d, "platform", list[i].platform_name);
        cJSON_AddStringToObject(d, "name", list[i].name);
        cJSON_AddStringToObject(d, "kind", list[i].kind);
        cJSON_AddNumberToObject(d, "compute_units", list[i].compute_units);
        cJSON_AddNumberToObject(d, "global_memory", (double)list[i].global_memory);
        cJSON_AddBoolToObject(d, "host_unified_memory", list[i].host_unified);
        cJSON_AddStringToObject(d, "opencl_c_version", list[i].opencl_c_version);
        cJSON_AddBoolToObject(d, "int64_atomics", list[i].int64_atomics);
        cJSON_AddItemToArray(root, d);
    }
    return root;
}

static void devices_print(const device_info *list, size_t count)
{
    printf("%-3s %-20s %-5s %5s %10s  %-22s %s\n", "#", "platform", "kind", "CUs", "memory",
           "OpenCL C", "device");
    for (size_t i = 0; i < count; i++)
        printf("%-3d %-20.20s %-5s %5u %7.1f GiB  %-22.22s %s%s\n", list[i].index,
               list[i].platform_name, list[i].kind, list[i].compute_units,
               list[i].global_memory / 1073741824.0, list[i].opencl_c_version, list[i].name,
               list[i].int64_atomics ? "" : " (no 64-bit atomics)");
    const char *env = getenv("IDMR_DEVICE");
    printf("default: %s\n", env && *env ? "IDMR_DEVICE" : "first GPU, else device 0");
    if (ranks_built())
        printf("mpi: %s (run under mpirun, the importance pass is shared by the ranks; %d "
               "rank%s now)\n",
               ranks_library()[0] ? ranks_library() : "yes", ranks_count(),
               ranks_count() == 1 ? "" : "s");
    else
        printf("mpi: not in this build\n");
}

int command_devices(int argc, char **argv)
{
    int json = 0;
    static const struct option options[] = {{"json", no_argument, NULL, 'j'}, {0, 0, 0, 0}};
    int c;
    while ((c = getopt_long(argc, argv, ":", options, NULL)) != -1) {
        if (c == 'j')
            json = 1;
        else
            return option_error("devices", c, argv, options);
    }
    device_info *list;
    size_t count;
    if (device_list(&list, &count))
        return fail();
    if (json) {
        cJSON *root = devices_json(list, count);
        json_print(root);
        cJSON_Delete(root);
    } else {
        devices_print(list, count);
    }
    free(list);
    return 0;
}
