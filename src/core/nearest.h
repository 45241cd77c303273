/* "Did you mean": the known word nearest to a misspelt one, by edit distance. */
#ifndef SD_CORE_NEAREST_H
#define SD_CORE_NEAREST_H

#include <stddef.h>

/* The Levenshtein distance (insertions, deletions, substitutions) between a and b. */
int sd_edit_distance(const char *a, const char *b);
/* The candidate nearest to word, or NULL when none is near enough to be a misspelling (at most
 * 2 edits, or a quarter of the word's length for long words), or, failing that, the one
 * candidate the word abbreviates (3 characters or more). Ties go to the first. */
const char *sd_nearest_word(const char *word, const char *const *candidates, size_t n);

#endif
