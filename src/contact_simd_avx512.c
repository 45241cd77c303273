/* The body-body pass's AVX-512 kernels (8 lanes): the touch filter and the gather. Their
 * references are the scalar loops of contact_bb.c; the same bits. */
#include "contact_kernels.h"

#ifdef SD_FILTER512
#include <immintrin.h>
#include <stddef.h>

/* Step 1 of sd_bb_chunk (the touch filter) for 8 pairs at a time, in AVX-512: the pair records
 * loaded from the chunk's view v, both centres and radii and the spring's feature gathered
 * into lanes, the touch test with the
 * scalar loop's operations in its order (same bits), the touching sphere pairs packed into the
 * batch by compress and stored 8 lanes wide (the arrays are padded by SS_PAD). A pair of
 * another kind (a log's) in a group takes the scalar loop's path for it, in pair order. Runs
 * while 8 pairs remain and returns where it stopped. */
__attribute__((target("avx512f,avx512vl,popcnt"))) int sd_avx512_ss_filter(const sd_world *w, const int32_t *ks,
                                                                           const soa_view *v, int i, int n, int *used,
                                                                           ss_batch *q, int *mp, int *gen, int *ngp)
{
    sd_hist *hist = v->sh;
    const double *pos = &w->b.pos[0].x, *rad = w->b.radius;
    int m = *mp, ng = *ngp;
    const __m256i one = _mm256_set1_epi32(1), none = _mm256_set1_epi32(-1), hi16 = _mm256_set1_epi32((int)0xFFFF0000u),
                  lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    for (; i + 8 <= n; i += 8) {
        /* the records field by field, in entry order (loads, where gathering them from the
         * store's scattered lines cost the one-thread step 12-14 %); cap in the low half
         * of ck and kind in the high half, kind SD_PAIR_SS is 0 */
        const __m256i ck = _mm256_loadu_si256((const __m256i *)(v->ck + i)),
                      a = _mm256_loadu_si256((const __m256i *)(v->a + i)),
                      b = _mm256_loadu_si256((const __m256i *)(v->b + i)),
                      off = _mm256_loadu_si256((const __m256i *)(v->off + i));
        const __mmask8 other = _mm256_test_epi32_mask(ck, hi16), ss = (__mmask8)~other;
        const __m256i a3 = _mm256_add_epi32(a, _mm256_add_epi32(a, a)),
                      b3 = _mm256_add_epi32(b, _mm256_add_epi32(b, b));
        const __m512d dx = _mm512_sub_pd(_mm512_i32gather_pd(a3, pos, 8), _mm512_i32gather_pd(b3, pos, 8));
        const __m512d dy = _mm512_sub_pd(_mm512_i32gather_pd(a3, pos + 1, 8), _mm512_i32gather_pd(b3, pos + 1, 8));
        const __m512d dz = _mm512_sub_pd(_mm512_i32gather_pd(a3, pos + 2, 8), _mm512_i32gather_pd(b3, pos + 2, 8));
        const __m512d ra = _mm512_i32gather_pd(a, rad, 8), rb = _mm512_i32gather_pd(b, rad, 8);
        const __m512d rs = _mm512_add_pd(ra, rb);
        const __m512d d2 =
            _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
        /* t = !(d2 >= rs^2), as the scalar loop (true for an unordered pair too); sphere pairs only */
        const __mmask8 t = (__mmask8)(_mm512_cmp_pd_mask(d2, _mm512_mul_pd(rs, rs), _CMP_NGE_UQ) & ss);
        /* the spring's feature (slot off, 32-byte slots: index 4 off, scale 8), of the sphere
         * lanes only: the others' off point into bb.hist, which need not be where hist is */
        /* (in a list's own slots, from the entries' flags: 0 with a spring, else -1) */
        const __m256i was =
            v->lsq ? _mm256_sub_epi32(_mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(v->act + i))), one)
                   : _mm256_mmask_i32gather_epi32(none, ss, _mm256_slli_epi32(off, 2),
                                                  (const int *)((const char *)hist + offsetof(sd_hist, feature)), 8);
        _mm256_mask_storeu_epi32(used + i, ss, _mm256_maskz_mov_epi32(t, one));
        /* the entries' flags: a spring after this step where they touch (soa_view.act; this
         * form reads the slots themselves) */
        for (int l = 0; l < 8; l++)
            v->act[i + l] = (uint8_t)(t >> l & 1);
        /* was | (t - 1): stored only where it changes (a contact that has just ended) */
        __mmask8 gone = v->lsq ? 0 : (__mmask8)(~t & ss & _mm256_cmpneq_epi32_mask(was, none));
        if (gone) {
            int32_t o[8];
            _mm256_storeu_si256((__m256i *)o, off);
            for (; gone; gone &= (__mmask8)(gone - 1))
                hist[o[__builtin_ctz(gone)]].feature = -1;
        }
        _mm512_storeu_pd(q->dx + m, _mm512_maskz_compress_pd(t, dx));
        _mm512_storeu_pd(q->dy + m, _mm512_maskz_compress_pd(t, dy));
        _mm512_storeu_pd(q->dz + m, _mm512_maskz_compress_pd(t, dz));
        _mm512_storeu_pd(q->ra + m, _mm512_maskz_compress_pd(t, ra));
        _mm512_storeu_pd(q->rb + m, _mm512_maskz_compress_pd(t, rb));
        if (!v->lsq) _mm512_storeu_pd(q->sqm + m, _mm512_maskz_compress_pd(t, _mm512_loadu_pd(v->sqm + i)));
        _mm256_storeu_si256((__m256i *)(q->ia + m), _mm256_maskz_compress_epi32(t, a));
        _mm256_storeu_si256((__m256i *)(q->ib + m), _mm256_maskz_compress_epi32(t, b));
        _mm256_storeu_si256((__m256i *)(q->off + m), _mm256_maskz_compress_epi32(t, off));
        _mm256_storeu_si256((__m256i *)(q->was + m), _mm256_maskz_compress_epi32(t, was));
        _mm256_storeu_si256((__m256i *)(q->sel + m),
                            _mm256_maskz_compress_epi32(t, _mm256_add_epi32(_mm256_set1_epi32(i), lane)));
        m += __builtin_popcount(t);
        /* the log pairs and cross entries of the group, as the scalar loop takes them, but a
         * sphere-log pair's apart test left to sd_avx2_sc_geom's lanes, as sd_avx2_ss_filter leaves it
         * (its kind from the view: the pair store's line is read only for the other log pairs) */
        const int defer = w->sw[SD_SW_SC_LANES] && w->sw[SD_SW_SC_GEOM];
        for (__mmask8 o = other; o; o &= (__mmask8)(o - 1))
            filter_other(w, ks, v, i + __builtin_ctz(o), defer, used, gen, &ng);
    }
    *mp = m;
    *ngp = ng;
    return i;
}

