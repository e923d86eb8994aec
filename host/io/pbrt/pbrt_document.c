/* pbrt_document.c — the pbrt-v4 reader's entry point (pbrt_load) and its statement walk: each
 * file read whole and tokenised, statements taken in order with pbrt's graphics state (the CTM,
 * ReverseOrientation, the current material and area light) kept on an attribute stack, the
 * transform statements applied to the CTM as pbrt applies them (each one multiplies the CTM on
 * the right: it acts first on the points given after it), Include/Import read in place, named
 * coordinate systems, and ObjectBegin/End/ObjectInstance (the shapes of an object kept in
 * object space until an instance puts a world-space copy of each in the scene). Statements for
 * what idmr does not simulate are warned about once; an unknown statement is an error. */
#include "io/pbrt/pbrt_loader.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/mitsuba_paths.h"

#define PBRT_MAX_INCLUDE_DEPTH 32

int pbrt_is_scene_file(const char *path)
{
    size_t n = strlen(path);
    return n >= 5 && strcmp(path + n - 5, ".pbrt") == 0;
}

char *pbrt_resolve_path(const pbrt_loader *ld, const char *written)
{
    return mitsuba_path_join(ld->scene_dir, written);
}

char *pbrt_read_text(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        error_set(IDMR_EXIT_INPUT, "cannot open '%s': %s", path, strerror(errno));
        return NULL;
    }
    size_t capacity = 1 << 16, used = 0;
    char *text = xmalloc(capacity);
    for (;;) {
        size_t n = fread(text + used, 1, capacity - used - 1, f);
        used += n;
        if (used + 1 < capacity)
            break;
        capacity *= 2;
        text = xrealloc(text, capacity);
    }
    int failed = ferror(f);
    fclose(f);
    if (failed) {
        free(text);
        error_set(IDMR_EXIT_INPUT, "cannot read '%s'", path);
        return NULL;
    }
    text[used] = '\0';
    *size = used;
    return text;
}

/* ---- statement arguments ---- */

/* One string argument of `statement`; malloc'd into *out. */
static int string_arg(pbrt_lexer *lx, const char *statement, char **out)
{
    pbrt_token t;
    if (pbrt_lexer_next(lx, &t))
        return -1;
    if (t.kind != PBRT_TOKEN_STRING)
        return pbrt_fail(lx->file, t.line, "%s: expected a quoted string, found '%.*s'", statement,
                         (int)(t.length > 64 ? 64 : t.length), t.text);
    *out = pbrt_token_string(&t);
    return 0;
}

/* `count` numbers, bracketed or not. */
static int number_args(pbrt_lexer *lx, const char *statement, int line, double *out, int count)
{
    pbrt_token t;
    if (pbrt_lexer_peek(lx, &t))
        return -1;
    int bracketed = t.kind == PBRT_TOKEN_OPEN;
    if (bracketed)
        pbrt_lexer_next(lx, &t);
    for (int i = 0; i < count; i++) {
        if (pbrt_lexer_next(lx, &t))
            return -1;
        if (t.kind != PBRT_TOKEN_NUMBER)
            return pbrt_fail(lx->file, t.line, "%s: %d numbers expected, found %d", statement,
                             count, i);
        if (pbrt_token_number(lx, &t, &out[i]))
            return error_prefix("%s", statement);
    }
    if (bracketed) {
        if (pbrt_lexer_next(lx, &t))
            return -1;
        if (t.kind != PBRT_TOKEN_CLOSE)
            return pbrt_fail(lx->file, line, "%s: %d numbers expected inside [ ]", statement,
                             count);
    }
    return 0;
}

/* A statement's parameters, read and handed to `read`, unused ones warned about. */
static int params_arg(pbrt_lexer *lx, pbrt_params *params) { return pbrt_params_read(lx, params); }

/* ---- graphics state ---- */

static void push_state(pbrt_loader *ld, char kind)
{
    ld->stack = xrealloc(ld->stack, (ld->stack_count + 1) * sizeof *ld->stack);
    ld->stack_kind = xrealloc(ld->stack_kind, ld->stack_count + 1);
    ld->stack[ld->stack_count] = ld->state;
    ld->stack_kind[ld->stack_count++] = kind;
}

