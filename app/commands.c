/* The command line's table (commands.h). */
#include "commands.h"

#include <string.h>

#include "core/nearest.h"

static const app_option run_options[] = {
    {"-o", "DIR"}, {"--output", "DIR"}, {"--overwrite", NULL}, {"--progress", "S"}, {"--set", "key=value"}, {"--threads", "N"}, {"--seed", "S"},
    {"--checkpoint-at", "flow_end"}, {"--restart", "CHECKPOINT"}, {"--decompose", NULL}, {"--max-memory", "BYTES"},
    {"--max-steps", "N"}, {"--help", NULL}, {NULL, NULL}};
static const app_option check_options[] = {{"--set", "key=value"}, {"--threads", "N"}, {"--seed", "S"},
                                           {"--png", "OUT.png"}, {"--max-memory", "BYTES"}, {"--max-steps", "N"},
                                           {"--help", NULL},  {NULL, NULL}};
static const app_option sweep_options[] = {{"-o", "DIR"},      {"--output", "DIR"},    {"--parallel", "N"},
                                           {"--dry-run", NULL}, {"--no-branch", NULL}, {"--shard", "U/N"},
                                           {"--collect", NULL}, {"--emit", "slurm"},   {"--max-memory", "BYTES"},
                                           {"--max-steps", "N"}, {"--help", NULL},
                                           {NULL, NULL}};
static const app_option params_options[] = {{"--markdown", NULL}, {"--help", NULL}, {NULL, NULL}};
static const app_option man_options[] = {{"--help", NULL}, {NULL, NULL}};
static const app_option completion_options[] = {{"bash", NULL}, {"--help", NULL}, {NULL, NULL}};

const app_command app_commands[] = {
    {"run",
     "sabodem run FILE [-o DIR] [--overwrite] [--progress S] [--set key=value]... [--threads N] [--seed S]\n"
     "                 [--checkpoint-at flow_end] [--restart CHECKPOINT] [--decompose] [--max-memory BYTES]\n"
     "                 [--max-steps N]",
     "simulate the scenario; outputs go to DIR (default out/<scenario name>)\n"
     "  -o, --output DIR          the output directory (refused if it holds another run's files)\n"
     "  --overwrite               delete another run's files in DIR first\n"
     "  --progress S              in a log (not a terminal), a progress line every S s of wall\n"
     "                            time (default 5; 0: every 2000 steps)\n"
     "  --set key=value           override a scenario key (sabodem params lists them)\n"
     "  --threads N               threads (solver.threads; 0: all cores)\n"
     "  --seed S                  the random seed (solver.seed)\n"
     "  --checkpoint-at flow_end  also write DIR/flow_end.ckpt when the flow reaches the dam\n"
     "  --restart CHECKPOINT      continue from such a checkpoint (the capture phase only; FILE may\n"
     "                            differ from the writer's scenario only in the dam layout and\n"
     "                            capture-phase keys, docs/sweep.md) or from a periodic one\n"
     "                            (output.checkpoint_interval: DIR/checkpoint_<step>.ckpt, the same\n"
     "                            scenario, any phase, the same bits as a run never stopped)\n"
     "  --decompose               the run over slabs along x, one a rank under mpirun -np N (which\n"
     "                            implies it), one in a single process: the same bits and outputs on\n"
     "                            any count of ranks (docs/decomposition.md)\n"
     "  --max-memory BYTES        refuse a scene estimated to need more memory (default 8G;\n"
     "                            suffixes K, M, G, T)\n"
     "  --max-steps N             refuse a run of more time steps (default 1e8)",
     run_options},
    {"check", "sabodem check FILE [--set key=value]... [--threads N] [--seed S] [--png OUT.png]\n"
              "                   [--max-memory BYTES] [--max-steps N]",
     "validate the scenario, estimate its memory, steps and time (in all, and of the packing and\n"
     "flow a sweep's branches share), build its scene without running and describe it: the debris\n"
     "(counts, solid volume, K_w), the dam (axes, clear gaps, l_H/d_max, l_V/d_max)\n"
     "  --png OUT.png  also draw the dam's front view (with the largest boulder and a log to\n"
     "                 scale) and a side view of the initial state (python3-matplotlib)\n"
     "  --max-memory BYTES, --max-steps N   the limits the estimate must keep to (as run)",
     check_options},
    {"sweep",
     "sabodem sweep FILE [-o DIR] [--parallel N] [--dry-run] [--no-branch]\n"
     "                   [--shard U/N | --collect | --emit slurm] [--max-memory BYTES] [--max-steps N]",
     "run a matrix of cases x seeds in parallel (resumable), with CSV and figures. vary takes a\n"
     "key's values (scalars or lists: spheres.counts: [[10, 20], [20, 10]]) or named variants\n"
     "that set several keys (layout: {narrow: {dam.l_h: 0.04, dam.l_v: 0.03}, wide: {...}}).\n"
     "Runs that differ only in keys acting after the flow (the dam layout, capture settings)\n"
     "share one packing + flow; a flow checkpoint is reused on resuming only when the engine\n"
     "and the keys acting before the flow end match it (docs/sweep.md). Under mpirun the\n"
     "ranks share the runs (one at a time each unless --parallel), rank 0 collects.\n"
     "  --parallel N  processes at once (default: the sweep file's, else the cores; 1 per rank\n"
     "                under mpirun)\n"
     "  --dry-run     list the runs and shared flows, what is already done, and the time\n"
     "                estimate (sabodem check's, per run and in all, with branching and N)\n"
     "  --no-branch   every run packs and flows on its own\n"
     "  --shard U/N   run only work unit U, U+N, U+2N, ... (a shared flow and its runs, or a\n"
     "                run); no results.csv (--collect writes it)\n"
     "  --collect     run nothing: results.csv, cases.csv and figures from the finished runs\n"
     "  --emit slurm  write DIR/slurm/: a job array (one task per unit, with its time estimate\n"
     "                in units.txt) and a collect job\n"
     "  --max-memory BYTES, --max-steps N   the limits each run's estimate must keep to (as run)",
     sweep_options},
    {"params", "sabodem params [--markdown]", "list every scenario key with its type, unit, default and range",
     params_options},
    {"man", "sabodem man", "print this manual page (roff; man -l <(sabodem man))", man_options},
    {"completion", "sabodem completion bash",
     "print the bash completion (source <(sabodem completion bash)): commands, options, scenario keys",
     completion_options},
};
const int app_n_commands = (int)(sizeof app_commands / sizeof app_commands[0]);

