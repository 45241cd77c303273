/* The status table's messages (sabodem.h SD_STATUS_TABLE), the wall clock and mkdir -p: the
 * small services every layer above may use. */
#ifndef SD_CORE_STATUS_H
#define SD_CORE_STATUS_H

#include "sabodem.h"

/* Wall-clock seconds since an arbitrary origin (monotonic). */
double sd_now(void);
/* mkdir -p; 0 on success. */
int sd_mkdir_p(const char *path);

#endif