static int pop_state(pbrt_loader *ld, const char *file, int line, char kind, const char *statement)
{
    if (!ld->stack_count || ld->stack_kind[ld->stack_count - 1] != kind)
        return pbrt_fail(file, line, "%s without a matching %s", statement,
                         kind == 'A' ? "AttributeBegin" : kind == 'T' ? "TransformBegin"
                                                                      : "ObjectBegin");
    pbrt_graphics_state saved = ld->stack[--ld->stack_count];
    if (kind == 'T')
        ld->state.ctm = saved.ctm;
    else
        ld->state = saved;
    return 0;
}

/* ctm = ctm * t, unless only the end time's transform is active (motion is not simulated: the
 * start time's transform is used). */
static void concat(pbrt_loader *ld, xform t, int start_active)
{
    if (start_active)
        ld->state.ctm = xform_multiply(&ld->state.ctm, &t);
}

/* The 16 values of Transform/ConcatTransform: pbrt lists the matrix column by column (the
 * translation is values 12, 13, 14). */
static xform matrix_from_file(const double v[16])
{
    double rows[16];
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            rows[4 * r + c] = v[4 * c + r];
    return xform_from_rows(rows);
}

/* pbrt's LookAt: camera space +z looks from eye to target, +y is `up` made orthogonal, +x =
 * up × direction; the matrix is camera-from-world. */
static int look_at(const double v[9], xform *out)
{
    double dir[3] = {v[3] - v[0], v[4] - v[1], v[5] - v[2]}, up[3] = {v[6], v[7], v[8]};
    double right[3], new_up[3];
    if (xform_normalize(dir) == 0.0 || xform_normalize(up) == 0.0)
        return -1;
    xform_cross(up, dir, right);
    if (xform_normalize(right) < 1e-12)
        return -1;
    xform_cross(dir, right, new_up);
    double rows[16] = {right[0], new_up[0], dir[0], v[0], right[1], new_up[1], dir[1], v[1],
                       right[2], new_up[2], dir[2], v[2], 0,        0,         0,      1};
    xform world_from_camera = xform_from_rows(rows);
    return xform_invert_affine(&world_from_camera, out);
}

static void set_coordinate_system(pbrt_loader *ld, const char *name, const xform *ctm)
{
    for (size_t i = 0; i < ld->coordinate_system_count; i++)
        if (strcmp(ld->coordinate_systems[i].name, name) == 0) {
            ld->coordinate_systems[i].ctm = *ctm;
            return;
        }
    ld->coordinate_systems = xrealloc(ld->coordinate_systems, (ld->coordinate_system_count + 1) *
                                                                  sizeof *ld->coordinate_systems);
    ld->coordinate_systems[ld->coordinate_system_count++] =
        (pbrt_named_xform){xstrdup(name), *ctm};
}

static const xform *find_coordinate_system(const pbrt_loader *ld, const char *name)
{
    for (size_t i = 0; i < ld->coordinate_system_count; i++)
        if (strcmp(ld->coordinate_systems[i].name, name) == 0)
            return &ld->coordinate_systems[i].ctm;
    return NULL;
}

/* ---- statements ---- */

static int parse_file(pbrt_loader *ld, const char *path, const char *includer, int include_line);

/* Statements whose whole content idmr does not simulate: a type (or name) argument and
 * parameters, warned about once. */
static const char *const ignored_with_params[] = {"Sampler", "Integrator", "PixelFilter",
                                                  "Accelerator", "MakeNamedMedium", NULL};

static int is_one_of(const pbrt_token *t, const char *const *words)
{
    for (size_t i = 0; words[i]; i++)
        if (pbrt_token_is(t, words[i]))
            return 1;
    return 0;
}

