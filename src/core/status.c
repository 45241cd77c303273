/* The status table's messages, the wall clock, mkdir -p (core/status.h). */
#include <errno.h>
#include <stdio.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <time.h>

#include "core/status.h"

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

int sd_mkdir_p(const char *path)
{
    char tmp[1024];
    snprintf(tmp, sizeof tmp, "%s", path);
    for (char *p = tmp + 1; *p; p++)
        if (*p == '/') {
            *p = 0;
            if (mkdir(tmp, 0777) && errno != EEXIST) return -1;
            *p = '/';
        }
    if (mkdir(tmp, 0777) && errno != EEXIST) return -1;
    return 0;
}
