/* FNV-1a 64: the one hash of the project (checkpoint checksums, scenario fingerprints, state
 * hashes), chosen for being byte-exact and trivial to restate, not for speed or strength.
 * Streaming: h = sd_hash_init(), then h = sd_hash_bytes(h, p, n) for each piece, equals
 * sd_hash() of all the pieces laid end to end. */
#ifndef SD_CORE_HASH_H
#define SD_CORE_HASH_H

#include <stddef.h>
#include <stdint.h>

/* The published FNV-1a 64 offset basis (14695981039346656037). */
#define SD_HASH_FNV1A_BASIS 0xcbf29ce484222325ULL

/* The basis every sabodem hash starts from: 1469598103934665603, the published basis with its
 * last decimal digit lost when it was first typed. Checkpoint checksums, the scenario
 * fingerprints inside checkpoints and the reference state hashes all depend on it, so it
 * stays: with the published basis every stored file and reference would have to be remade,
 * and the mixing is the same FNV-1a either way. */
#define SD_HASH_SEED 0x14650fb0739d0383ULL

static inline uint64_t sd_hash_init(void) { return SD_HASH_SEED; }

/* h continued over the n bytes at p (p may be NULL when n is 0) */
uint64_t sd_hash_bytes(uint64_t h, const void *p, size_t n);

static inline uint64_t sd_hash(const void *p, size_t n) { return sd_hash_bytes(sd_hash_init(), p, n); }

#endif
