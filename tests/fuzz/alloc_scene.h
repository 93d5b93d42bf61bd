/* What the failed-allocation scenarios (alloc_fmi2.c, alloc_fmi3.c) run: the same for both FMI
 * versions. Values are set only where the FMU has the variable (the comb-drive actuator has
 * neither the scene nor solver.method). */
#ifndef CSFH_ALLOC_SCENE_H
#define CSFH_ALLOC_SCENE_H

#include <stddef.h>

#define ALLOC_TOLERANCE 1e-6
#define ALLOC_CS_STEP 2e-3 /* s: the communication step */
#define ALLOC_CS_STEPS 48
#define ALLOC_STATES_AT 0.088 /* s: FMU states taken and restored (auto runs BDF by then) */
#define ALLOC_ME_STEP 1e-5 /* s: the explicit Euler step of model exchange */
#define ALLOC_ME_STEPS 40

/* A falling body that hits the bore and comes to rest on it: contact events and, for auto, the
 * stiff resting contact where it switches to BDF. */
static const struct {
    const char *name;
    double value;
} alloc_scene[] = {
    {"body1.x", 0.0},
    {"body1.y", -0.0199},
    {"contact.cr", 0.2},
};
#define ALLOC_SCENE_SIZE (sizeof(alloc_scene) / sizeof(alloc_scene[0]))

#endif
