/* Fuzz target: sweep file text → sd_sweep_run as a dry run (the sweep read, every case's
 * scenario loaded and checked, the runs and branches listed; nothing run or written). The
 * input sits beside a small fixed base scenario, base.yaml, that sweep files name. */
#include "fuzz_io.h"
#include "sweep.h"

static const char base_yaml[] = "solver: {dt: 1.0e-5, duration: 0.001}\n"
                                "elements:\n"
                                "  - {type: sphere, radius: 0.005, position: [0, 0, 0.1]}\n"
                                "dam: {l_h: 0.05, l_v: 0.04}\n";

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int ready;
    if (!ready) {
        fuzz_file("base.yaml", base_yaml, sizeof base_yaml - 1);
        ready = 1;
    }
    const char *path = fuzz_file("input.yaml", data, size);
    char out[128];
    snprintf(out, sizeof out, "%s/out", fuzz_dir());
    sd_sweep_opts o;
    memset(&o, 0, sizeof o);
    o.dry_run = 1;
    o.parallel = 1;
    volatile sig_atomic_t stop = 0;
    sd_sweep_run(path, out, &o, &stop, fuzz_null(), fuzz_null());
    return 0;
}
