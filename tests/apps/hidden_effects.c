/* Effects the sim-to-real loop is never told about (issue 17's blind discovery tests,
 * tests/apps/discovery_test.cpp): written only here, loaded by `talus synth --effect-plugin` to
 * make the "measured" runs and never given to `talus diagnose`, which must find a term for them
 * from the residual alone. Six families, each acting where a real machine's would. leakage:
 * cylinder leakage with pressure, the speed falls by k |F| in the direction of motion on the lift
 * or tilt cylinder (held cylinders do not leak: their valve is closed). dead_band: a valve dead
 * band δ, u → sign(u) max(|u| − δ, 0) on the lift or tilt command. load_delay: a transport delay
 * that grows with load, u(t) → u(t − k |F|) on a cylinder. speed_loss: a drive loss growing with
 * speed, u → u − k u |u| on the drive's target speed. load_gain: a load cell whose gain depends on
 * the load, x → x (1 + k |f_lift|) on f_tilt or f_traction. inertia: a mass k the model lacks,
 * a force −k dv/dt on the frames (since 2026-12-01, for the tractive-force target). dig_loss: the
 * lift gets (1 − k) of its command inside the run's digging phase (pile runs only, the phase
 * features' test). "cylinder" 0 is lift and 1
 * tilt; "channel" 0 is f_tilt and 1 f_traction. */
#include <math.h>
#include <stdlib.h>

#include "vehicle/effect_abi.h"

/* the command history of load_delay: 5 ms steps, longer than any delay drawn (0.5 s) */
#define HISTORY 512

typedef struct hidden {
  double k;        /* the magnitude, in the family's unit */
  double which;    /* cylinder or channel, 0 or 1 */
  int started;     /* the pressure below has a value */
  double pressure; /* the cylinder's force through the oil's compliance [N] */
  int count;       /* load_delay: samples in the history */
  double t[HISTORY], u[HISTORY];
} hidden;

static void* create(void) { return calloc(1, sizeof(hidden)); }
static void destroy(void* self) { free(self); }
static void set_parameter(void* self, int index, double value) {
  hidden* e = (hidden*)self;
  if (index == 0) e->k = value;
  if (index == 1) e->which = value;
}
static void reset(void* self) {
  ((hidden*)self)->count = 0;
  ((hidden*)self)->started = 0;
}

#ifdef TALUS_HIDDEN_ONLY_BROKEN
/* broken: a command that is not a number once k > 0.5, the model of a user's effect whose
 * arithmetic fails in part of its range; the diagnosis must report it and go on (built alone as
 * talus_broken_effect, TALUS_HIDDEN_ONLY_BROKEN) */
static void broken(void* self, const talus_effect_context* c, talus_commands* u) {
  const hidden* e = (const hidden*)self;
  (void)c;
  if (e->k > 0.5) u->lift = NAN;
}

static const talus_effect_parameter kBroken[] = {
    {"k", 0.0, 0.0, 1.0, "1", "above 0.5 the lift command is NaN"}};

static const talus_effect_type kEffects[] = {
    {"broken", "fails above half its range", 1, kBroken, create, destroy, set_parameter, reset,
     broken, NULL, NULL, NULL},
};
static const talus_effect_plugin_info kInfo = {TALUS_EFFECT_ABI_VERSION, "talus broken test effect",
                                               1, kEffects};
#else
/* the lift or tilt command and force of the previous sample */
static double* command_of(const hidden* e, talus_commands* u) {
  return e->which < 0.5 ? &u->lift : &u->tilt;
}
/* the cylinder's force as its pressure carries it: the previous sample's force through a
 * first-order lag of 40 ms (the oil's compliance; a loader boom's hydraulic natural frequency is
 * a few hertz), which also keeps a correction fed by the force from chattering at the step rate */
static double force_of(hidden* e, const talus_effect_context* c) {
  const double f = e->which < 0.5 ? c->previous->f_lift : c->previous->f_tilt;
  e->pressure = e->started ? e->pressure + (1.0 - exp(-c->h / 0.04)) * (f - e->pressure) : f;
  e->started = 1;
  return e->pressure;
}

/* sign(u), linear below 1 mm/s so a held cylinder stays held */
static double ramp_sign(double u) { return u > 1e-3 ? 1.0 : u < -1e-3 ? -1.0 : u / 1e-3; }

static void leakage(void* self, const talus_effect_context* c, talus_commands* u) {
  hidden* e = (hidden*)self;
  double* v = command_of(e, u);
  *v -= e->k * fabs(force_of(e, c)) * ramp_sign(*v);
}

static void dead_band(void* self, const talus_effect_context* c, talus_commands* u) {
  const hidden* e = (const hidden*)self;
  double* v = command_of(e, u);
  const double magnitude = fabs(*v) - e->k;
  (void)c;
  *v = magnitude > 0.0 ? copysign(magnitude, *v) : 0.0;
}

