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
 * has it (core/scene.h, instances). Either may be written with the whole scene scaled (every
 * top-level transform, the sensor's included, followed by a uniform scale), to try the passes'
 * numbers far from the unit scale: the image stays the same. instanced_cornell_write_variant()
 * writes other placements and another material for the knot (test_instance_totals: a copy
 * hidden behind the back wall, mirror knots). */
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

/* Writes text to f with `<scale value="scale"/>` before every "</transform>" (none for 1). */
static inline void instanced_cornell_put_scaled(FILE *f, const char *text, size_t length,
                                                double scale)
{
    const char *end = text + length;
    for (const char *at; text < end; text = at + strlen("</transform>")) {
        at = strstr(text, "</transform>");
        if (!at || at >= end) {
            fprintf(f, "%.*s", (int)(end - text), text);
            return;
        }
        fprintf(f, "%.*s", (int)(at - text), text);
        if (scale != 1.0)
            fprintf(f, "<scale value=\"%.17g\"/>", scale);
        fputs("</transform>", f);
    }
}

/* DIR/NAME: data/cornell/scene.xml with its knot shape replaced by `group` and `knots` (XML
 * text), every transform but the group's scaled by `scale`; 0 or -1. */
static inline int instanced_cornell_write_with(const char *dir, const char *name,
                                               const char *group, const char *knots,
                                               double scale, char *path, size_t size)
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
    instanced_cornell_put_scaled(f, xml, (size_t)(knot - xml), scale);
    fputs(group, f);
    instanced_cornell_put_scaled(f, knots, strlen(knots), scale);
    instanced_cornell_put_scaled(f, after, strlen(after), scale);
    return fclose(f) == 0 ? 0 : -1;
}

/* The knot's copies and material: copy k is named names[k] (its instance's id; the flat
 * scene's shape is NAME_knot), placed by placements[k] (transform XML after the knot's own),
 * mirroring where mirrored[k]; bsdf is the knot's material (XML: a <ref> or a <bsdf>). */
typedef struct instanced_cornell_variant {
    int count;
    const char *const *names;
    const char *const *placements;
    const int *mirrored;
    const char *bsdf;
} instanced_cornell_variant;

/* DIR/instancedTAG-SCALE.xml (flat = 0) or DIR/flatTAG-SCALE.xml (flat = 1) of variant v, the
 * whole scene scaled by `scale` (1: as the box is), into path; 0 or -1. */
static inline int instanced_cornell_write_variant(const char *dir, int flat, double scale,
                                                  const instanced_cornell_variant *v,
                                                  const char *tag, char *path, size_t size)
{
    char knot[PATH_MAX], file[128];
    static char group[PATH_MAX + 1024], text[16384];
    if (!realpath(IDMR_ROOT "/data/cornell/meshes/knot.ply", knot))
        return -1;
    int at = 0;
    group[0] = 0;
    if (!flat)
        snprintf(group, sizeof group,
                 "    <shape type=\"shapegroup\" id=\"knots\">\n"
                 "        <shape type=\"ply\" id=\"knot\">\n"
                 "            <string name=\"filename\" value=\"%s\"/>\n"
                 "            <transform name=\"to_world\">" INSTANCED_CORNELL_KNOT_TO_WORLD
                 "</transform>\n"
                 "            %s\n"
                 "        </shape>\n"
                 "    </shape>\n",
                 knot, v->bsdf);
    for (int k = 0; k < v->count; k++) {
        const char *name = v->names[k], *placement = v->placements[k];
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
                           "        %s\n"
                           "    </shape>\n",
                           name, knot, v->mirrored[k] ? "true" : "false", placement, v->bsdf);
    }
    snprintf(file, sizeof file, "%s%s-%g.xml", flat ? "flat" : "instanced", tag, scale);
    return instanced_cornell_write_with(dir, file, group, text, scale, path, size);
}

/* DIR/instanced-SCALE.xml (flat = 0) or DIR/flat-SCALE.xml (flat = 1): the three copies above,
 * the knot orange; into path; 0 or -1. */
static inline int instanced_cornell_write(const char *dir, int flat, double scale, char *path,
                                          size_t size)
{
    const instanced_cornell_variant three = {INSTANCED_CORNELL_COPIES, instanced_cornell_copies,
                                             instanced_cornell_placements,
                                             instanced_cornell_mirrored, "<ref id=\"orange\"/>"};
    return instanced_cornell_write_variant(dir, flat, scale, &three, "", path, size);
}

#endif
