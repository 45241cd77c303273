/* The command line's one table: each subcommand's name, usage, help and options. The usage
 * text, `COMMAND --help`, "did you mean", the man page and the bash completion all come from it
 * (and from the scenario's parameter table, for the keys). */
#ifndef SD_APP_COMMANDS_H
#define SD_APP_COMMANDS_H

#include <stdio.h>

typedef struct {
    const char *name;     /* -o, --set, ... */
    const char *argument; /* what follows it (DIR, key=value, ...), NULL for a flag */
} app_option;

typedef struct {
    const char *name, *usage, *help;
    const app_option *options; /* ends with {NULL, NULL} */
} app_command;

extern const app_command app_commands[];
extern const int app_n_commands;

/* The command called name, or NULL. */
const app_command *app_command_find(const char *name);
/* The usage and every command's help (sabodem --help). */
void app_print_usage(FILE *f);
/* " (did you mean 'X'?)" for a word near a command's name (cmd NULL) or one of cmd's options,
 * else "" (in buf). */
const char *app_did_you_mean(const app_command *cmd, const char *word, char *buf, size_t n);

#endif
