/* core/hash.h and core/binio.h: FNV-1a 64 against its published test vectors and the project's
 * own basis, streaming against one-shot; every typed put read back bit for bit, in the buffer
 * and the sink mode; a failing sink and a short read fail safely (sticky flag, zeros). */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "core/binio.h"
#include "core/hash.h"

static void test_hash(void)
{
    /* published FNV-1a 64 vectors (Fowler, Noll, Vo: the FNV test suite) */
    CHECK(sd_hash_bytes(SD_HASH_FNV1A_BASIS, "", 0) == 0xcbf29ce484222325ULL);
    CHECK(sd_hash_bytes(SD_HASH_FNV1A_BASIS, "a", 1) == 0xaf63dc4c8601ec8cULL);
    CHECK(sd_hash_bytes(SD_HASH_FNV1A_BASIS, "foobar", 6) == 0x85944171f73967e8ULL);
    CHECK(SD_HASH_FNV1A_BASIS == 14695981039346656037ULL);

    /* the basis of every stored sabodem hash (hash.h): pinned, so that it cannot drift */
    CHECK(SD_HASH_SEED == 1469598103934665603ULL);
    CHECK(sd_hash_init() == SD_HASH_SEED);
    CHECK(sd_hash(NULL, 0) == SD_HASH_SEED);
    CHECK(sd_hash("a", 1) == 0x44bd8ad473cd9906ULL);
    CHECK(sd_hash("foobar", 6) == 0x88fad7c0a8ff07f2ULL);

    /* streaming: any cut into two or three pieces gives the one-shot value */
    unsigned char buf[97];
    for (size_t k = 0; k < sizeof buf; k++)
        buf[k] = (unsigned char)(k * 37u + 11u);
    const uint64_t whole = sd_hash(buf, sizeof buf);
    int same = 1;
    for (size_t i = 0; i <= sizeof buf; i++)
        for (size_t j = i; j <= sizeof buf; j++) {
            uint64_t h = sd_hash_init();
            h = sd_hash_bytes(h, buf, i);
            h = sd_hash_bytes(h, buf + i, j - i);
            h = sd_hash_bytes(h, buf + j, sizeof buf - j);
            same &= h == whole;
        }
    CHECK(same);
    CHECK(sd_hash(buf, sizeof buf - 1) != whole);
}

/* a sink that keeps what it is given, and fails (ENOSPC) once more than `room` bytes came */
typedef struct {
    unsigned char data[4096];
    size_t n, room;
    int calls;
} test_sink;

static int keep(void *ctx, const void *p, size_t n)
{
    test_sink *s = ctx;
    s->calls++;
    if (n > s->room - s->n) return ENOSPC;
    memcpy(s->data + s->n, p, n);
    s->n += n;
    return 0;
}

static const int32_t I32[] = {0, 1, -1, INT32_MIN, INT32_MAX, 123456789};
static const int64_t I64[] = {0, -1, INT64_MIN, INT64_MAX, 1234567890123LL};
static const uint64_t U64[] = {0, 1, UINT64_MAX, 0x0123456789abcdefULL};
static const char RAW[] = "raw\0bytes";

static void put_all(sd_bin_writer *w)
{
    const double f64[] = {0.0, -0.0, 1.0 / 3.0, -1.5, 1e-310, 1e308, INFINITY, -INFINITY, NAN};
    for (size_t k = 0; k < sizeof I32 / sizeof I32[0]; k++)
        sd_bin_put_i32(w, I32[k]);
    for (size_t k = 0; k < sizeof I64 / sizeof I64[0]; k++)
        sd_bin_put_i64(w, I64[k]);
    for (size_t k = 0; k < sizeof U64 / sizeof U64[0]; k++)
        sd_bin_put_u64(w, U64[k]);
    for (size_t k = 0; k < sizeof f64 / sizeof f64[0]; k++)
        sd_bin_put_f64(w, f64[k]);
    sd_bin_put_vec3(w, v3(1.25, -0.0, 1e-300));
    sd_bin_put(w, RAW, sizeof RAW);
    sd_bin_put(w, NULL, 0); /* nothing, and no error */
}

static const size_t ALL_BYTES = sizeof I32 + sizeof I64 + sizeof U64 + 9 * 8 + 24 + sizeof RAW;

static void get_all(const void *p, size_t n)
{
    const double f64[] = {0.0, -0.0, 1.0 / 3.0, -1.5, 1e-310, 1e308, INFINITY, -INFINITY, NAN};
    sd_bin_reader r;
    sd_bin_reader_init(&r, p, n);
    for (size_t k = 0; k < sizeof I32 / sizeof I32[0]; k++)
        CHECK(sd_bin_get_i32(&r) == I32[k]);
    for (size_t k = 0; k < sizeof I64 / sizeof I64[0]; k++)
        CHECK(sd_bin_get_i64(&r) == I64[k]);
    for (size_t k = 0; k < sizeof U64 / sizeof U64[0]; k++)
        CHECK(sd_bin_get_u64(&r) == U64[k]);
    for (size_t k = 0; k < sizeof f64 / sizeof f64[0]; k++) {
        double v = sd_bin_get_f64(&r);
        CHECK(memcmp(&v, &f64[k], 8) == 0); /* bits: -0.0 and NaN included */
    }
    sd_vec3 v = sd_bin_get_vec3(&r), want = v3(1.25, -0.0, 1e-300);
    CHECK(memcmp(&v, &want, sizeof v) == 0);
    const char *raw = sd_bin_take(&r, sizeof RAW);
    CHECK(raw != NULL && memcmp(raw, RAW, sizeof RAW) == 0);
    CHECK(!r.bad);
    CHECK(sd_bin_left(&r) == 0);
}

