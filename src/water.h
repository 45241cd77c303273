/* The water's forces on the moving bodies inside the step, for the flow and capture phases: the
 * external-force hook (sabodem.h sd_external_force_fn) that the driver hands the world while
 * the water is on. */
#ifndef SD_WATER_H
#define SD_WATER_H

#include "fluid.h"
#include "sabodem.h"

/* What the hook needs: the flow's parameters, the capture's pond depth h_D at the dam, whether
 * the capture profile applies, and where: in the pond's region x_from <= x < xd (the trap
 * plane or the dam face; -inf for the whole flume upstream), the flow profile elsewhere; or a
 * uniform stream (U at every depth up to h: a scene's uniform or still water) for every body. */
typedef struct {
    sd_fluid_params fp;
    double h_d, xd, x_from; /* m */
    int capture, uniform;
} sd_water;

/* sd_external_force_fn with ctx an sd_water: the forces on the bodies index[k0 .. k1) (store
 * indices) into out[k - k0]. Safe from several threads at once (it reads ctx only). */
void sd_water_forces(void *ctx, const sd_world *w, const int32_t *index, int k0, int k1, sd_vec3 *out);

#endif
