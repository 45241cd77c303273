/* "Did you mean": edit distance with two rows (the words are keys and options, short). */
#include "core/nearest.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

/* The distance, or any value above max once every way through the table costs more than max
 * (each row's smallest entry never decreases down the table). */
static int edit_distance_bounded(const char *a, const char *b, int max)
{
    const size_t na = strlen(a), nb = strlen(b);
    int stack[2][64], *row = stack[0], *prev = stack[1];
    int *heap = NULL;
    if (nb + 1 > 64) {
        heap = malloc(2 * (nb + 1) * sizeof(int));
        if (!heap) return (int)(na > nb ? na : nb); /* (no memory: as far as can be) */
        row = heap;
        prev = heap + nb + 1;
    }
    for (size_t j = 0; j <= nb; j++)
        prev[j] = (int)j;
    for (size_t i = 1; i <= na; i++) {
        row[0] = (int)i;
        int row_min = row[0];
        for (size_t j = 1; j <= nb; j++) {
            int best = prev[j - 1] + (a[i - 1] != b[j - 1]);
            if (prev[j] + 1 < best) best = prev[j] + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            if (best < row_min) row_min = best;
        }
        if (row_min > max) {
            free(heap);
            return max + 1;
        }
        int *t = prev;
        prev = row;
        row = t;
    }
    const int d = prev[nb];
    free(heap);
    return d;
}

int sd_edit_distance(const char *a, const char *b)
{
    return edit_distance_bounded(a, b, INT_MAX - 1);
}

const char *sd_nearest_word(const char *word, const char *const *candidates, size_t n)
{
    const int len = (int)strlen(word);
    const int limit = len / 4 > 2 ? len / 4 : 2;
    const char *best = NULL;
    int best_d = limit + 1;
    for (size_t k = 0; k < n; k++) {
        /* the length difference alone costs that many edits: a long mangled word against short
         * keys is settled without the table */
        const int dl = len - (int)strlen(candidates[k]);
        if (dl >= best_d || -dl >= best_d) continue;
        const int d = edit_distance_bounded(word, candidates[k], best_d - 1);
        if (d < best_d) {
            best_d = d;
            best = candidates[k];
        }
    }
    if (best || len < 3) return best;
    /* an abbreviation: the one candidate that begins with the word */
    for (size_t k = 0; k < n; k++)
        if (!strncmp(candidates[k], word, (size_t)len)) {
            if (best) return NULL;
            best = candidates[k];
        }
    return best;
}
