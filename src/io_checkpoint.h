/* Checkpoint and restart: the whole state of a world in one versioned, checksummed binary
 * file, written atomically, from which a run continues bit for bit as if never stopped.
 *
 * Saved: the world definition; the springs of the pairs of materials that have their own; every
 * body field of the field table (bodies.c, the material ids among them), in store order, with
 * gid_map and next_gid; the triangles (vertices and normals as stored, groups, active flags,
 * materials, the last step's wall loads, the dirty flag); the triangle grid while it is current
 * (its cell size depends on the bodies present when it was built, so it is not recomputed);
 * both candidate pair lists with their effective masses and contact history slots (the pair
 * order is the summation order); the history carried between a store change (add, remove,
 * group switch) and the next rebuild; time, step, last_rebuild_time, need_rebuild,
 * rebuild_every_step, the contact count and the timers; and an opaque blob of the driver's own
 * state (phase, accumulators, rng). Recomputed on reading, deterministically: bt_start from
 * the pair lists, the weld ids of the walls (a pure function of the
 * vertices), scratch arrays. Not saved: the per-pair out[] and active[] (rewritten by the next
 * force pass before the gather reads them), the parallel pass's body ranges and cross-pair
 * list (sd_owned: derived from the pair list on first use), the body grid and cell ranges (rebuilt from scratch
 * at every candidate rebuild), the history shear of empty slots (never read; written as 0).
 * io_checkpoint.c asserts the sizes of the structures it serialises, so that a new field in
 * sd_world, sd_world_def, sd_walls, sd_pairlist... fails the build until it is handled here.
 * Nothing of the restore forces a candidate rebuild: the next rebuild happens at the step it
 * would have happened at without the restart.
 *
 * File layout (all integers and doubles in the writer's native byte order, which the header
 * records; a reader of the other byte order refuses the file):
 *   header, 64 bytes:
 *     0  char[8]  "SABODEMC"
 *     8  u32      format version (SD_CHECKPOINT_VERSION)
 *     12 u32      0x01020304 written natively (endianness check)
 *     16 u8[8]    sizes: double, sd_vec3, sd_quat, int32, int64, sd_tri, 0, 0
 *     24 f64      -1.5 (IEEE-754 binary64 check)
 *     32 u64      payload length in bytes (the file is exactly 64 + that long)
 *     40 u64      FNV-1a 64 of the payload, from sabodem's basis (sd_hash, core/hash.h)
 *     48 u64[2]   zero (reserved)
 *   payload: sections in a fixed order, each u32 tag (4 ASCII chars), u32 0, u64 length,
 *   then the content: DEF, MATL (count, then per pair of materials a <= b: a, b, k_n, k_s,
 *   damping, tan_phi, cohesion), BODY (n, field count, then per field: name, element size, the n
 *   elements), GIDS, WALL, TGRD, PRBB, PRBT (pair lists), OLDH (carried history), TIME, XTRA.
 * Every header byte is checked by value and the payload by its checksum, so a truncated,
 * corrupted or foreign file is refused, and the content is range-checked before use. */
#ifndef SD_IO_CHECKPOINT_H
#define SD_IO_CHECKPOINT_H

#include <stddef.h>

#include "sabodem.h"

#define SD_CHECKPOINT_VERSION 2u

/* (sd_checkpoint_write and sd_checkpoint_read: sabodem.h) */

/* sd_checkpoint_write that fails (as a full disk would, errno ENOSPC) once more than fail_after
 * bytes of the file have been written (-1: never), for the tests. */
sd_status sd_checkpoint_write_capped(const char *path, const sd_world *w, const void *extra, size_t extra_len,
                                     long long fail_after);

#endif
