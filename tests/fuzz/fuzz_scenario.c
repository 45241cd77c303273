/* Fuzz target: scenario text → sd_scenario_load → resource estimate → the scene built → two
 * steps. Scenes above a small size (SMALL_BODIES elements, SMALL_BYTES of memory) are loaded
 * and estimated but not built, so that one input takes milliseconds. */
#include "build.h"
#include "fuzz_io.h"
#include "scenario.h"

#define SMALL_BODIES 3000.0
#define SMALL_BYTES (64.0 * 1024 * 1024)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("input.yaml", data, size);
    sd_scenario s;
    if (sd_scenario_load(&s, path, NULL, 0, fuzz_null())) return 0;
    sd_scenario_cost c;
    sd_scenario_estimate(&s, &c);
    const sd_scenario_limits lim = {SMALL_BYTES, 1e12};
    if (c.bodies <= SMALL_BODIES && !sd_scenario_check_cost(&s, &c, &lim, fuzz_null())) {
        s.world.threads = 1;
        sd_world *w;
        if (sd_world_create(&s.world, &w) == SD_OK) {
            sd_build_info info;
            if (sd_build_scene(w, &s, &info, fuzz_null()) == SD_OK && sd_world_check(w) == SD_OK)
                for (int k = 0; k < 2 && sd_world_step(w) == SD_OK; k++) {
                }
            sd_world_destroy(w);
        }
    }
    sd_scenario_free(&s);
    return 0;
}
