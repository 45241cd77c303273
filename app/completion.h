/* The bash completion (`sabodem completion bash`), generated from the command and parameter
 * tables. */
#ifndef SD_APP_COMPLETION_H
#define SD_APP_COMPLETION_H

#include <stdio.h>

void app_print_bash_completion(FILE *f);

#endif