/* Statements that take a type string and parameters and go to a reader. */
static int typed_statement(pbrt_loader *ld, pbrt_lexer *lx, const pbrt_token *keyword,
                           const char *statement)
{
    char *type = NULL;
    pbrt_params params;
    int line = keyword->line;
    if (string_arg(lx, statement, &type))
        return -1;
    if (params_arg(lx, &params)) {
        free(type);
        return -1;
    }
    char label[128];
    snprintf(label, sizeof label, "%s \"%s\"", statement, type);
    int status = 0;
    if (strcmp(statement, "Camera") == 0)
        status = pbrt_read_camera(ld, lx->file, line, type, &params);
    else if (strcmp(statement, "Film") == 0)
        status = pbrt_read_film(ld, lx->file, line, type, &params);
    else if (strcmp(statement, "Material") == 0) {
        int index = pbrt_read_material(ld, lx->file, line, NULL, type, &params);
        status = index < 0 ? -1 : 0;
        ld->state.material = index;
    } else if (strcmp(statement, "MakeNamedMaterial") == 0) {
        snprintf(label, sizeof label, "MakeNamedMaterial \"%s\"", type);
        status = pbrt_read_material(ld, lx->file, line, type, NULL, &params) < 0 ? -1 : 0;
    } else if (strcmp(statement, "Shape") == 0)
        status = pbrt_read_shape(ld, lx->file, line, (long)keyword->offset, type, &params);
    else if (strcmp(statement, "AreaLightSource") == 0)
        status = pbrt_read_area_light(ld, lx->file, line, type, &params);
    else if (strcmp(statement, "LightSource") == 0)
        status = pbrt_read_light(ld, lx->file, line, type, &params);
    else { /* ignored_with_params */
        for (size_t i = 0; i < params.count; i++)
            params.items[i].used = 1;
        pbrt_warn(lx->file, line, "%s \"%s\" is not simulated by idmr: ignored", statement, type);
    }
    if (!status)
        pbrt_params_warn_unused(lx->file, label, &params);
    pbrt_params_free(&params);
    free(type);
    return status;
}

static int statement_texture(pbrt_loader *ld, pbrt_lexer *lx, int line)
{
    char *name = NULL, *type = NULL, *class_name = NULL;
    pbrt_params params = {0};
    int status = -1;
    if (string_arg(lx, "Texture", &name) || string_arg(lx, "Texture", &type) ||
        string_arg(lx, "Texture", &class_name) || params_arg(lx, &params))
        goto done;
    status = pbrt_read_texture(ld, lx->file, line, name, type, class_name, &params);
    if (!status) {
        char label[300];
        snprintf(label, sizeof label, "Texture \"%s\"", class_name);
        pbrt_params_warn_unused(lx->file, label, &params);
    }
done:
    pbrt_params_free(&params);
    free(name);
    free(type);
    free(class_name);
    return status;
}

static int statement_include(pbrt_loader *ld, pbrt_lexer *lx, int line, const char *statement)
{
    char *written;
    if (string_arg(lx, statement, &written))
        return -1;
    if (ld->include_depth >= PBRT_MAX_INCLUDE_DEPTH) {
        free(written);
        return pbrt_fail(lx->file, line, "%s: more than %d files included in each other (a loop?)",
                         statement, PBRT_MAX_INCLUDE_DEPTH);
    }
    size_t n = strlen(written);
    if (n >= 3 && strcmp(written + n - 3, ".gz") == 0) {
        int status = pbrt_fail(lx->file, line,
                               "%s \"%s\": gzipped scene files are not read (unpack it with gunzip)",
                               statement, written);
        free(written);
        return status;
    }
    char *path = pbrt_resolve_path(ld, written);
    free(written);
    ld->include_depth++;
    int status = parse_file(ld, path, lx->file, line);
    ld->include_depth--;
    free(path);
    return status;
}

