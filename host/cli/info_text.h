/* info_text.h — the text form of `idmr info`, printed from the JSON object that --json prints
 * (command_info.c describes its keys), so that the two forms cannot disagree. */
#ifndef IDMR_CLI_INFO_TEXT_H
#define IDMR_CLI_INFO_TEXT_H
#include <cjson/cJSON.h>

/* Prints `info` on stdout: the scene, a table of meshes, materials and lights counted by kind,
 * camera, bounding box, features, device memory and, when built, the BVH. */
void info_text_print(const cJSON *info);

#endif
