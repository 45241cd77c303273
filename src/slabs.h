/* One system over several slab worlds along x (docs/decomposition.md): each world owns the bodies
 * of its slab and holds ghost copies of the others' bodies within the ghost width of it; the
 * ghosts' states come from their owners before every step, the bodies change owner and the
 * boundaries move only when the candidate pairs are remade (in every world at the same steps),
 * and every owned body sums the same pair forces in the same order as one world holding
 * everything with the same fixed grid: the same bits. sd_slab is one slab (what one MPI rank
 * holds) with the exchange left to its caller; sd_slabs, n of them in one process exchanging by
 * memory copies. */
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
    int threads;        /* each slab world's threads (0: one) */
} sd_slabs_opts;

typedef struct {
    long steps, rebuilds; /* steps, and the redistributions (one per rebuild of the pairs) */
    long migrations;      /* bodies that changed owner */
    long boundary_moves;  /* inner boundaries that moved */
    long ghost_records;   /* body records copied to a world that does not own them */
    long springs_sent;    /* springs put into a world at its rebuilds */
    double bytes;         /* what an MPI transport would have sent: records and springs */
} sd_slabs_stats;

/* ---- One slab, as one MPI rank holds it: the step in phases, the exchange between them done
 * by the caller (sd_slabs below by memory copies; tests/mpi_slabs.c by MPI). A step:
 *   any = OR over the slabs of sd_slab_wants_rebuild
 *   if any and sd_slab_balance_due: bins (grid.nx of them) = the sum over the slabs, in slab
 *     order, of sd_slab_work_bins; sd_slab_balance(bins), the same on every slab
 *   sd_slab_pack(any); message r -> slab k: sd_slab_outbox(slab r, k); sd_slab_unpack(any, in)
 *   sd_slab_step_world
 * any = 1: the redistribution (records of every body to every slab that will hold it, springs
 * to every slab that will hold their first body); 0: the ghosts' refresh. */
typedef struct sd_slab sd_slab;
/* slab k of n over the state of `whole` (every slab is made from the same whole world; over MPI
 * each rank builds it, or rank 0 sends it) with bounds xb[0 .. n] */
sd_status sd_slab_create(const sd_world *whole, const sd_grid_def *g, const sd_slabs_opts *o, int k, const double *xb,
                         sd_slab **out);
void sd_slab_destroy(sd_slab *s);
/* the first bounds of n slabs over whole: as many moving bodies in each */
void sd_slab_first_bounds(const sd_world *whole, int n, double *xb);
int sd_slab_wants_rebuild(const sd_slab *s);
int sd_slab_balance_due(const sd_slab *s);
int sd_slab_bins(const sd_slab *s); /* the bins' count (grid.nx) */
void sd_slab_work_bins(const sd_slab *s, double *bins);
void sd_slab_balance(sd_slab *s, const double *bins);
sd_status sd_slab_set_bounds(sd_slab *s, const double *x);
sd_status sd_slab_pack(sd_slab *s, int any);
const void *sd_slab_outbox(const sd_slab *s, int to, size_t *len);
sd_status sd_slab_unpack(sd_slab *s, int any, const void *const *in, const size_t *len);
sd_status sd_slab_step_world(sd_slab *s);
/* the owned bodies' records and the springs of their pairs (whose first body it owns), for the
 * state hash (sd_state_hash_records over every slab's) */
sd_status sd_slab_state(const sd_slab *s, void **recs, int *nb, sd_spring **springs, int *ns);
/* A body new to the system (a record made elsewhere, say the dam's pipes built into a copy of
 * the whole world; x its centre's): put in by the slab that owns it by x, left to the others; the pairs are
 * remade at the next step, which hands it to the slabs that hold it as a ghost. */
sd_status sd_slab_add_body(sd_slab *s, const void *rec, double x);
/* 1 when the slab owns the body gid (it moves it, or holds it fixed, and others take its ghosts from it) */
int sd_slab_owns(const sd_slab *s, int gid);
/* the contact points of the last step of the pairs whose first body the slab owns (a body-body
 * pair's first body in key order, sd_spring; a wall pair's body): summed over the slabs, the one
 * world's sd_world_contact_count */
long sd_slab_contacts(const sd_slab *s);
sd_world *sd_slab_world(sd_slab *s);
const sd_slabs_stats *sd_slab_stats(const sd_slab *s);
int sd_slab_owned(const sd_slab *s);
double sd_slab_ghost_width(const sd_slab *s);
void sd_slab_bounds(const sd_slab *s, double *x);

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
/* the bodies slab k owns */
int sd_slabs_owned(const sd_slabs *s, int k);
double sd_slabs_ghost_width(const sd_slabs *s);

#endif