static int statement_transform(pbrt_loader *ld, pbrt_lexer *lx, const pbrt_token *t,
                               int start_active)
{
    double v[16];
    const char *file = lx->file;
    int line = t->line;
    if (pbrt_token_is(t, "Identity")) {
        if (start_active)
            ld->state.ctm = xform_identity();
    } else if (pbrt_token_is(t, "Translate")) {
        if (number_args(lx, "Translate", line, v, 3))
            return -1;
        concat(ld, xform_translate(v[0], v[1], v[2]), start_active);
    } else if (pbrt_token_is(t, "Scale")) {
        if (number_args(lx, "Scale", line, v, 3))
            return -1;
        concat(ld, xform_scale(v[0], v[1], v[2]), start_active);
    } else if (pbrt_token_is(t, "Rotate")) {
        if (number_args(lx, "Rotate", line, v, 4))
            return -1;
        if (v[1] == 0.0 && v[2] == 0.0 && v[3] == 0.0)
            return pbrt_fail(file, line, "Rotate: the axis is zero");
        concat(ld, xform_rotate(v + 1, v[0]), start_active);
    } else if (pbrt_token_is(t, "LookAt")) {
        xform m;
        if (number_args(lx, "LookAt", line, v, 9))
            return -1;
        if (look_at(v, &m))
            return pbrt_fail(file, line,
                             "LookAt: the eye is the target, or up is parallel to the view");
        concat(ld, m, start_active);
    } else if (pbrt_token_is(t, "Transform") || pbrt_token_is(t, "ConcatTransform")) {
        int replace = pbrt_token_is(t, "Transform");
        if (number_args(lx, replace ? "Transform" : "ConcatTransform", line, v, 16))
            return -1;
        xform m = matrix_from_file(v);
        if (replace && start_active)
            ld->state.ctm = m;
        else
            concat(ld, m, start_active);
    } else {
        return 1;
    }
    return 0;
}

