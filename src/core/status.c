#include <sys/time.h>
#include <time.h>

#include "../world_internal.h"

const char *sd_status_message(sd_status s)
{
    static const char *msg[] = {
#define SD_X_MSG(name, text) text,
        SD_STATUS_TABLE(SD_X_MSG)
#undef SD_X_MSG
    };
    if ((int)s < 0 || s >= SD_STATUS_COUNT) return "unknown status";
    return msg[s];
}

double sd_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