static void load_delay(void* self, const talus_effect_context* c, talus_commands* u) {
  hidden* e = (hidden*)self;
  double* v = command_of(e, u);
  const double when = c->t - e->k * fabs(force_of(e, c));
  int i;
  /* remember this step's command (the oldest dropped when full) */
  if (e->count == HISTORY) {
    for (i = 1; i < HISTORY; ++i) {
      e->t[i - 1] = e->t[i];
      e->u[i - 1] = e->u[i];
    }
    e->count = HISTORY - 1;
  }
  e->t[e->count] = c->t;
  e->u[e->count] = *v;
  ++e->count;
  /* the command at `when`, linear between steps, the first before the first */
  if (when <= e->t[0]) {
    *v = e->u[0];
    return;
  }
  for (i = 1; i < e->count; ++i) {
    if (when <= e->t[i]) {
      const double w = (when - e->t[i - 1]) / (e->t[i] - e->t[i - 1]);
      *v = e->u[i - 1] + w * (e->u[i] - e->u[i - 1]);
      return;
    }
  }
}

static void speed_loss(void* self, const talus_effect_context* c, talus_commands* u) {
  const hidden* e = (const hidden*)self;
  (void)c;
  u->drive -= e->k * u->drive * fabs(u->drive);
}

/* a mass the model lacks (a heavier counterweight, mud on the frames): a force −k dv/dt along
 * the world's x axis, the heading of the straight runs the tests drive, half on each frame; the
 * acceleration from the drive speeds of the last two samples */
static void inertia(void* self, const talus_effect_context* c, talus_step_controls* controls) {
  hidden* e = (hidden*)self;
  const double v = c->previous->v_drive;
  const double a = e->started ? (v - e->pressure) / c->h : 0.0;
  const double force[3] = {-0.5 * e->k * a, 0.0, 0.0};
  const double torque[3] = {0.0, 0.0, 0.0};
  e->pressure = v; /* the previous speed (the struct's spare state) */
  e->started = 1;
  controls->add_wrench(controls->host, "rear_frame", force, torque);
  controls->add_wrench(controls->host, "front_frame", force, torque);
}

/* flow the dig takes from the lift (a priority valve feeding the tilt while the bucket is in the
 * pile): the lift gets (1 − k) of its command inside the run's digging phase, as the context
 * reports it (the scenario's marks, moved with the operator's inputs) */
static void dig_loss(void* self, const talus_effect_context* c, talus_commands* u) {
  const hidden* e = (const hidden*)self;
  if (c->digging) u->lift *= 1.0 - e->k;
}

static void load_gain(void* self, const talus_effect_context* c, talus_sensor_sample* s) {
  const hidden* e = (const hidden*)self;
  const double gain = 1.0 + e->k * fabs(s->f_lift);
  (void)c;
  if (e->which < 0.5) {
    s->f_tilt *= gain;
  } else {
    s->f_traction *= gain;
  }
}

static const talus_effect_parameter kCylinder = {"cylinder", 0.0, 0.0,
                                                 1.0,        "1", "0: lift, 1: tilt"};
static const talus_effect_parameter kLeakage[] = {
    {"k", 1e-7, 0.0, 1e-5, "(m/s)/N", "speed lost per newton of cylinder force"}, kCylinder};
static const talus_effect_parameter kDeadBand[] = {{"k", 0.03, 0.0, 0.1, "m/s", "the dead band"},
                                                   kCylinder};
static const talus_effect_parameter kLoadDelay[] = {
    {"k", 1e-6, 0.0, 1e-5, "s/N", "delay per newton"}, kCylinder};
static const talus_effect_parameter kSpeedLoss[] = {
    {"k", 0.03, 0.0, 0.2, "s/m", "loss per (m/s)^2"}};
static const talus_effect_parameter kInertia[] = {
    {"k", 2000.0, 0.0, 2e4, "kg", "the mass the model lacks"}};
static const talus_effect_parameter kDigLoss[] = {
    {"k", 0.3, 0.0, 0.9, "1", "share of the lift command lost in the dig"}};
static const talus_effect_parameter kLoadGain[] = {
    {"k", 1e-6, 0.0, 1e-5, "1/N", "gain per newton of lift force"},
    {"channel", 0.0, 0.0, 1.0, "1", "0: f_tilt, 1: f_traction"}};

static const talus_effect_type kEffects[] = {
    {"leakage", "leakage with pressure", 2, kLeakage, create, destroy, set_parameter, reset,
     leakage, NULL, NULL, NULL},
    {"dead_band", "valve dead band", 2, kDeadBand, create, destroy, set_parameter, reset, dead_band,
     NULL, NULL, NULL},
    {"load_delay", "delay growing with load", 2, kLoadDelay, create, destroy, set_parameter, reset,
     load_delay, NULL, NULL, NULL},
    {"speed_loss", "drive loss with speed", 1, kSpeedLoss, create, destroy, set_parameter, reset,
     speed_loss, NULL, NULL, NULL},
    {"load_gain", "load-dependent load-cell gain", 2, kLoadGain, create, destroy, set_parameter,
     reset, NULL, NULL, load_gain, NULL},
    {"inertia", "a mass the model lacks", 1, kInertia, create, destroy, set_parameter, reset, NULL,
     inertia, NULL, NULL},
    {"dig_loss", "lift flow lost in the dig", 1, kDigLoss, create, destroy, set_parameter, reset,
     dig_loss, NULL, NULL, NULL},
};

static const talus_effect_plugin_info kInfo = {TALUS_EFFECT_ABI_VERSION,
                                               "talus hidden test effects", 7, kEffects};
#endif

const talus_effect_plugin_info* talus_effect_plugin_entry(void);
const talus_effect_plugin_info* talus_effect_plugin_entry(void) { return &kInfo; }