/* The statements without a type argument other than transforms. */
static int statement_other(pbrt_loader *ld, pbrt_lexer *lx, const pbrt_token *t, int *start_active)
{
    const char *file = lx->file;
    int line = t->line;
    char *name = NULL;
    int status = 0;
    if (pbrt_token_is(t, "AttributeBegin")) {
        push_state(ld, 'A');
    } else if (pbrt_token_is(t, "AttributeEnd")) {
        return pop_state(ld, file, line, 'A', "AttributeEnd");
    } else if (pbrt_token_is(t, "TransformBegin")) {
        push_state(ld, 'T');
    } else if (pbrt_token_is(t, "TransformEnd")) {
        return pop_state(ld, file, line, 'T', "TransformEnd");
    } else if (pbrt_token_is(t, "ReverseOrientation")) {
        ld->state.reverse_orientation = !ld->state.reverse_orientation;
    } else if (pbrt_token_is(t, "WorldBegin")) {
        if (ld->in_world)
            return pbrt_fail(file, line, "WorldBegin: a second WorldBegin");
        if (ld->stack_count)
            return pbrt_fail(file, line, "WorldBegin inside AttributeBegin/TransformBegin");
        ld->in_world = 1;
        ld->state.ctm = xform_identity();
        xform identity = xform_identity();
        set_coordinate_system(ld, "world", &identity);
        return pbrt_camera_finish(ld);
    } else if (pbrt_token_is(t, "WorldEnd")) {
        /* pbrt-v3's end of the scene: nothing to do. */
    } else if (pbrt_token_is(t, "CoordinateSystem")) {
        if (string_arg(lx, "CoordinateSystem", &name))
            return -1;
        set_coordinate_system(ld, name, &ld->state.ctm);
    } else if (pbrt_token_is(t, "CoordSysTransform")) {
        if (string_arg(lx, "CoordSysTransform", &name))
            return -1;
        const xform *m = find_coordinate_system(ld, name);
        if (!m)
            status = pbrt_fail(file, line, "CoordSysTransform: no coordinate system '%s'", name);
        else if (*start_active)
            ld->state.ctm = *m;
    } else if (pbrt_token_is(t, "NamedMaterial")) {
        if (string_arg(lx, "NamedMaterial", &name))
            return -1;
        int index = pbrt_find_material(ld, name);
        if (index < 0)
            status = pbrt_fail(file, line, "NamedMaterial: no material named '%s'", name);
        ld->state.material = index;
    } else if (pbrt_token_is(t, "ObjectBegin")) {
        if (string_arg(lx, "ObjectBegin", &name))
            return -1;
        if (ld->current_object)
            status = pbrt_fail(file, line, "ObjectBegin \"%s\" inside another object", name);
        for (size_t i = 0; !status && i < ld->object_count; i++)
            if (strcmp(ld->objects[i].name, name) == 0)
                status = pbrt_fail(file, line, "ObjectBegin: object '%s' defined twice", name);
        if (!status) {
            push_state(ld, 'O');
            ld->objects = xrealloc(ld->objects, (ld->object_count + 1) * sizeof *ld->objects);
            pbrt_object *o = &ld->objects[ld->object_count++];
            memset(o, 0, sizeof *o);
            o->name = name;
            name = NULL;
            ld->current_object = o;
        }
    } else if (pbrt_token_is(t, "ObjectEnd")) {
        if (!ld->current_object)
            return pbrt_fail(file, line, "ObjectEnd without ObjectBegin");
        ld->current_object = NULL;
        return pop_state(ld, file, line, 'O', "ObjectEnd");
    } else if (pbrt_token_is(t, "ObjectInstance")) {
        if (string_arg(lx, "ObjectInstance", &name))
            return -1;
        if (ld->current_object)
            status = pbrt_fail(file, line, "ObjectInstance inside an object definition");
        else
            status = pbrt_instance_object(ld, file, line, name, &ld->state.ctm);
    } else if (pbrt_token_is(t, "ActiveTransform")) {
        pbrt_token which;
        if (pbrt_lexer_next(lx, &which))
            return -1;
        if (pbrt_token_is(&which, "StartTime") || pbrt_token_is(&which, "All"))
            *start_active = 1;
        else if (pbrt_token_is(&which, "EndTime"))
            *start_active = 0;
        else
            return pbrt_fail(file, line, "ActiveTransform: expected StartTime, EndTime or All");
        pbrt_warn(file, line, "ActiveTransform: motion is not simulated: the start time's "
                              "transforms are used");
    } else if (pbrt_token_is(t, "TransformTimes")) {
        double v[2];
        if (number_args(lx, "TransformTimes", line, v, 2))
            return -1;
        pbrt_warn(file, line, "TransformTimes: motion is not simulated: ignored");
    } else if (pbrt_token_is(t, "ColorSpace")) {
        if (string_arg(lx, "ColorSpace", &name))
            return -1;
        pbrt_warn(file, line, "ColorSpace \"%s\": colours are read as linear sRGB", name);
    } else if (pbrt_token_is(t, "MediumInterface")) {
        pbrt_token next;
        if (string_arg(lx, "MediumInterface", &name) || pbrt_lexer_peek(lx, &next))
            return -1;
        if (next.kind == PBRT_TOKEN_STRING) {
            free(name);
            if (string_arg(lx, "MediumInterface", &name))
                return -1;
        }
        pbrt_warn(file, line, "MediumInterface: participating media are not simulated: ignored");
    } else if (pbrt_token_is(t, "Option") || pbrt_token_is(t, "Attribute")) {
        pbrt_params params;
        int is_option = pbrt_token_is(t, "Option");
        if (!is_option && string_arg(lx, "Attribute", &name))
            return -1;
        if (params_arg(lx, &params))
            status = -1;
        else {
            if (is_option)
                pbrt_warn(file, line, "Option: rendering options are not used by idmr: ignored");
            else
                pbrt_warn(file, line,
                          "Attribute \"%s\": parameter defaults are not read by idmr: ignored",
                          name);
            pbrt_params_free(&params);
        }
    } else {
        return 1;
    }
    free(name);
    return status;
}

