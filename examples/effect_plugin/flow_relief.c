/* An example effect plug-in for talus (docs/effects.md, "Plug-ins"): flow_relief, an effect that
 * is not among the built-ins. A relief valve whose cracking pressure falls with flow: above a
 * cylinder speed v0 the lift and tilt cylinders' force limits drop as
 *     F_limit(|v|) = F_limit / (1 + droop (|v| / v0 - 1)+)
 * with |v| the cylinder's extension rate in the previous sample. Its signature: heavy loads at high
 * cylinder speeds saturate lower (the lift force caps and the boom slows while digging hard).
 *
 * Build (CMake target talus_example_effect, a MODULE library):
 *     cmake --build build --target talus_example_effect
 * or by hand, with talus's source folder as include path:
 *     cc -shared -fPIC -I TALUS_SOURCE flow_relief.c -o libflow_relief.so
 * Use:
 *     talus run --scenario flat-lift --effect-plugin build/libtalus_example_effect.so \
 *               --effect flow_relief:speed=0.1,droop=2 --out out/relief */
#include <math.h>
#include <stdlib.h>

#include "vehicle/effect_abi.h"

/* one instance's state: its parameters (the hooks read only these) */
typedef struct flow_relief {
  double speed; /* m/s */
  double droop; /* 1 */
} flow_relief;

/* defaults and ranges: talus checks values against them before set_parameter */
static const talus_effect_parameter kParameters[] = {
    {"speed", 0.1, 0.01, 0.5, "m/s", "cylinder speed above which the relief setting falls"},
    {"droop", 2.0, 0.0, 10.0, "1", "relative fall of the force limit per multiple of speed above it"},
};

static void* create(void) {
  flow_relief* e = (flow_relief*)malloc(sizeof(flow_relief));
  if (!e) return NULL;
  e->speed = kParameters[0].value;
  e->droop = kParameters[1].value;
  return e;
}

static void destroy(void* self) { free(self); }

static void set_parameter(void* self, int index, double value) {
  flow_relief* e = (flow_relief*)self;
  if (index == 0) e->speed = value;
  if (index == 1) e->droop = value;
}

/* the force limits' factor at extension rate v */
static double factor(const flow_relief* e, double v) {
  const double excess = fabs(v) / e->speed - 1.0;
  return 1.0 / (1.0 + e->droop * (excess > 0.0 ? excess : 0.0));
}

static void on_step(void* self, const talus_effect_context* context, talus_step_controls* controls) {
  const flow_relief* e = (const flow_relief*)self;
  const double lift = factor(e, context->previous->lift_rate);
  const double tilt = factor(e, context->previous->tilt_rate);
  controls->lift_force_min *= lift;
  controls->lift_force_max *= lift;
  controls->tilt_force_min *= tilt;
  controls->tilt_force_max *= tilt;
}

static const talus_effect_type kEffects[] = {
    {"flow_relief", "relief pressure falling with flow: lower cylinder force limits at high speed",
     (int)(sizeof(kParameters) / sizeof(kParameters[0])), kParameters, create, destroy,
     set_parameter, NULL /* reset: no state */, NULL /* on_commands */, on_step,
     NULL /* on_sensors */, NULL /* on_soil */},
};

static const talus_effect_plugin_info kInfo = {TALUS_EFFECT_ABI_VERSION, "talus example effects", 1, kEffects};

/* the entry point talus looks up (visible: built without -fvisibility=hidden) */
const talus_effect_plugin_info* talus_effect_plugin_entry(void);
const talus_effect_plugin_info* talus_effect_plugin_entry(void) { return &kInfo; }
