#include "hash.h"

uint64_t sd_hash_bytes(uint64_t h, const void *p, size_t n)
{
    const unsigned char *q = p;
    for (size_t k = 0; k < n; k++) {
        h ^= q[k];
        h *= 0x100000001b3ULL; /* the FNV 64-bit prime */
    }
    return h;
}