static int statement(pbrt_loader *ld, pbrt_lexer *lx, const pbrt_token *t, int *start_active)
{
    static const char *const typed[] = {"Camera", "Film", "Material", "MakeNamedMaterial",
                                        "Shape", "AreaLightSource", "LightSource", NULL};
    if (t->kind != PBRT_TOKEN_WORD)
        return pbrt_fail(lx->file, t->line, "expected a statement, found '%.*s'",
                         (int)(t->length > 64 ? 64 : t->length), t->text);
    if (is_one_of(t, typed) || is_one_of(t, ignored_with_params)) {
        char statement_name[32];
        snprintf(statement_name, sizeof statement_name, "%.*s", (int)t->length, t->text);
        if (!ld->in_world && (pbrt_token_is(t, "Shape") || pbrt_token_is(t, "Material") ||
                              pbrt_token_is(t, "AreaLightSource") ||
                              pbrt_token_is(t, "MakeNamedMaterial")))
            return pbrt_fail(lx->file, t->line, "%s before WorldBegin", statement_name);
        return typed_statement(ld, lx, t, statement_name);
    }
    if (pbrt_token_is(t, "Texture"))
        return statement_texture(ld, lx, t->line);
    if (pbrt_token_is(t, "Include") || pbrt_token_is(t, "Import"))
        return statement_include(ld, lx, t->line, pbrt_token_is(t, "Include") ? "Include" : "Import");
    int status = statement_transform(ld, lx, t, *start_active);
    if (status <= 0)
        return status;
    status = statement_other(ld, lx, t, start_active);
    if (status <= 0)
        return status;
    return pbrt_fail(lx->file, t->line, "unknown statement '%.*s'",
                     (int)(t->length > 64 ? 64 : t->length), t->text);
}

static int parse_file(pbrt_loader *ld, const char *path, const char *includer, int include_line)
{
    size_t size;
    char *text = pbrt_read_text(path, &size);
    if (!text)
        return includer ? error_prefix("%s:%d: Include", includer, include_line) : -1;
    pbrt_lexer lx;
    pbrt_lexer_init(&lx, path, text, size);
    int start_active = 1, status = 0;
    size_t stack_at_start = ld->stack_count;
    for (;;) {
        pbrt_token t;
        if ((status = pbrt_lexer_next(&lx, &t)) != 0 || t.kind == PBRT_TOKEN_END)
            break;
        if ((status = statement(ld, &lx, &t, &start_active)) != 0)
            break;
    }
    if (!status && !includer && ld->stack_count > stack_at_start)
        status = pbrt_fail(path, lx.line, "the file ends inside %s",
                           ld->stack_kind[ld->stack_count - 1] == 'O'   ? "ObjectBegin"
                           : ld->stack_kind[ld->stack_count - 1] == 'T' ? "TransformBegin"
                                                                        : "AttributeBegin");
    free(text);
    return status;
}

static void loader_free(pbrt_loader *ld)
{
    for (size_t i = 0; i < ld->material_count; i++) {
        free(ld->materials[i].name);
        free(ld->materials[i].type);
        free(ld->materials[i].texture_file);
    }
    free(ld->materials);
    for (size_t i = 0; i < ld->texture_count; i++) {
        free(ld->textures[i].name);
        free(ld->textures[i].class_name);
        free(ld->textures[i].file);
    }
    free(ld->textures);
    for (size_t i = 0; i < ld->coordinate_system_count; i++)
        free(ld->coordinate_systems[i].name);
    free(ld->coordinate_systems);
    pbrt_objects_free(ld);
    free(ld->stack);
    free(ld->stack_kind);
    free(ld->scene_dir);
    free(ld->camera_file);
}

scene *pbrt_load(const char *path)
{
    pbrt_loader ld;
    memset(&ld, 0, sizeof ld);
    ld.s = scene_create(path);
    ld.scene_dir = mitsuba_path_directory(path);
    ld.state.ctm = xform_identity();
    ld.state.material = -1;
    ld.default_material = -1;
    ld.film_width = 1280;
    ld.film_height = 720;
    pbrt_warnings_reset();
    int status = parse_file(&ld, path, NULL, 0);
    if (!status && !ld.in_world)
        pbrt_warn(path, 1, "no WorldBegin: the file describes no world");
    if (!status && ld.camera_seen && !ld.s->has_camera)
        status = pbrt_camera_finish(&ld);
    if (!status && !ld.s->has_camera)
        pbrt_warn(path, 1, "no Camera: the scene has no camera");
    if (!status && scene_finalize(ld.s))
        status = -1;
    loader_free(&ld);
    pbrt_warnings_reset();
    if (status) {
        scene_free(ld.s);
        return NULL;
    }
    return ld.s;
}
