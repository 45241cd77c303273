/* What the dam holds, for the driver and the tests: the capture's pond depth and an element
 * crossing the dam. (The trap ratio and the flow's measures over a run: run_ctx.h.) */
#ifndef SD_TRAP_H
#define SD_TRAP_H

#include "scenario.h"

/* Capture-phase depth h_D (SPEC §5, eqs 51-53): the highest centre among moving elements
 * within water.probe upstream of the dam face, never below h. Elements lighter than water
 * (floating logs) are left out unless water.h_d_floating is set. */
double sd_trap_capture_depth(const sd_scenario *s, const sd_world *w);
/* Whether an element is crossing the dam's trap plane at x = xt: moving, its centre past xt by
 * less than 2 cm, and moving downstream faster than ~1 mm/s (the capture's settled rule). */
int sd_trap_crossing(const sd_world *w, double xt);

#endif