const app_command *app_command_find(const char *name)
{
    for (int k = 0; k < app_n_commands; k++)
        if (!strcmp(name, app_commands[k].name)) return &app_commands[k];
    return NULL;
}

void app_print_usage(FILE *f)
{
    for (int k = 0; k < app_n_commands; k++)
        fprintf(f, "%s %s\n", k ? "      " : "usage:", app_commands[k].usage);
    fprintf(f, "       sabodem --version\n\n");
    for (int k = 0; k < app_n_commands; k++) {
        const char *h = app_commands[k].help;
        fprintf(f, "%-10s ", app_commands[k].name);
        for (; *h; h++) { /* (the help's lines indented under the name) */
            fputc(*h, f);
            if (*h == '\n') fputs("           ", f);
        }
        fputc('\n', f);
    }
    fprintf(f, "\n"
               "sabodem COMMAND --help shows one command.\n"
               "environment (how the engine runs; the results are the same bits whatever they say):\n"
               "  SD_SIMD=scalar|avx2|avx512|auto   the hand-written kernels' width (auto: the CPU's best,\n"
               "                                    AVX2 on AMD CPUs)\n"
               "  SD_PREFETCH=on|off|auto           the contact pass's prefetch (auto: tried during the run)\n"
               "  OMP_NUM_THREADS                   threads when --threads is not given\n"
               "  SABODEM_SCRIPTS                   where the plotting scripts are, if not beside the program\n");
}

const char *app_did_you_mean(const app_command *cmd, const char *word, char *buf, size_t n)
{
    const char *cand[32];
    size_t nc = 0;
    if (cmd)
        for (const app_option *o = cmd->options; o->name && nc < 32; o++)
            cand[nc++] = o->name;
    else
        for (int k = 0; k < app_n_commands && nc < 32; k++)
            cand[nc++] = app_commands[k].name;
    const char *best = sd_nearest_word(word, cand, nc);
    if (best)
        snprintf(buf, n, " (did you mean '%s'?)", best);
    else
        buf[0] = 0;
    return buf;
}
