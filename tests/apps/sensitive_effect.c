/* An effect whose simulation is chaotic in its parameter (issue 17, the sensitivity spread;
 * tests/apps/diagnose_test.cpp), written only here and given to `talus diagnose` as a candidate.
 *
 * chaotic_bias: the model of a simulation that is chaotic in its parameter, as a D400 dig is in a
 * soil or machine parameter (docs/sim2real.md, "The simulation's sensitivity"): the traction
 * reading gains the bias b, its mean response, smooth in b, plus A s(t; b), a realisation that
 * any change of b's bits replaces by another: s is a sum of K sines of 1 to 6 Hz (a D400 dig's
 * forces decorrelate within about 0.1 s) whose phases come from a hash of b, scaled to unit
 * variance. Given to the loop as a candidate (built as talus_sensitive_effect), its fit
 * leaves a residual of two realisations' difference that no fit can remove, which the
 * sensitivity spread must recognise as the simulation's own */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "vehicle/effect_abi.h"

#define CHAOS_SINES 16
/* A [N]: 1.25 times the default sensor noise of f_traction (2 kN, sim2real/synthetic.cpp), so the
 * difference of two realisations (variance 2 A^2 = 3.1 sigma^2) is beyond noise, yet small beside
 * the offset the loop fits (60-90 kN in the tests) */
#define CHAOS_AMPLITUDE 2.5e3
#define CHAOS_LOW_HZ 1.0
#define CHAOS_HIGH_HZ 6.0
#define CHAOS_TWO_PI 6.283185307179586

typedef struct chaotic {
  double bias;
  double phase[CHAOS_SINES];
} chaotic;

/* splitmix64 (Steele, Lea and Flood 2014): a well-mixed 64-bit hash */
static uint64_t mix(uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

static void* create_chaotic(void) { return calloc(1, sizeof(chaotic)); }
static void destroy_chaotic(void* self) { free(self); }
static void set_chaotic(void* self, int index, double value) {
  chaotic* e = (chaotic*)self;
  uint64_t bits = 0;
  int j;
  if (index != 0) return;
  e->bias = value;
  memcpy(&bits, &value, sizeof bits);
  for (j = 0; j < CHAOS_SINES; ++j) {
    bits = mix(bits);
    e->phase[j] = CHAOS_TWO_PI * (double)(bits >> 11) / 9007199254740992.0; /* 2^53 */
  }
}

static void chaotic_bias(void* self, const talus_effect_context* c, talus_sensor_sample* s) {
  const chaotic* e = (const chaotic*)self;
  double sum = 0.0;
  int j;
  (void)c;
  for (j = 0; j < CHAOS_SINES; ++j) {
    const double hz = CHAOS_LOW_HZ + (CHAOS_HIGH_HZ - CHAOS_LOW_HZ) * (j + 0.5) / CHAOS_SINES;
    sum += sin(CHAOS_TWO_PI * hz * s->t + e->phase[j]);
  }
  /* a sum of K unit sines of independent phases has variance K / 2 */
  s->f_traction += e->bias + CHAOS_AMPLITUDE * sqrt(2.0 / CHAOS_SINES) * sum;
}

static const talus_effect_parameter kChaotic[] = {
    {"bias", 0.0, 0.0, 100e3, "N", "the traction reading's mean offset"}};

static const talus_effect_type kEffects[] = {
    {"chaotic_bias", "a traction offset whose realisation is chaotic in it", 1, kChaotic,
     create_chaotic, destroy_chaotic, set_chaotic, NULL, NULL, NULL, chaotic_bias, NULL},
};
static const talus_effect_plugin_info kInfo = {TALUS_EFFECT_ABI_VERSION,
                                               "talus sensitive test effect", 1, kEffects};

const talus_effect_plugin_info* talus_effect_plugin_entry(void);
const talus_effect_plugin_info* talus_effect_plugin_entry(void) { return &kInfo; }
