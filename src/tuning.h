/* The engine's tuning (sabodem.h sd_tuning), as a world resolves it. */
#ifndef SD_TUNING_H
#define SD_TUNING_H

#include "sabodem.h"

/* The level a world runs at when asked for `asked` (SD_SIMD_AUTO or a level) on a CPU whose best
 * is `cpu`, AMD or not. */
int sd_tuning_simd_level(int asked, int cpu, int amd);

#endif
