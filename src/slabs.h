/* One system over several slab worlds along x (docs/decomposition.md): each world owns the bodies
 * of its slab and holds ghost copies of the others' bodies within the ghost width of it; the
 * ghosts' states come from their owners before every step, the bodies change owner and the
 * boundaries move only when the candidate pairs are remade (in every world at the same steps),
 * and every owned body sums the same pair forces in the same order as one world holding
 * everything with the same fixed grid: the same bits. This is the decomposition's logic with
 * the exchange done by memory copies, all the slabs in one process (for the tests, and the
 * model of the MPI transport, which is not written yet). */
#ifndef SD_SLABS_H
#define SD_SLABS_H

#include "sabodem.h"

#define SD_SLABS_MAX 64

typedef struct {
    int n;              /* slabs, 1 .. SD_SLABS_MAX */
    double ghost_width; /* m; 0: twice the largest bounding radius plus the margin */
    int rebalance;      /* move the boundaries by the measured work every this many rebuilds (0: never) */
    int work_time;      /* 1: work is each slab's wall time; 0: counted (moving bodies + contacts, each
                         * step), which gives the same boundaries on every machine */
} sd_slabs_opts;

typedef struct {
    long steps, rebuilds; /* steps, and the redistributions (one per rebuild of the pairs) */
    long migrations;      /* bodies that changed owner */
    long boundary_moves;  /* inner boundaries that moved */
    long ghost_records;   /* body records copied to a world that does not own them */
    long springs_sent;    /* springs put into a world at its rebuilds */
    double bytes;         /* what an MPI transport would have sent: records and springs */
} sd_slabs_stats;

typedef struct sd_slabs sd_slabs;

/* n slab worlds holding the state of `whole` (its definition, triangles, bodies, springs and
 * clock), with the fixed grid g (which whole should have too, for the same bits). The slab
 * worlds run on one thread each. */
sd_status sd_slabs_create(const sd_world *whole, const sd_grid_def *g, const sd_slabs_opts *o, sd_slabs **out);
void sd_slabs_destroy(sd_slabs *s);
sd_status sd_slabs_step(sd_slabs *s);
sd_status sd_slabs_run(sd_slabs *s, long steps);
/* sd_state_hash_records over the owned bodies and each pair's spring from the owner of its first
 * body: sd_world_state_hash_canonical of the one world that would hold them all. */
uint64_t sd_slabs_state_hash(sd_slabs *s);
/* The boundaries: x[0 .. n] (x[0] = -inf, x[n] = +inf); slab k owns the bodies with x[k] <= x < x[k+1]
 * at the last redistribution. */
void sd_slabs_bounds(const sd_slabs *s, double *x);
/* New inner boundaries x[1 .. n-1], ascending, taken at the next redistribution. */
sd_status sd_slabs_set_bounds(sd_slabs *s, const double *x);
sd_slabs_stats sd_slabs_get_stats(const sd_slabs *s);
int sd_slabs_count(const sd_slabs *s);
sd_world *sd_slabs_world(sd_slabs *s, int k);
/* the slab owning gid (-1: none) and the bodies slab k owns */
int sd_slabs_owner(const sd_slabs *s, int gid);
int sd_slabs_owned(const sd_slabs *s, int k);
double sd_slabs_ghost_width(const sd_slabs *s);

#endif
