/* The man page, from the command table (commands.c) and the scenario's parameter table. */
#include "manpage.h"

#include "commands.h"
#include "core/roff.h"
#include "scenario.h"

static void text_block(FILE *f, const char *text)
{
    fputs(".nf\n", f);
    sd_roff_puts(f, text);
    fputs("\n.fi\n", f);
}

void app_print_man(FILE *f, const char *version)
{
    fputs(".\\\" -*- coding: UTF-8 -*-\n", f); /* (the keys' meanings hold Greek letters) */
    fprintf(f, ".TH SABODEM 1 \"\" \"sabodem %s\" \"User Commands\"\n", version);
    fputs(".SH NAME\nsabodem \\- debris flow with boulders and driftwood against a steel\\-pipe grid check dam "
          "(3\\-D DEM)\n.SH SYNOPSIS\n",
          f);
    for (int k = 0; k < app_n_commands; k++)
        text_block(f, app_commands[k].usage);
    text_block(f, "sabodem COMMAND --help\nsabodem --version");
    fputs(".SH DESCRIPTION\nsabodem simulates a debris flow carrying boulders (spheres) and logs (cylinders) into a "
          "permeable grid\\-type check dam of steel pipes with the 3\\-D Distinct Element Method, and reports the "
          "trap ratio P_V and the force on every pipe. A scenario is a YAML file of the keys below.\n"
          ".SH COMMANDS\n",
          f);
    for (int k = 0; k < app_n_commands; k++) {
        fputs(".TP\n.B ", f);
        sd_roff_puts(f, app_commands[k].name);
        fputc('\n', f);
        text_block(f, app_commands[k].help);
    }
    fputs(".SH SCENARIO KEYS\nEach key goes in a scenario file as a section and a name (solver: {dt: 1.0e\\-5}) or "
          "on the command line as \\-\\-set key=value.\n",
          f);
    sd_scenario_print_params(f, SD_PARAMS_ROFF);
    fputs(".SH EXIT STATUS\n0 done, 1 the run failed, 2 bad input or usage (reported as file:line:col: message, with "
          "no output directory left), 130 interrupted (every output file closed and valid).\n"
          ".SH ENVIRONMENT\n"
          ".TP\n.B SD_SIMD\nscalar, avx2, avx512 or auto: the SIMD kernels (the same results whatever it says)\n"
          ".TP\n.B SD_PREFETCH\non, off or auto: the contact pass's prefetch (the same results)\n"
          ".TP\n.B OMP_NUM_THREADS\nthreads when \\-\\-threads is not given\n"
          ".TP\n.B SABODEM_SCRIPTS\nwhere the plotting scripts are, if not in ../share/sabodem beside the program\n"
          ".SH FILES\nA run writes summary.json, series.csv, VTK files and side views into its output directory.\n"
          ".SH SEE ALSO\nThe project's README.md and docs/ (model, scenario keys, sweeps, the C and Python API).\n",
          f);
}
