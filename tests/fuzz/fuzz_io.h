/* What the fuzz harnesses share: the readers under test take file paths, so each input is
 * written to a file in a directory of the process's own (made once, removed at exit), and
 * their messages go to /dev/null. */
#ifndef SD_FUZZ_IO_H
#define SD_FUZZ_IO_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char fuzz_dir_path[64];

static inline void fuzz_dir_remove(void)
{
    static const char *const names[] = {"input.yaml", "base.yaml", "input.ckpt", "fixed.yaml", "input.stl", NULL};
    char p[128];
    for (int k = 0; names[k]; k++) {
        snprintf(p, sizeof p, "%s/%s", fuzz_dir_path, names[k]);
        unlink(p);
    }
    rmdir(fuzz_dir_path);
}

/* The process's directory (made on first use). */
static inline const char *fuzz_dir(void)
{
    if (!fuzz_dir_path[0]) {
        snprintf(fuzz_dir_path, sizeof fuzz_dir_path, "/tmp/sd_fuzz.XXXXXX");
        if (!mkdtemp(fuzz_dir_path)) {
            perror("fuzz: mkdtemp");
            abort();
        }
        atexit(fuzz_dir_remove);
    }
    return fuzz_dir_path;
}

/* Write data to <dir>/name; returns the path (static storage, one per name slot). */
static inline const char *fuzz_file(const char *name, const void *data, size_t size)
{
    static char path[4][128];
    static int slot;
    char *p = path[slot++ & 3];
    snprintf(p, 128, "%s/%s", fuzz_dir(), name);
    FILE *f = fopen(p, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f)) {
        perror("fuzz: writing the input file");
        abort();
    }
    return p;
}

static inline FILE *fuzz_null(void)
{
    static FILE *f;
    if (!f) f = fopen("/dev/null", "w");
    if (!f) abort();
    return f;
}

#endif
