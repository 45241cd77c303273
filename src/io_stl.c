/* STL reader (docs/meshes.md). A file is binary when it is at least 84 bytes long and its size
 * is exactly 84 + 50 N for the count N at byte 80, whatever its first bytes say (exporters
 * write binary files whose header begins with "solid"); otherwise it must be ASCII, beginning
 * with "solid". Everything is checked before it is used: the size against the count before
 * anything is reserved, every keyword and number of the ASCII grammar, every coordinate finite.
 * Triangles of zero area are dropped and counted (exporters leave them at creases); the
 * facet normals are read and ignored, since the engine's triangles are two-sided and take
 * their normal from the corners. */
#include "io_stl.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/vmath.h"

void sd_stl_free(sd_stl_mesh *m)
{
    free(m->tri);
    free(m->where);
    memset(m, 0, sizeof *m);
}

const char *sd_stl_where(const sd_stl_mesh *m, int k, char *buf, size_t len)
{
    if (m->binary)
        snprintf(buf, len, "triangle index %d (byte offset %lld)", m->where[k], 84LL + 50LL * m->where[k]);
    else
        snprintf(buf, len, "line %d", m->where[k]);
    return buf;
}

/* A triangle of zero area: its corners on a line, to rounding (the cross product of two edges
 * below 1e-12 of the longest edge squared), or coincident. */
static int degenerate(const sd_vec3 t[3])
{
    const sd_vec3 ab = v3_sub(t[1], t[0]), ac = v3_sub(t[2], t[0]), bc = v3_sub(t[2], t[1]);
    const double l2 = fmax(fmax(v3_norm2(ab), v3_norm2(ac)), v3_norm2(bc));
    return !(v3_norm(v3_cross(ab, ac)) > 1e-12 * l2);
}

/* Append a triangle (or count it dropped); -1 when out of memory. */
static int push(sd_stl_mesh *m, int *cap, const sd_vec3 t[3], int where)
{
    if (degenerate(t)) {
        if (!m->dropped++) m->first_dropped = where;
        return 0;
    }
    if (m->n == *cap) {
        const int nc = *cap ? 2 * *cap : 64;
        void *a = realloc(m->tri, (size_t)nc * sizeof *m->tri);
        if (a) m->tri = a;
        void *b = realloc(m->where, (size_t)nc * sizeof *m->where);
        if (b) m->where = b;
        if (!a || !b) return -1;
        *cap = nc;
    }
    memcpy(m->tri[m->n], t, sizeof m->tri[0]);
    m->where[m->n++] = where;
    return 0;
}

