/* instanced_cornell.h — the instanced scene of the instanced passes' test and benchmark, and the
 * same scene written flat. Header-only, no cmocka (the benchmark uses it).
 *
 * The shipped Cornell box with its knot made the shape of a shapegroup and placed three times
 * (as test_reduce_instances places it): where the box has it ("seen"), half size, turned and
 * moved up left ("turned"), and mirrored in x with a non-uniform scale ("mirrored": -0.6, 0.45,
 * 0.75, so that normals need the placement's inverse transpose and the winding its reversal).
 * The flat scene writes the three copies as shapes of their own, each with the group's and the
 * instance's transforms in one to_world; the mirrored one with flip_normals, since a loader
 * keeps an instance's side where its placement mirrors but a plain shape's winding as its file
 * has it (core/scene.h, instances). */
#ifndef IDMR_TESTS_INSTANCED_CORNELL_H
#define IDMR_TESTS_INSTANCED_CORNELL_H

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif

#define INSTANCED_CORNELL_COPIES 3
static const char *const instanced_cornell_copies[INSTANCED_CORNELL_COPIES] = {"seen", "turned",
                                                                               "mirrored"};
static const char *const instanced_cornell_placements[INSTANCED_CORNELL_COPIES] = {
    "",
    "<scale value=\"0.5\"/><rotate y=\"1\" angle=\"40\"/><translate x=\"-0.3\" y=\"0.6\" z=\"0.1\"/>",
    "<scale x=\"-0.6\" y=\"0.45\" z=\"0.75\"/><translate y=\"0.2\"/>"};
/* Whether a copy's placement mirrors (the flat scene's flip_normals). */
static const int instanced_cornell_mirrored[INSTANCED_CORNELL_COPIES] = {0, 0, 1};
/* The knot's own transform in the Cornell box. */
#define INSTANCED_CORNELL_KNOT_TO_WORLD                                                         \
    "<rotate x=\"1\" angle=\"-70\"/><translate x=\"0.35\" y=\"-0.5\" z=\"0.25\"/>"

/* DIR/NAME: data/cornell/scene.xml with its knot shape replaced by `knots` (XML text); 0 or -1. */
static inline int instanced_cornell_write_with(const char *dir, const char *name,
                                               const char *knots, char *path, size_t size)
{
    FILE *f = fopen(IDMR_ROOT "/data/cornell/scene.xml", "rb");
    if (!f)
        return -1;
    static char xml[1 << 16];
    size_t length = fread(xml, 1, sizeof xml - 1, f);
    fclose(f);
    xml[length] = 0;
    char *knot = strstr(xml, "    <shape type=\"ply\" id=\"knot\">");
    char *after = knot ? strstr(knot, "</shape>") : NULL;
    if (!after)
        return -1;
    after += strlen("</shape>");
    snprintf(path, size, "%s/%s", dir, name);
    f = fopen(path, "w");
    if (!f)
        return -1;
    fprintf(f, "%.*s%s%s", (int)(knot - xml), xml, knots, after);
    return fclose(f) == 0 ? 0 : -1;
}

/* DIR/instanced.xml (flat = 0) or DIR/flat.xml (flat = 1) into path; 0 or -1. */
static inline int instanced_cornell_write(const char *dir, int flat, char *path, size_t size)
{
    char knot[PATH_MAX];
    static char text[16384];
    if (!realpath(IDMR_ROOT "/data/cornell/meshes/knot.ply", knot))
        return -1;
    int at = 0;
    if (!flat)
        at += snprintf(text, sizeof text,
                       "    <shape type=\"shapegroup\" id=\"knots\">\n"
                       "        <shape type=\"ply\" id=\"knot\">\n"
                       "            <string name=\"filename\" value=\"%s\"/>\n"
                       "            <transform name=\"to_world\">" INSTANCED_CORNELL_KNOT_TO_WORLD
                       "</transform>\n"
                       "            <ref id=\"orange\"/>\n"
                       "        </shape>\n"
                       "    </shape>\n",
                       knot);
    for (int k = 0; k < INSTANCED_CORNELL_COPIES; k++) {
        const char *name = instanced_cornell_copies[k], *placement = instanced_cornell_placements[k];
        if (!flat)
            at += snprintf(text + at, sizeof text - (size_t)at,
                           "    <shape type=\"instance\" id=\"%s\"><ref id=\"knots\"/>"
                           "<transform name=\"to_world\">%s</transform></shape>\n",
                           name, placement);
        else
            at += snprintf(text + at, sizeof text - (size_t)at,
                           "    <shape type=\"ply\" id=\"%s_knot\">\n"
                           "        <string name=\"filename\" value=\"%s\"/>\n"
                           "        <boolean name=\"flip_normals\" value=\"%s\"/>\n"
                           "        <transform name=\"to_world\">" INSTANCED_CORNELL_KNOT_TO_WORLD
                           "%s</transform>\n"
                           "        <ref id=\"orange\"/>\n"
                           "    </shape>\n",
                           name, knot, instanced_cornell_mirrored[k] ? "true" : "false", placement);
    }
    return instanced_cornell_write_with(dir, flat ? "flat.xml" : "instanced.xml", text, path,
                                        size);
}

#endif
