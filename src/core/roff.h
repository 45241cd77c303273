/* Text for roff (the man page): what must be escaped, escaped. */
#ifndef SD_CORE_ROFF_H
#define SD_CORE_ROFF_H

#include <stdio.h>

/* s onto f with backslashes and hyphens escaped (a hyphen in an option or a key is a minus), and
 * a control character at a line's start ('.' or '\'') made plain text. */
void sd_roff_puts(FILE *f, const char *s);

#endif
