/* A sweep file (docs/sweep.md): the base scenario, the seeds, the matrix and the fixed
 * overrides. The matrix is a list of axes; an axis is either one scenario key with its values
 * (scalars, or lists for list-valued keys) or a named set of variants, each of which sets
 * several keys together. Read with every error as file:line:col. */
#ifndef SD_SWEEP_FILE_H
#define SD_SWEEP_FILE_H

#include <stdio.h>

#include "scenario.h"

#define SD_SWEEP_MAX_AXES 8
#define SD_SWEEP_MAX_VALUES 32  /* values (or variants) of one axis */
#define SD_SWEEP_MAX_KEYS 16    /* keys one variant sets */
#define SD_SWEEP_MAX_SETS 64    /* fixed overrides (set:) */
#define SD_SWEEP_MAX_RUNS 10000 /* runs in one sweep (the paper's matrix: 60) */
#define SD_SWEEP_MAX_TEXT 8192  /* one override, "key=value" with the value in YAML flow form */
#define SD_SWEEP_MAX_NAME 64    /* a variant's or a set of variants' name, with its terminator */

/* One "key=value" override, as `--set` takes it, and where its value stands in the sweep file. */
typedef struct {
    char *text;
    int line, col;
} sd_sweep_override;

typedef struct {
    char *label; /* in results.csv, directory names and figures: the value as written (a list in
                  * YAML flow form, [0.05, 0.1]), or the variant's name */
    int n;       /* overrides it makes: 1 for a key's value, 0 to SD_SWEEP_MAX_KEYS for a variant */
    sd_sweep_override set[SD_SWEEP_MAX_KEYS];
} sd_sweep_value;

typedef struct {
    char name[128]; /* the scenario key, or the variants' name: results.csv's column */
    int variants;   /* 1: named variants */
    int n_val;
    sd_sweep_value val[SD_SWEEP_MAX_VALUES];
    int capture; /* 1 when every key it sets acts only from the capture phase on
                  * (sd_scenario_is_capture_key): its values can share a flow */
} sd_sweep_axis;

typedef struct {
    char path[1024]; /* the sweep file, for messages */
    char base[1024]; /* the scenario it varies (relative paths: from the sweep file's directory) */
    int runs;        /* seeds per case */
    long seed_base;
    int parallel; /* processes at once (0: not given) */
    int n_axes;
    sd_sweep_axis axis[SD_SWEEP_MAX_AXES];
    int n_set;
    sd_sweep_override set[SD_SWEEP_MAX_SETS];
} sd_sweep_file;

/* Read a sweep file; 0, or -1 with the errors in err (file:line:col: message). Free it with
 * sd_sweep_file_free either way. */
int sd_sweep_file_load(sd_sweep_file *d, const char *path, FILE *err);
void sd_sweep_file_free(sd_sweep_file *d);
/* The cases: the product of the axes' value counts (as a double: 8 axes of 32 values overflow
 * an int; sd_sweep_file_load refuses more than SD_SWEEP_MAX_RUNS runs). */
double sd_sweep_file_cases(const sd_sweep_file *d);
/* The scenario of one run: the base, the fixed overrides, the axes' values idx[] (one index per
 * axis), the seed and one thread. 0, or -1 with the errors in err, an override's named at its
 * place in the sweep file. */
int sd_sweep_file_scenario(const sd_sweep_file *d, const int *idx, long seed, sd_scenario *s, FILE *err);

#endif
