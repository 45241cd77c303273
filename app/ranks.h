/* The processes of one `mpirun` (Open MPI), for sweeps spread over ranks. Built from
 * app/ranks_mpi.c when CMake finds MPI (SD_MPI), else from app/ranks_single.c: one process. */
#ifndef SD_APP_RANKS_H
#define SD_APP_RANKS_H

typedef struct {
    int rank, size; /* this process and how many (0, 1 without mpirun) */
    int active;     /* 1 when MPI was started (the program was launched by mpirun) */
} app_ranks;

/* Starts MPI only when the program was launched by an MPI launcher (its environment says so),
 * so that a plain `sabodem sweep` never touches MPI. 0, or 2 with a message on stderr. */
int app_ranks_start(app_ranks *r, int *argc, char ***argv);

/* Waits for every rank, and returns the largest of the ranks' codes (the same on every rank). */
int app_ranks_max(const app_ranks *r, int code);

void app_ranks_finish(app_ranks *r);

/* The ranks as the transport of one decomposed run (sd_run_comm over MPI_COMM_WORLD); 0, or -1
 * when MPI was not started (the run is then one process). */
struct sd_run_comm;
int app_ranks_comm(const app_ranks *r, struct sd_run_comm *comm);

#endif
