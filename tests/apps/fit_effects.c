/* Effects given to `talus diagnose` as candidates by the tests of its scan and fit (issue 17,
 * tests/apps/diagnose_test.cpp), written only here. Each is smooth in its parameters and each
 * parameter acts on its own command, so the data decide every parameter, and a test can hold the
 * fit to the value the data were made with:
 *   drive_drag       the drive command loses k u|u|, k in [0, 0.2] s/m: a range from zero, where
 *                    a true k below 0.0055 (the test draws 0.0025-0.005) fits worse at the scan's
 *                    first centre (0.011) than at zero, and only the points the scan adds towards
 *                    zero come near it (docs/sim2real.md section 3). The law of
 *                    hidden_effects.c's speed_loss, written again on purpose: that file's effects
 *                    are never given to the loop, these are
 *   cylinder_losses  the lift and tilt commands each scaled by (1 - loss): two parameters, fitted
 *                    by BOBYQA to convergence
 *   command_losses   the lift, tilt and drive commands each scaled by (1 - loss): three
 *                    parameters, scanned on a Halton design and fitted */
#include <math.h>
#include <stdlib.h>

#include "vehicle/effect_abi.h"

/* one instance's parameters: k (drive_drag) or the losses of lift, tilt and drive */
typedef struct fit_effect {
  double p[3];
} fit_effect;

static const talus_effect_parameter kDrag[] = {
    {"k", 0.03, 0.0, 0.2, "s/m", "drive speed lost per (m/s)^2 of command"}};
/* a loss up to half the command: beyond it a scenario's cylinders hardly move */
static const talus_effect_parameter kLosses[] = {
    {"lift", 0.1, 0.0, 0.5, "1", "fraction of the lift command lost"},
    {"tilt", 0.1, 0.0, 0.5, "1", "fraction of the tilt command lost"},
    {"drive", 0.1, 0.0, 0.5, "1", "fraction of the drive command lost"}};

static void* create(void) { return calloc(1, sizeof(fit_effect)); }
static void destroy(void* self) { free(self); }
static void set_parameter(void* self, int index, double value) {
  if (index >= 0 && index < 3) ((fit_effect*)self)->p[index] = value;
}

static void drive_drag(void* self, const talus_effect_context* c, talus_commands* u) {
  const fit_effect* e = (const fit_effect*)self;
  (void)c;
  u->drive -= e->p[0] * u->drive * fabs(u->drive);
}

static void cylinder_losses(void* self, const talus_effect_context* c, talus_commands* u) {
  const fit_effect* e = (const fit_effect*)self;
  (void)c;
  u->lift *= 1.0 - e->p[0];
  u->tilt *= 1.0 - e->p[1];
}

static void command_losses(void* self, const talus_effect_context* c, talus_commands* u) {
  const fit_effect* e = (const fit_effect*)self;
  cylinder_losses(self, c, u);
  u->drive *= 1.0 - e->p[2];
}

static const talus_effect_type kEffects[] = {
    {"drive_drag", "drive loss with speed squared (a test's candidate)", 1, kDrag, create, destroy,
     set_parameter, NULL, drive_drag, NULL, NULL, NULL},
    {"cylinder_losses", "lift and tilt commands partly lost (a test's candidate)", 2, kLosses,
     create, destroy, set_parameter, NULL, cylinder_losses, NULL, NULL, NULL},
    {"command_losses", "lift, tilt and drive commands partly lost (a test's candidate)", 3, kLosses,
     create, destroy, set_parameter, NULL, command_losses, NULL, NULL, NULL},
};

static const talus_effect_plugin_info kInfo = {TALUS_EFFECT_ABI_VERSION, "talus fit-test effects",
                                               3, kEffects};

const talus_effect_plugin_info* talus_effect_plugin_entry(void);
const talus_effect_plugin_info* talus_effect_plugin_entry(void) { return &kInfo; }
