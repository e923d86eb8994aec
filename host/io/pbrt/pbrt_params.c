/* pbrt_params.c — pbrt-v4 parameter lists: `"type name" [ values ]` or `"type name" value`,
 * checked against the type when read (numbers, strings or bools; the count the type asks for),
 * looked up by name by the readers, and the ones no reader used warned about. */
#include "io/pbrt/pbrt_loader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

typedef enum value_class { VALUES_NUMBERS, VALUES_STRINGS, VALUES_BOOLS, VALUES_SPECTRUM } value_class;

typedef struct type_rule {
    const char *type;
    value_class values;
    int multiple; /* the count must be a multiple of this (0: exactly `exact`) */
    int exact;
} type_rule;

static const type_rule type_rules[] = {
    {"float", VALUES_NUMBERS, 1, 0},   {"integer", VALUES_NUMBERS, 1, 0},
    {"point2", VALUES_NUMBERS, 2, 0},  {"vector2", VALUES_NUMBERS, 2, 0},
    {"point3", VALUES_NUMBERS, 3, 0},  {"vector3", VALUES_NUMBERS, 3, 0},
    {"point", VALUES_NUMBERS, 3, 0},   {"vector", VALUES_NUMBERS, 3, 0},
    {"normal", VALUES_NUMBERS, 3, 0},  {"normal3", VALUES_NUMBERS, 3, 0},
    {"rgb", VALUES_NUMBERS, 0, 3},     {"color", VALUES_NUMBERS, 0, 3},
    {"blackbody", VALUES_NUMBERS, 0, 1}, {"string", VALUES_STRINGS, 1, 0},
    {"texture", VALUES_STRINGS, 0, 1}, {"bool", VALUES_BOOLS, 1, 0},
    {"spectrum", VALUES_SPECTRUM, 1, 0},
};

static const type_rule *find_rule(const char *type)
{
    for (size_t i = 0; i < sizeof type_rules / sizeof *type_rules; i++)
        if (strcmp(type, type_rules[i].type) == 0)
            return &type_rules[i];
    return NULL;
}

static void param_free(pbrt_param *p)
{
    free(p->type);
    free(p->name);
    free(p->numbers);
    for (size_t i = 0; i < p->string_count; i++)
        free(p->strings[i]);
    free(p->strings);
}

void pbrt_params_free(pbrt_params *params)
{
    for (size_t i = 0; i < params->count; i++)
        param_free(&params->items[i]);
    free(params->items);
    params->items = NULL;
    params->count = 0;
}

/* "type name" into p->type and p->name: exactly two words. */
static int split_declaration(const pbrt_lexer *lx, const pbrt_token *t, pbrt_param *p)
{
    char *text = pbrt_token_string(t);
    char first[64], second[256], extra[8];
    int words = sscanf(text, "%63s %255s %7s", first, second, extra);
    if (words != 2) {
        pbrt_fail(lx->file, t->line,
                  "\"%s\": a parameter is declared as \"type name\" (or a statement is missing "
                  "before this string)",
                  text);
        free(text);
        return -1;
    }
    free(text);
    p->type = xstrdup(first);
    p->name = xstrdup(second);
    return 0;
}

/* One value token into p (number, string or bool, as the token is). */
static int add_value(const pbrt_lexer *lx, const pbrt_token *t, pbrt_param *p, size_t *capacity)
{
    if (t->kind == PBRT_TOKEN_STRING) {
        p->strings = xrealloc(p->strings, (p->string_count + 1) * sizeof *p->strings);
        p->strings[p->string_count++] = pbrt_token_string(t);
        return 0;
    }
    double value;
    if (pbrt_token_is(t, "true") || pbrt_token_is(t, "false")) {
        value = pbrt_token_is(t, "true");
        p->strings = xrealloc(p->strings, (p->string_count + 1) * sizeof *p->strings);
        p->strings[p->string_count++] = xstrdup(value ? "true" : "false");
        return 0;
    }
    if (t->kind != PBRT_TOKEN_NUMBER)
        return pbrt_fail(lx->file, t->line, "\"%s %s\": unexpected '%.*s' among the values",
                         p->type, p->name, (int)(t->length > 64 ? 64 : t->length), t->text);
    if (pbrt_token_number(lx, t, &value))
        return error_prefix("\"%s %s\"", p->type, p->name);
    if (p->number_count == *capacity) {
        *capacity = *capacity ? 2 * *capacity : 16;
        p->numbers = xrealloc(p->numbers, *capacity * sizeof *p->numbers);
    }
    p->numbers[p->number_count++] = value;
    return 0;
}