/* ------------------------------------------------------------------ binary ---- */

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float get_f32(const unsigned char *p)
{
    const uint32_t u = get_u32(p); /* (little-endian, whatever the machine) */
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static int read_binary(const unsigned char *p, const char *name, int max_triangles, sd_stl_mesh *m,
                       char *msg, size_t msglen)
{
    const uint32_t count = get_u32(p + 80);
    if (count == 0) {
        snprintf(msg, msglen, "%s: binary STL with no triangles (its count at byte offset 80 is 0)", name);
        return -1;
    }
    if (count > (uint32_t)max_triangles) {
        snprintf(msg, msglen, "%s: binary STL of %lu triangles, more than the limit of %d", name, (unsigned long)count,
                 max_triangles);
        return -1;
    }
    m->binary = 1;
    int cap = 0;
    for (uint32_t k = 0; k < count; k++) {
        const unsigned char *f = p + 84 + 50 * (size_t)k + 12; /* (the normal skipped) */
        sd_vec3 t[3];
        for (int v = 0; v < 3; v++) {
            double x[3];
            for (int d = 0; d < 3; d++) {
                x[d] = get_f32(f + 12 * v + 4 * d);
                if (!isfinite(x[d])) {
                    snprintf(msg, msglen, "%s: triangle index %lu (byte offset %llu): vertex %d's %c is not finite (%g)", name,
                             (unsigned long)k, 84ULL + 50ULL * k, v + 1, "xyz"[d], x[d]);
                    return -1;
                }
            }
            t[v] = v3(x[0], x[1], x[2]);
        }
        if (push(m, &cap, t, (int)k)) {
            snprintf(msg, msglen, "%s: out of memory at triangle %lu", name, (unsigned long)k);
            return -1;
        }
    }
    return 0;
}

/* ------------------------------------------------------------------- ASCII ---- */

typedef struct {
    const unsigned char *p;
    size_t len, pos;
    int line;
    const char *name;
    char *msg;
    size_t msglen;
} text_in;

static int is_space(int c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

/* The next token (its bytes and length, 0 at the end) and its line. */
static size_t next_token(text_in *in, const unsigned char **tok, int *line)
{
    while (in->pos < in->len && is_space(in->p[in->pos]))
        if (in->p[in->pos++] == '\n') in->line++;
    *line = in->line;
    const size_t s = in->pos;
    while (in->pos < in->len && !is_space(in->p[in->pos]))
        in->pos++;
    *tok = in->p + s;
    return in->pos - s;
}

/* The token equals the keyword, in any case. */
static int is_kw(const unsigned char *tok, size_t n, const char *kw)
{
    if (n != strlen(kw)) return 0;
    for (size_t k = 0; k < n; k++) {
        const int c = tok[k] >= 'A' && tok[k] <= 'Z' ? tok[k] - 'A' + 'a' : tok[k];
        if (c != kw[k]) return 0;
    }
    return 1;
}

/* A token as it may be shown in a message: at most 24 characters, bytes outside printable
 * ASCII as \xNN. */
static const char *shown(const unsigned char *tok, size_t n, char buf[128])
{
    size_t o = 0;
    for (size_t k = 0; k < n && k < 24; k++)
        o += (size_t)snprintf(buf + o, 128 - o, tok[k] >= 0x20 && tok[k] < 0x7f ? "%c" : "\\x%02x", tok[k]);
    if (n > 24) snprintf(buf + o, 128 - o, "...");
    return buf;
}

static int fail_at(text_in *in, int line, const char *what, const unsigned char *tok, size_t n)
{
    char b[128];
    if (n)
        snprintf(in->msg, in->msglen, "%s:%d: expected %s, found '%s'", in->name, line, what, shown(tok, n, b));
    else
        snprintf(in->msg, in->msglen, "%s:%d: expected %s, found the end of the file", in->name, line, what);
    return -1;
}

static int expect_kw(text_in *in, const char *kw)
{
    const unsigned char *tok;
    int line;
    const size_t n = next_token(in, &tok, &line);
    if (is_kw(tok, n, kw)) return 0;
    char what[32];
    snprintf(what, sizeof what, "'%s'", kw);
    return fail_at(in, line, what, tok, n);
}

/* A number; what names it in the message ("vertex 2's y"). */
static int expect_number(text_in *in, const char *what, double *x)
{
    const unsigned char *tok;
    int line;
    const size_t n = next_token(in, &tok, &line);
    char buf[64], w[48];
    snprintf(w, sizeof w, "a number (%s)", what);
    if (n == 0 || n >= sizeof buf) return fail_at(in, line, w, tok, n);
    memcpy(buf, tok, n);
    buf[n] = 0;
    char *end;
    *x = strtod(buf, &end);
    if (*end || end == buf) return fail_at(in, line, w, tok, n);
    return 0;
}

/* Skip the rest of a 'solid' or 'endsolid' line (the name), up to a token that begins the next
 * part (stop), so that files written on one line read too. */
static void skip_name(text_in *in, int line, const char *stop1, const char *stop2)
{
    for (;;) {
        const size_t pos = in->pos;
        const int l0 = in->line;
        const unsigned char *tok;
        int tl;
        const size_t n = next_token(in, &tok, &tl);
        if (n == 0 || tl != line || is_kw(tok, n, stop1) || (stop2 && is_kw(tok, n, stop2))) {
            in->pos = pos;
            in->line = l0;
            return;
        }
    }
}

static int read_ascii(text_in *in, int max_triangles, sd_stl_mesh *m)
{
    int cap = 0, solids = 0;
    for (;;) {
        const unsigned char *tok;
        int line;
        size_t n = next_token(in, &tok, &line);
        if (n == 0 && solids) return 0;
        if (!is_kw(tok, n, "solid")) return fail_at(in, line, solids ? "'solid' or the end of the file" : "'solid'", tok, n);
        solids++;
        skip_name(in, line, "facet", "endsolid");
        for (;;) {
            n = next_token(in, &tok, &line);
            if (is_kw(tok, n, "endsolid")) {
                skip_name(in, line, "solid", NULL);
                break;
            }
            if (!is_kw(tok, n, "facet")) return fail_at(in, line, "'facet' or 'endsolid'", tok, n);
            const int facet_line = line;
            double x;
            static const char *const nw[3] = {"the normal's x", "the normal's y", "the normal's z"};
            if (expect_kw(in, "normal")) return -1;
            for (int d = 0; d < 3; d++)
                if (expect_number(in, nw[d], &x)) return -1;
            if (expect_kw(in, "outer") || expect_kw(in, "loop")) return -1;
            sd_vec3 t[3];
            for (int v = 0; v < 3; v++) {
                double c[3];
                if (expect_kw(in, "vertex")) return -1;
                for (int d = 0; d < 3; d++) {
                    char w[32];
                    snprintf(w, sizeof w, "vertex %d's %c", v + 1, "xyz"[d]);
                    if (expect_number(in, w, &c[d])) return -1;
                    if (!isfinite(c[d])) {
                        snprintf(in->msg, in->msglen, "%s:%d: vertex %d's %c is not finite (%g)", in->name, in->line,
                                 v + 1, "xyz"[d], c[d]);
                        return -1;
                    }
                }
                t[v] = v3(c[0], c[1], c[2]);
            }
            if (expect_kw(in, "endloop") || expect_kw(in, "endfacet")) return -1;
            if (m->n >= max_triangles) {
                snprintf(in->msg, in->msglen, "%s:%d: more than the limit of %d triangles", in->name, facet_line,
                         max_triangles);
                return -1;
            }
            if (push(m, &cap, t, facet_line)) {
                snprintf(in->msg, in->msglen, "%s:%d: out of memory", in->name, facet_line);
                return -1;
            }
        }
    }
}

/* ---------------------------------------------------------------- the file ---- */

/* Begins with "solid" (after white space), in any case, followed by white space or the end. */
static int begins_solid(const unsigned char *p, size_t len)
{
    size_t k = 0;
    while (k < len && is_space(p[k]))
        k++;
    return len - k >= 5 && is_kw(p + k, 5, "solid") && (len - k == 5 || is_space(p[k + 5]));
}

int sd_stl_parse(const void *data, size_t len, const char *name, int max_triangles, sd_stl_mesh *m, char *msg,
                 size_t msglen)
{
    memset(m, 0, sizeof *m);
    const unsigned char *p = data;
    if (max_triangles > SD_STL_MAX_TRIANGLES) max_triangles = SD_STL_MAX_TRIANGLES;
    if (max_triangles < 0) max_triangles = 0;
    if (len == 0) {
        snprintf(msg, msglen, "%s: empty file", name);
        return -1;
    }
    const uint64_t count = len >= 84 ? get_u32(p + 80) : 0, want = 84 + 50 * count;
    int rc;
    if (len >= 84 && want == len) {
        rc = read_binary(p, name, max_triangles, m, msg, msglen);
    } else if (begins_solid(p, len)) {
        /* text: a control byte means a binary file whose size does not match its count */
        for (size_t k = 0; k < len; k++) {
            if ((p[k] >= 0x20 && p[k] != 0x7f) || is_space(p[k])) continue;
            int line = 1;
            for (size_t j = 0; j < k; j++)
                line += p[j] == '\n';
            if (len >= 84)
                snprintf(msg, msglen,
                         "%s:%d: byte 0x%02x at byte offset %zu is not text: a binary STL whose size does not match "
                         "its count? (it declares %llu triangles, 84 + 50 x %llu = %llu bytes; the file has %zu)",
                         name, line, p[k], k, (unsigned long long)count, (unsigned long long)count,
                         (unsigned long long)want, len);
            else
                snprintf(msg, msglen, "%s:%d: byte 0x%02x at byte offset %zu is not text", name, line, p[k], k);
            return -1;
        }
        text_in in = {p, len, 0, 1, name, msg, msglen};
        rc = read_ascii(&in, max_triangles, m);
    } else if (len < 84) {
        snprintf(msg, msglen,
                 "%s: neither ASCII STL (it does not begin with 'solid') nor binary (%zu bytes, fewer than the 80-byte "
                 "header and the 4-byte count)",
                 name, len);
        return -1;
    } else if (len < want) {
        const uint64_t k = (len - 84) / 50;
        snprintf(msg, msglen,
                 "%s: truncated binary STL: it declares %llu triangles (84 + 50 x %llu = %llu bytes) but has %zu bytes; "
                 "triangle index %llu is cut at byte offset %zu",
                 name, (unsigned long long)count, (unsigned long long)count, (unsigned long long)want, len,
                 (unsigned long long)k, len);
        return -1;
    } else {
        snprintf(msg, msglen,
                 "%s: binary STL declares %llu triangles (84 + 50 x %llu = %llu bytes) but has %zu bytes: %llu bytes "
                 "after the last triangle, from byte offset %llu",
                 name, (unsigned long long)count, (unsigned long long)count, (unsigned long long)want, len,
                 (unsigned long long)(len - want), (unsigned long long)want);
        return -1;
    }
    if (!rc && m->n == 0) {
        if (m->dropped)
            snprintf(msg, msglen, "%s: every one of its %d triangles has zero area", name, m->dropped);
        else
            snprintf(msg, msglen, "%s: holds no triangles", name);
        rc = -1;
    }
    if (rc) sd_stl_free(m);
    return rc;
}

int sd_stl_read(const char *path, int max_triangles, sd_stl_mesh *m, char *msg, size_t msglen)
{
    memset(m, 0, sizeof *m);
    if (max_triangles > SD_STL_MAX_TRIANGLES) max_triangles = SD_STL_MAX_TRIANGLES;
    if (max_triangles < 0) max_triangles = 0;
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(msg, msglen, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fileno(f), &st) || !S_ISREG(st.st_mode)) {
        snprintf(msg, msglen, "%s: not a regular file", path);
        fclose(f);
        return -1;
    }
    if ((double)st.st_size > SD_STL_MAX_BYTES) {
        snprintf(msg, msglen, "%s: %.0f bytes, more than the limit of %.0f for an STL file", path, (double)st.st_size,
                 SD_STL_MAX_BYTES);
        fclose(f);
        return -1;
    }
    const size_t len = (size_t)st.st_size;
    /* a binary file's count against the limit before its bytes are read */
    unsigned char head[84];
    if (len >= 84 && fread(head, 1, 84, f) == 84) {
        const uint64_t count = get_u32(head + 80);
        if (84 + 50 * count == len && count > (uint64_t)max_triangles) {
            snprintf(msg, msglen, "%s: binary STL of %llu triangles, more than the limit of %d", path,
                     (unsigned long long)count, max_triangles);
            fclose(f);
            return -1;
        }
    }
    rewind(f);
    unsigned char *buf = malloc(len ? len : 1);
    if (!buf) {
        snprintf(msg, msglen, "%s: out of memory for its %zu bytes", path, len);
        fclose(f);
        return -1;
    }
    const size_t got = fread(buf, 1, len, f);
    const int bad = ferror(f) || got != len;
    fclose(f);
    if (bad) {
        snprintf(msg, msglen, "%s: read error (%zu of %zu bytes)", path, got, len);
        free(buf);
        return -1;
    }
    const int rc = sd_stl_parse(buf, len, path, max_triangles, m, msg, msglen);
    free(buf);
    return rc;
}
