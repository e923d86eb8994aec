/* pbrt_lexer.c — a pbrt-v4 file cut into tokens (see pbrt_loader.h): unquoted words and numbers
 * separated by white space, "quoted strings" (which may not span lines), [ and ], and # comments
 * to the end of the line. Each token keeps its line and byte span, which the writer uses to
 * replace a statement in place. */
#include "io/pbrt/pbrt_loader.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

void pbrt_lexer_init(pbrt_lexer *lx, const char *file, const char *text, size_t size)
{
    memset(lx, 0, sizeof *lx);
    lx->file = file;
    lx->text = text;
    lx->size = size;
    lx->line = 1;
    if (size >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) /* a UTF-8 byte order mark */
        lx->pos = 3;
}

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

static int is_delimiter(char c) { return is_space(c) || c == '"' || c == '[' || c == ']' || c == '#'; }

/* Skips white space and comments, counting lines. */
static void skip_blank(pbrt_lexer *lx)
{
    while (lx->pos < lx->size) {
        char c = lx->text[lx->pos];
        if (c == '\n') {
            lx->line++;
            lx->pos++;
        } else if (is_space(c)) {
            lx->pos++;
        } else if (c == '#') {
            while (lx->pos < lx->size && lx->text[lx->pos] != '\n')
                lx->pos++;
        } else {
            break;
        }
    }
}

static int read_string(pbrt_lexer *lx, pbrt_token *out)
{
    size_t start = lx->pos++;
    while (lx->pos < lx->size) {
        char c = lx->text[lx->pos];
        if (c == '\n')
            break;
        if (c == '\\' && lx->pos + 1 < lx->size && lx->text[lx->pos + 1] != '\n') {
            lx->pos += 2;
            continue;
        }
        if (c == '"') {
            out->kind = PBRT_TOKEN_STRING;
            out->text = lx->text + start + 1;
            out->length = lx->pos - start - 1;
            out->offset = start;
            out->end = ++lx->pos;
            return 0;
        }
        lx->pos++;
    }
    return pbrt_fail(lx->file, out->line, "unterminated string (a string ends on its line)");
}

static int read_token(pbrt_lexer *lx, pbrt_token *out)
{
    skip_blank(lx);
    memset(out, 0, sizeof *out);
    out->line = lx->line;
    out->offset = out->end = lx->pos;
    if (lx->pos >= lx->size) {
        out->kind = PBRT_TOKEN_END;
        out->text = "";
        return 0;
    }
    char c = lx->text[lx->pos];
    if (c == '"')
        return read_string(lx, out);
    if (c == '[' || c == ']') {
        out->kind = c == '[' ? PBRT_TOKEN_OPEN : PBRT_TOKEN_CLOSE;
        out->text = lx->text + lx->pos;
        out->length = 1;
        out->end = ++lx->pos;
        return 0;
    }
    if (c == '\0')
        return pbrt_fail(lx->file, lx->line, "unexpected NUL byte (not a text file?)");
    size_t start = lx->pos;
    while (lx->pos < lx->size && !is_delimiter(lx->text[lx->pos]) && lx->text[lx->pos] != '\0')
        lx->pos++;
    out->text = lx->text + start;
    out->length = lx->pos - start;
    out->end = lx->pos;
    out->kind = (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' ? PBRT_TOKEN_NUMBER
                                                                          : PBRT_TOKEN_WORD;
    return 0;
}

int pbrt_lexer_next(pbrt_lexer *lx, pbrt_token *out)
{
    if (lx->has_peeked) {
        *out = lx->peeked;
        lx->has_peeked = 0;
        return 0;
    }
    return read_token(lx, out);
}

int pbrt_lexer_peek(pbrt_lexer *lx, pbrt_token *out)
{
    if (!lx->has_peeked) {
        if (read_token(lx, &lx->peeked))
            return -1;
        lx->has_peeked = 1;
    }
    *out = lx->peeked;
    return 0;
}

char *pbrt_token_string(const pbrt_token *t)
{
    char *out = xmalloc(t->length + 1);
    size_t n = 0;
    for (size_t i = 0; i < t->length; i++) {
        char c = t->text[i];
        if (c == '\\' && i + 1 < t->length) {
            c = t->text[++i];
            switch (c) {
            case 'n': c = '\n'; break;
            case 't': c = '\t'; break;
            case 'r': c = '\r'; break;
            case 'b': c = '\b'; break;
            case 'f': c = '\f'; break;
            default: break; /* \\ \" \' and anything else: the character itself */
            }
        }
        out[n++] = c;
    }
    out[n] = '\0';
    return out;
}

int pbrt_token_is(const pbrt_token *t, const char *word)
{
    size_t length = strlen(word);
    return t->kind == PBRT_TOKEN_WORD && t->length == length && memcmp(t->text, word, length) == 0;
}

int pbrt_token_number(const pbrt_lexer *lx, const pbrt_token *t, double *out)
{
    char buffer[128];
    if (t->kind != PBRT_TOKEN_NUMBER || t->length >= sizeof buffer)
        return pbrt_fail(lx->file, t->line, "expected a number, found '%.*s'",
                         (int)(t->length > 64 ? 64 : t->length), t->text);
    memcpy(buffer, t->text, t->length);
    buffer[t->length] = '\0';
    char *end;
    errno = 0;
    double value = strtod(buffer, &end);
    if (end == buffer || *end != '\0' || !isfinite(value) || (errno == ERANGE && fabs(value) > 1.0))
        return pbrt_fail(lx->file, t->line, "bad number '%s'", buffer);
    *out = value;
    return 0;
}
