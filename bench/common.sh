# Shared by bench/run.sh and bench/compare.sh (sourced): how the codes are pinned, the median of
# a column, and LAMMPS's rates from its log.
# One thread or rank pinned to CPU 0 (a VM's two vCPUs can differ in speed for minutes at a
# time, and a ratio across them would measure that too); two threads one per core, as mpirun
# --bind-to core pins two ranks.
pin="taskset -c 0"
command -v taskset >/dev/null || pin=""
bind="env OMP_PROC_BIND=true OMP_PLACES=cores"
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
# LAMMPS "Loop time of T on P procs for N steps with A atoms" for the dense (3rd) and flow (4th) runs
lammps_rates() {
  awk '/^Loop time of/ {n++; t=$4; s=$9; a=$12; if (n==3) d=a*s/t; if (n==4) f=a*s/t} END {print d, f}' "$1"
}