/* Checks the values read against the type's rule; turns bool strings into numbers. */
static int check_values(const char *file, pbrt_param *p)
{
    const type_rule *rule = find_rule(p->type);
    if (!rule)
        return pbrt_fail(file, p->line, "\"%s %s\": unknown parameter type '%s'", p->type,
                         p->name, p->type);
    if (p->number_count && p->string_count)
        return pbrt_fail(file, p->line, "\"%s %s\": numbers and strings mixed in one value list",
                         p->type, p->name);
    size_t count = p->number_count + p->string_count;
    if (count == 0)
        return pbrt_fail(file, p->line, "\"%s %s\": no values", p->type, p->name);
    switch (rule->values) {
    case VALUES_NUMBERS:
        if (p->string_count)
            return pbrt_fail(file, p->line, "\"%s %s\": expected numbers, found a string",
                             p->type, p->name);
        if (strcmp(p->type, "integer") == 0)
            for (size_t i = 0; i < p->number_count; i++)
                if (p->numbers[i] != floor(p->numbers[i]) || fabs(p->numbers[i]) > 2147483647.0)
                    return pbrt_fail(file, p->line, "\"%s %s\": %g is not an integer", p->type,
                                     p->name, p->numbers[i]);
        break;
    case VALUES_STRINGS:
        if (p->number_count)
            return pbrt_fail(file, p->line, "\"%s %s\": expected a string, found a number",
                             p->type, p->name);
        break;
    case VALUES_BOOLS:
        if (p->number_count)
            return pbrt_fail(file, p->line, "\"%s %s\": expected true or false, found a number",
                             p->type, p->name);
        p->numbers = xmalloc(p->string_count * sizeof *p->numbers);
        for (size_t i = 0; i < p->string_count; i++) {
            if (strcmp(p->strings[i], "true") && strcmp(p->strings[i], "false"))
                return pbrt_fail(file, p->line, "\"%s %s\": '%s' is not true or false", p->type,
                                 p->name, p->strings[i]);
            p->numbers[i] = strcmp(p->strings[i], "true") == 0;
            free(p->strings[i]);
        }
        p->number_count = p->string_count;
        p->string_count = 0;
        free(p->strings);
        p->strings = NULL;
        return 0;
    case VALUES_SPECTRUM:
        if (p->string_count > 1)
            return pbrt_fail(file, p->line, "\"%s %s\": one named spectrum or file expected",
                             p->type, p->name);
        if (p->number_count && p->number_count % 2)
            return pbrt_fail(file, p->line,
                             "\"%s %s\": a sampled spectrum is wavelength-value pairs (%zu "
                             "values given)",
                             p->type, p->name, p->number_count);
        return 0;
    }
    if (rule->multiple && count % (size_t)rule->multiple)
        return pbrt_fail(file, p->line, "\"%s %s\": %zu values, not a multiple of %d", p->type,
                         p->name, count, rule->multiple);
    if (!rule->multiple && count != (size_t)rule->exact)
        return pbrt_fail(file, p->line, "\"%s %s\": %zu values where %d are expected", p->type,
                         p->name, count, rule->exact);
    return 0;
}

/* One parameter: the declaration string has been taken as `declaration`. */
static int read_param(pbrt_lexer *lx, const pbrt_token *declaration, pbrt_param *p)
{
    pbrt_token t;
    size_t capacity = 0;
    memset(p, 0, sizeof *p);
    p->line = declaration->line;
    p->offset = declaration->offset;
    if (split_declaration(lx, declaration, p) || pbrt_lexer_next(lx, &t))
        return -1;
    if (t.kind == PBRT_TOKEN_OPEN) {
        for (;;) {
            if (pbrt_lexer_next(lx, &t))
                return -1;
            if (t.kind == PBRT_TOKEN_CLOSE)
                break;
            if (t.kind == PBRT_TOKEN_END || t.kind == PBRT_TOKEN_OPEN)
                return pbrt_fail(lx->file, t.line, "\"%s %s\": '[' without a matching ']'",
                                 p->type, p->name);
            if (add_value(lx, &t, p, &capacity))
                return -1;
        }
    } else if (t.kind == PBRT_TOKEN_END || t.kind == PBRT_TOKEN_CLOSE ||
               (t.kind == PBRT_TOKEN_WORD && !pbrt_token_is(&t, "true") &&
                !pbrt_token_is(&t, "false"))) {
        return pbrt_fail(lx->file, t.line, "\"%s %s\": a value is missing", p->type, p->name);
    } else if (add_value(lx, &t, p, &capacity)) {
        return -1;
    }
    p->end = t.end;
    return check_values(lx->file, p);
}

