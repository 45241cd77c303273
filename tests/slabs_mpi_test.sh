#!/bin/bash
# One run over MPI ranks (tests/mpi_slabs.c): mpirun -np 1, 2, 3 and 4 (oversubscribed), each
# rank a slab; every 250 steps the state hash gathered on rank 0 equals one world's.
set -u
bin="$1"
code=0
# (under the sanitizers: Open MPI's own allocations, some from plugins it has unloaded by exit,
# read as leaks, so LeakSanitizer is off for the ranks; test_slabs checks the slab code's own
# memory in one process)
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
for n in 1 2 3 4; do
  if OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_mpi_yield_when_idle=1 \
     OMPI_NUM_THREADS=1 OMP_NUM_THREADS=1 mpirun --oversubscribe -np "$n" "$bin"; then
    echo "ok   mpirun -np $n"
  else
    echo "FAIL mpirun -np $n"
    code=1
  fi
done
exit $code
