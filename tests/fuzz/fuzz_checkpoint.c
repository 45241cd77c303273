/* Fuzz target: checkpoint bytes → sd_checkpoint_read → two steps of the world read; then the
 * run driver's restart check (sd_run_check_restart: the driver's state blob and the scenario
 * fingerprint) against the fixed scenario the seed checkpoints were written with
 * (tests/fuzz/ckpt_scenario.yaml; its path SD_FUZZ_CKPT_SCENARIO comes from the build).
 * A checksum over the payload guards the file, so a mutated input would almost never get past
 * it: the harness writes the true payload length and checksum into the header first (when the
 * input is at least a header long), and the reader's checks behind the checksum are fuzzed. */
#include "core/hash.h"
#include "fuzz_io.h"
#include "run.h"
#include "scenario.h"

#define HEADER 64
#define SMALL_BODIES 3000

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static sd_scenario s;
    static int ready;
    if (!ready) {
        if (sd_scenario_load(&s, SD_FUZZ_CKPT_SCENARIO, NULL, 0, stderr)) abort();
        ready = 1;
    }
    uint8_t *buf = malloc(size ? size : 1);
    if (!buf) return 0;
    if (size) memcpy(buf, data, size);
    if (size >= HEADER) {
        const uint64_t plen = size - HEADER, h = sd_hash(buf + HEADER, plen);
        memcpy(buf + 32, &plen, 8);
        memcpy(buf + 40, &h, 8);
    }
    const char *path = fuzz_file("input.ckpt", buf, size);
    free(buf);
    sd_world *w = NULL;
    void *extra = NULL;
    size_t elen = 0;
    char msg[512];
    if (sd_checkpoint_read(path, &w, &extra, &elen, msg, sizeof msg) == SD_OK) {
        if (sd_world_body_count(w) <= SMALL_BODIES && sd_world_check(w) == SD_OK) {
            sd_world_set_threads(w, 1);
            for (int k = 0; k < 2 && sd_world_step(w) == SD_OK; k++) {
            }
        }
        sd_world_destroy(w);
        free(extra);
        sd_run_check_restart(&s, path, msg, sizeof msg);
    }
    return 0;
}