/* Step 3 of sd_bb_chunk in AVX-512, 8 lanes at a time (the last group masked): the touching
 * pairs' velocities, spins and stored springs gathered into the batch, a new contact's spring
 * +0.0 as the scalar loop's mask gives it (same bits). */
__attribute__((target("avx512f,avx512vl"))) void sd_avx512_ss_gather(const sd_world *w, ss_batch *q, int m)
{
    const double *vel = &w->b.vel[0].x, *om = &w->b.omega[0].x;
    const char *sh = (const char *)q->sh + offsetof(sd_hist, shear);
    const __m512d zero = _mm512_setzero_pd();
    for (int j = 0; j < m; j += 8) {
        const __mmask8 live = (__mmask8)(m - j >= 8 ? 0xFF : (1u << (m - j)) - 1u);
        const __m256i ia = _mm256_maskz_loadu_epi32(live, q->ia + j), ib = _mm256_maskz_loadu_epi32(live, q->ib + j);
        const __m256i a3 = _mm256_add_epi32(ia, _mm256_add_epi32(ia, ia)),
                      b3 = _mm256_add_epi32(ib, _mm256_add_epi32(ib, ib));
        _mm512_storeu_pd(q->vx + j, _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, live, a3, vel, 8),
                                                  _mm512_mask_i32gather_pd(zero, live, b3, vel, 8)));
        _mm512_storeu_pd(q->vy + j, _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, live, a3, vel + 1, 8),
                                                  _mm512_mask_i32gather_pd(zero, live, b3, vel + 1, 8)));
        _mm512_storeu_pd(q->vz + j, _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, live, a3, vel + 2, 8),
                                                  _mm512_mask_i32gather_pd(zero, live, b3, vel + 2, 8)));
        _mm512_storeu_pd(q->wax + j, _mm512_mask_i32gather_pd(zero, live, a3, om, 8));
        _mm512_storeu_pd(q->way + j, _mm512_mask_i32gather_pd(zero, live, a3, om + 1, 8));
        _mm512_storeu_pd(q->waz + j, _mm512_mask_i32gather_pd(zero, live, a3, om + 2, 8));
        _mm512_storeu_pd(q->wbx + j, _mm512_mask_i32gather_pd(zero, live, b3, om, 8));
        _mm512_storeu_pd(q->wby + j, _mm512_mask_i32gather_pd(zero, live, b3, om + 1, 8));
        _mm512_storeu_pd(q->wbz + j, _mm512_mask_i32gather_pd(zero, live, b3, om + 2, 8));
        /* the spring of a held contact (its feature was 0); 32-byte slots: index 4 off, scale 8 */
        const __mmask8 held = (__mmask8)(live & _mm256_cmpeq_epi32_mask(_mm256_maskz_loadu_epi32(live, q->was + j),
                                                                        _mm256_setzero_si256()));
        const __m256i o4 = _mm256_slli_epi32(_mm256_maskz_loadu_epi32(live, q->off + j), 2);
        _mm512_storeu_pd(q->sx + j, _mm512_mask_i32gather_pd(zero, held, o4, sh, 8));
        _mm512_storeu_pd(q->sy + j, _mm512_mask_i32gather_pd(zero, held, o4, sh + 8, 8));
        _mm512_storeu_pd(q->sz + j, _mm512_mask_i32gather_pd(zero, held, o4, sh + 16, 8));
        if (q->lsq) /* (a list's own slot: sqm in the first 8 bytes) */
            _mm512_storeu_pd(q->sqm + j, _mm512_mask_i32gather_pd(zero, live, o4, sh - 8, 8));
    }
}

/* the table's form of the gather (contact_internal.h sd_contact_kernels): all m lanes */
static int ss_gather8(const sd_world *w, ss_batch *q, int m)
{
    sd_avx512_ss_gather(w, q, m);
    return m;
}

/* AVX-512: the filter and the gather in 8 lanes; the sums, the sphere-log geometry and the
 * near test in AVX2's 4; the springs as the compiler vectorizes them (where the AVX2 loop,
 * which skips the limit's root and division, ran no faster) */
const sd_contact_kernels sd_avx512_kernels = {
    .ss_filter = sd_avx512_ss_filter,
    .ss_gather = ss_gather8,
    .ss_law_spring = NULL,
    .ss_sums = sd_avx2_ss_sums,
    .sc_geom = sd_avx2_sc_geom,
    .near_test = sd_avx2_near_test,
};
#else
typedef int sd_contact_simd_avx512_none; /* (ISO C: a translation unit declares something) */
#endif
