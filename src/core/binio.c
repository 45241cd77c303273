#include "binio.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

void sd_bin_writer_init(sd_bin_writer *w) { memset(w, 0, sizeof *w); }

void sd_bin_writer_init_sink(sd_bin_writer *w, sd_bin_sink sink, void *ctx)
{
    memset(w, 0, sizeof *w);
    w->sink = sink;
    w->sink_ctx = ctx;
}

void sd_bin_writer_fini(sd_bin_writer *w)
{
    free(w->p);
    memset(w, 0, sizeof *w);
}

void sd_bin_put(sd_bin_writer *w, const void *p, size_t n)
{
    if (w->err || n == 0) return;
    if (w->sink) {
        int e = w->sink(w->sink_ctx, p, n);
        if (e) {
            w->err = e;
            return;
        }
        w->n += n;
        return;
    }
    if (n > w->cap - w->n) {
        /* doubling keeps a long run of small puts linear */
        size_t cap = w->cap ? w->cap : 1024;
        while (cap - w->n < n) {
            if (cap > SIZE_MAX / 2) {
                w->err = ENOMEM;
                return;
            }
            cap *= 2;
        }
        unsigned char *q = realloc(w->p, cap);
        if (!q) {
            w->err = ENOMEM;
            return;
        }
        w->p = q;
        w->cap = cap;
    }
    memcpy(w->p + w->n, p, n);
    w->n += n;
}

void sd_bin_reader_init(sd_bin_reader *r, const void *p, size_t n)
{
    /* never a NULL base: a take of zero bytes then yields a valid pointer, not NULL + 0 */
    static const unsigned char none[1];
    r->p = p ? p : none;
    r->n = p ? n : 0;
    r->pos = 0;
    r->bad = 0;
}

const void *sd_bin_take(sd_bin_reader *r, size_t n)
{
    if (r->bad || n > r->n - r->pos) {
        r->bad = 1;
        return NULL;
    }
    const void *q = r->p + r->pos;
    r->pos += n;
    return q;
}

void sd_bin_get(sd_bin_reader *r, void *dst, size_t n)
{
    if (n == 0) return;
    const void *q = sd_bin_take(r, n);
    if (q)
        memcpy(dst, q, n);
    else
        memset(dst, 0, n);
}
