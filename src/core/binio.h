/* Binary serialisation, the one writer and one reader behind checkpoints and the run driver's
 * state blob. Values are written as their bytes in the machine's own order and layout, with
 * no framing: the formats built on it (io_checkpoint.h) record byte order and sizes once in
 * their header instead of converting every value.
 *
 * Writer: without a sink it appends to a growable buffer (p, n); with a sink every put goes
 * straight to the sink and only the count n is kept, so a file is streamed without holding it
 * in memory. The first failure (ENOMEM, or the sink's error) is kept in err and every later
 * put is dropped, so a sequence of puts is checked once at the end.
 *
 * Reader: a bounded cursor over bytes it does not own. A read past the end sets the sticky
 * bad flag and yields zeros, so a parser reads a whole record and checks bad once, and a
 * truncated or hostile input can never make it read outside the bytes. */
#ifndef SD_CORE_BINIO_H
#define SD_CORE_BINIO_H

#include <stddef.h>
#include <stdint.h>

#include "vmath.h"

/* 0 when the n bytes at p were taken, else an errno value (which becomes the writer's err) */
typedef int (*sd_bin_sink)(void *ctx, const void *p, size_t n);

typedef struct {
    unsigned char *p; /* the bytes put so far (no sink); owned, freed by sd_bin_writer_fini */
    size_t n;         /* bytes put so far, in either mode */
    size_t cap;
    int err; /* errno of the first failure, 0 while none */
    sd_bin_sink sink;
    void *sink_ctx;
} sd_bin_writer;

typedef struct {
    const unsigned char *p;
    size_t n, pos;
    int bad; /* sticky: a read ran past the end (or the caller found the content invalid) */
} sd_bin_reader;

void sd_bin_writer_init(sd_bin_writer *w);
void sd_bin_writer_init_sink(sd_bin_writer *w, sd_bin_sink sink, void *ctx);
void sd_bin_writer_fini(sd_bin_writer *w);

void sd_bin_put(sd_bin_writer *w, const void *p, size_t n);
static inline void sd_bin_put_i32(sd_bin_writer *w, int32_t v) { sd_bin_put(w, &v, sizeof v); }
static inline void sd_bin_put_i64(sd_bin_writer *w, int64_t v) { sd_bin_put(w, &v, sizeof v); }
static inline void sd_bin_put_u64(sd_bin_writer *w, uint64_t v) { sd_bin_put(w, &v, sizeof v); }
static inline void sd_bin_put_f64(sd_bin_writer *w, double v) { sd_bin_put(w, &v, sizeof v); }
static inline void sd_bin_put_vec3(sd_bin_writer *w, sd_vec3 v) { sd_bin_put(w, &v, sizeof v); }

void sd_bin_reader_init(sd_bin_reader *r, const void *p, size_t n);
static inline size_t sd_bin_left(const sd_bin_reader *r) { return r->n - r->pos; }

/* The next n bytes in place, or NULL (and bad set) when fewer are left. */
const void *sd_bin_take(sd_bin_reader *r, size_t n);
/* The next n bytes copied to dst, or zeros there (and bad set) when fewer are left. */
void sd_bin_get(sd_bin_reader *r, void *dst, size_t n);

static inline int32_t sd_bin_get_i32(sd_bin_reader *r)
{
    int32_t v;
    sd_bin_get(r, &v, sizeof v);
    return v;
}
static inline int64_t sd_bin_get_i64(sd_bin_reader *r)
{
    int64_t v;
    sd_bin_get(r, &v, sizeof v);
    return v;
}
static inline uint64_t sd_bin_get_u64(sd_bin_reader *r)
{
    uint64_t v;
    sd_bin_get(r, &v, sizeof v);
    return v;
}
static inline double sd_bin_get_f64(sd_bin_reader *r)
{
    double v;
    sd_bin_get(r, &v, sizeof v);
    return v;
}
static inline sd_vec3 sd_bin_get_vec3(sd_bin_reader *r)
{
    sd_vec3 v;
    sd_bin_get(r, &v, sizeof v);
    return v;
}

#endif
