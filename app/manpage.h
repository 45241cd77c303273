/* The man page (`sabodem man`), generated from the command and parameter tables. */
#ifndef SD_APP_MANPAGE_H
#define SD_APP_MANPAGE_H

#include <stdio.h>

void app_print_man(FILE *f, const char *version);

#endif
