/* "Did you mean": edit distance with two rows (the words are keys and options, short). */
#include "core/nearest.h"

#include <stdlib.h>
#include <string.h>

int sd_edit_distance(const char *a, const char *b)
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
        for (size_t j = 1; j <= nb; j++) {
            int best = prev[j - 1] + (a[i - 1] != b[j - 1]);
            if (prev[j] + 1 < best) best = prev[j] + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
        }
        int *t = prev;
        prev = row;
        row = t;
    }
    const int d = prev[nb];
    free(heap);
    return d;
}

const char *sd_nearest_word(const char *word, const char *const *candidates, size_t n)
{
    const int len = (int)strlen(word);
    const int limit = len / 4 > 2 ? len / 4 : 2;
    const char *best = NULL;
    int best_d = limit + 1;
    for (size_t k = 0; k < n; k++) {
        const int d = sd_edit_distance(word, candidates[k]);
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
