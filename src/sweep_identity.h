/* The identity of a sweep's shared flow checkpoint (docs/sweep.md), kept beside it in a JSON
 * file: what made it (the engine: the program's version, the source it was built from, the
 * checkpoint and driver-state formats) and what it holds (the scenario up to the branch point:
 * the hash of every key that acts before the flow ends, the seed included, and their values).
 * A resumed sweep branches from a checkpoint only when both match; otherwise it computes the
 * flow again. */
#ifndef SD_SWEEP_IDENTITY_H
#define SD_SWEEP_IDENTITY_H

#include <stddef.h>

#include "scenario.h"

enum { SD_IDENTITY_SAME = 0, SD_IDENTITY_ENGINE = 1, SD_IDENTITY_SCENARIO = 2, SD_IDENTITY_NONE = -1 };

/* This program's engine, in words: "sabodem 0.9.0 (git <commit>), checkpoint format 1, driver
 * state SDRUNv3". */
void sd_sweep_identity_engine(char *buf, size_t n);
/* Write the identity of a flow of scenario s to path, atomically; 0, or -1 (errno set). */
int sd_sweep_identity_write(const char *path, const sd_scenario *s);
/* Compare the identity at path with this program and s: SD_IDENTITY_SAME; _ENGINE (made by
 * another engine) or _SCENARIO (for other values of keys that act before the branch point),
 * with what differs in msg; _NONE when there is none or it cannot be read (why in msg). */
int sd_sweep_identity_check(const char *path, const sd_scenario *s, char *msg, size_t n);

#endif