int pbrt_params_read(pbrt_lexer *lx, pbrt_params *out)
{
    pbrt_token t;
    memset(out, 0, sizeof *out);
    for (;;) {
        if (pbrt_lexer_peek(lx, &t))
            goto fail;
        if (t.kind != PBRT_TOKEN_STRING)
            return 0;
        pbrt_lexer_next(lx, &t);
        out->items = xrealloc(out->items, (out->count + 1) * sizeof *out->items);
        pbrt_param *p = &out->items[out->count++];
        if (read_param(lx, &t, p))
            goto fail;
        for (size_t i = 0; i + 1 < out->count; i++)
            if (strcmp(out->items[i].name, p->name) == 0) {
                pbrt_fail(lx->file, p->line, "parameter '%s' given twice", p->name);
                goto fail;
            }
    }
fail:
    pbrt_params_free(out);
    return -1;
}

pbrt_param *pbrt_param_find(pbrt_params *params, const char *name)
{
    for (size_t i = 0; i < params->count; i++)
        if (strcmp(params->items[i].name, name) == 0) {
            params->items[i].used = 1;
            return &params->items[i];
        }
    return NULL;
}

int pbrt_param_typed(const char *file, pbrt_params *params, const char *name,
                     const char *const *types, size_t count, pbrt_param **out)
{
    pbrt_param *p = pbrt_param_find(params, name);
    *out = p;
    if (!p)
        return 0;
    int match = 0;
    for (size_t i = 0; types[i]; i++)
        match |= strcmp(p->type, types[i]) == 0;
    if (!match)
        return pbrt_fail(file, p->line, "\"%s %s\": '%s' should be of type %s", p->type, p->name,
                         p->name, types[0]);
    if (count && p->number_count + p->string_count != count)
        return pbrt_fail(file, p->line, "\"%s %s\": %zu values where %zu %s expected", p->type,
                         p->name, p->number_count + p->string_count, count,
                         count == 1 ? "is" : "are");
    return 0;
}

int pbrt_param_float(const char *file, pbrt_params *params, const char *name, double fallback,
                     double *out)
{
    static const char *const types[] = {"float", "integer", NULL};
    pbrt_param *p;
    *out = fallback;
    if (pbrt_param_typed(file, params, name, types, 1, &p))
        return -1;
    if (p)
        *out = p->numbers[0];
    return 0;
}

int pbrt_param_int(const char *file, pbrt_params *params, const char *name, long fallback,
                   long *out)
{
    static const char *const types[] = {"integer", NULL};
    pbrt_param *p;
    *out = fallback;
    if (pbrt_param_typed(file, params, name, types, 1, &p))
        return -1;
    if (p)
        *out = (long)p->numbers[0];
    return 0;
}

int pbrt_param_bool(const char *file, pbrt_params *params, const char *name, int fallback,
                    int *out)
{
    static const char *const types[] = {"bool", NULL};
    pbrt_param *p;
    *out = fallback;
    if (pbrt_param_typed(file, params, name, types, 1, &p))
        return -1;
    if (p)
        *out = p->numbers[0] != 0.0;
    return 0;
}

int pbrt_param_string(const char *file, pbrt_params *params, const char *name,
                      const char *fallback, const char **out)
{
    static const char *const types[] = {"string", "texture", NULL};
    pbrt_param *p;
    *out = fallback;
    if (pbrt_param_typed(file, params, name, types, 1, &p))
        return -1;
    if (p)
        *out = p->strings[0];
    return 0;
}

int pbrt_param_point3(const char *file, pbrt_params *params, const char *name,
                      const double fallback[3], double out[3])
{
    static const char *const types[] = {"point3", "point", "vector3", "vector", "normal",
                                        "normal3", NULL};
    pbrt_param *p;
    for (int k = 0; k < 3; k++)
        out[k] = fallback[k];
    if (pbrt_param_typed(file, params, name, types, 3, &p))
        return -1;
    for (int k = 0; p && k < 3; k++)
        out[k] = p->numbers[k];
    return 0;
}

void pbrt_params_warn_unused(const char *file, const char *statement, const pbrt_params *params)
{
    for (size_t i = 0; i < params->count; i++) {
        const pbrt_param *p = &params->items[i];
        if (!p->used)
            pbrt_warn(file, p->line, "%s: parameter \"%s %s\" is not used by idmr: ignored",
                      statement, p->type, p->name);
    }
}

int pbrt_sampled_spectrum(const char *file, const pbrt_param *p, const char *name,
                          spectrum_use use, float out[3])
{
    enum { MOST = 512 };
    int count = (int)(p->number_count / 2);
    double lambda[MOST], value[MOST];
    if (count > MOST)
        count = MOST;
    for (int i = 0; i < count; i++) {
        lambda[i] = p->numbers[2 * i];
        value[i] = p->numbers[2 * i + 1];
        if (i && lambda[i] <= lambda[i - 1])
            return pbrt_fail(file, p->line, "\"spectrum %s\": wavelengths must increase", name);
    }
    spectrum_to_rgb(lambda, value, count, use, out);
    return 0;
}