static void test_round_trip(void)
{
    /* buffer mode */
    sd_bin_writer w;
    sd_bin_writer_init(&w);
    put_all(&w);
    CHECK(w.err == 0);
    CHECK(w.n == ALL_BYTES);
    /* the layout is the values' own bytes, end to end (the file formats rely on it) */
    CHECK(memcmp(w.p, &I32[0], 4) == 0 && memcmp(w.p + 4, &I32[1], 4) == 0);
    CHECK(memcmp(w.p + sizeof I32, &I64[0], 8) == 0);
    get_all(w.p, w.n);

    /* sink mode: the same bytes, handed over put by put, none kept in the writer */
    test_sink s = {{0}, 0, sizeof s.data, 0};
    sd_bin_writer ws;
    sd_bin_writer_init_sink(&ws, keep, &s);
    put_all(&ws);
    CHECK(ws.err == 0);
    CHECK(ws.n == w.n && s.n == w.n);
    CHECK(ws.p == NULL);
    CHECK(memcmp(s.data, w.p, w.n) == 0);
    sd_bin_writer_fini(&ws);
    sd_bin_writer_fini(&w);
    CHECK(w.p == NULL && w.n == 0);

    /* growth well past the first allocation */
    sd_bin_writer g;
    sd_bin_writer_init(&g);
    for (int32_t k = 0; k < 100000; k++)
        sd_bin_put_i32(&g, k * 7 - 3);
    CHECK(g.err == 0 && g.n == 400000);
    sd_bin_reader r;
    sd_bin_reader_init(&r, g.p, g.n);
    int ok = 1;
    for (int32_t k = 0; k < 100000; k++)
        ok &= sd_bin_get_i32(&r) == k * 7 - 3;
    CHECK(ok && !r.bad && sd_bin_left(&r) == 0);
    sd_bin_writer_fini(&g);
}

static void test_sink_failure(void)
{
    /* room for two i32s: the third put fails, and every later one is dropped unseen */
    test_sink s = {{0}, 0, 8, 0};
    sd_bin_writer w;
    sd_bin_writer_init_sink(&w, keep, &s);
    sd_bin_put_i32(&w, 1);
    sd_bin_put_i32(&w, 2);
    sd_bin_put_f64(&w, 3.0);
    CHECK(w.err == ENOSPC);
    CHECK(w.n == 8 && s.n == 8 && s.calls == 3);
    sd_bin_put_i32(&w, 4);
    CHECK(w.err == ENOSPC && w.n == 8 && s.calls == 3);
}

static void test_truncated(void)
{
    unsigned char buf[10];
    for (size_t k = 0; k < sizeof buf; k++)
        buf[k] = (unsigned char)(0x10 + k);
    sd_bin_reader r;
    sd_bin_reader_init(&r, buf, sizeof buf);
    uint64_t first;
    memcpy(&first, buf, 8);
    CHECK(sd_bin_get_u64(&r) == first);
    CHECK(!r.bad && sd_bin_left(&r) == 2);

    /* 4 bytes wanted, 2 left: bad, zero, and the cursor does not move */
    CHECK(sd_bin_get_i32(&r) == 0);
    CHECK(r.bad);
    CHECK(sd_bin_left(&r) == 2);

    /* sticky: what would fit fails too, and every typed get reads zero */
    unsigned char one = 0xAA;
    sd_bin_get(&r, &one, 1);
    CHECK(one == 0);
    CHECK(sd_bin_take(&r, 1) == NULL);
    CHECK(sd_bin_get_i64(&r) == 0);
    CHECK(sd_bin_get_u64(&r) == 0);
    double d = sd_bin_get_f64(&r);
    CHECK(d == 0.0 && !signbit(d));
    sd_vec3 v = sd_bin_get_vec3(&r);
    CHECK(v.x == 0.0 && v.y == 0.0 && v.z == 0.0);
    unsigned char block[16];
    memset(block, 0xAA, sizeof block);
    sd_bin_get(&r, block, sizeof block);
    int zero = 1;
    for (size_t k = 0; k < sizeof block; k++)
        zero &= block[k] == 0;
    CHECK(zero);
    CHECK(r.bad && sd_bin_left(&r) == 2);

    /* a count beyond the end cannot wrap the bound (n > left, not pos + n > size) */
    sd_bin_reader big;
    sd_bin_reader_init(&big, buf, sizeof buf);
    CHECK(sd_bin_take(&big, SIZE_MAX) == NULL && big.bad);

    /* nothing to read: a zero-byte take succeeds, anything more fails */
    sd_bin_reader empty;
    sd_bin_reader_init(&empty, NULL, 0);
    CHECK(sd_bin_take(&empty, 0) != NULL && !empty.bad);
    CHECK(sd_bin_get_i32(&empty) == 0 && empty.bad);
}

int main(void)
{
    test_hash();
    test_round_trip();
    test_sink_failure();
    test_truncated();
    return check_report("test_binio");
}
