/* core/nearest.h ("did you mean"): edit distances against hand-counted values, long words past
 * the stack rows, and which candidate is offered (or none). */
#include <string.h>

#include "check.h"
#include "core/nearest.h"

int main(void)
{
    CHECK(sd_edit_distance("kitten", "sitting") == 3);
    CHECK(sd_edit_distance("", "abc") == 3);
    CHECK(sd_edit_distance("abc", "") == 3);
    CHECK(sd_edit_distance("solver.dt", "solver.dt") == 0);
    CHECK(sd_edit_distance("contact.kn", "contact.k_n") == 1);
    CHECK(sd_edit_distance("flaw", "lawn") == 2);
    /* longer than the 64-entry rows on the stack: one substitution in 100 characters */
    char a[101], b[101];
    memset(a, 'x', 100);
    a[100] = 0;
    memcpy(b, a, sizeof a);
    b[50] = 'y';
    CHECK(sd_edit_distance(a, b) == 1);
    CHECK(sd_edit_distance(a, "x") == 99);

    static const char *const keys[] = {"solver.dt", "solver.duration", "solver.seed", "dam.l_h", "dam.l_v"};
    const size_t n = sizeof keys / sizeof keys[0];
    CHECK(sd_nearest_word("solver.durration", keys, n) == keys[1]);
    CHECK(sd_nearest_word("solver.sed", keys, n) == keys[2]);
    CHECK(sd_nearest_word("dam.l_x", keys, n) == keys[3]); /* a tie: the first */
    CHECK(sd_nearest_word("water.u", keys, n) == NULL);
    CHECK(sd_nearest_word("solver.d", keys, n) == keys[0]);
    /* an abbreviation, when it is one candidate's alone */
    static const char *const opts[] = {"--markdown", "--help"};
    CHECK(sd_nearest_word("--mark", opts, 2) == opts[0]);
    static const char *const two[] = {"--dry-run", "--dry-spell"};
    CHECK(sd_nearest_word("--dr", two, 2) == NULL);
    CHECK(sd_nearest_word("x", keys, 0) == NULL);
    /* a long mangled word: none near (the length difference settles it), and a long word one
     * edit from a long candidate is still found past the bound of the earlier candidates */
    static char big[20001];
    memset(big, 'd', sizeof big - 1);
    CHECK(sd_nearest_word(big, keys, n) == NULL);
    char c[101];
    memcpy(c, a, sizeof a);
    c[7] = 'z';
    const char *const longs[] = {"solver.dt", b, a};
    CHECK(sd_nearest_word(c, longs, 3) == a); /* 2 edits from b, then 1 from a: a is offered */
    CHECK(sd_edit_distance(c, b) == 2 && sd_edit_distance(c, a) == 1);
    return check_report("test_nearest");
}
