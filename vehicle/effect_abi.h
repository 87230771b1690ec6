/* The C interface of effect plug-ins (docs/effects.md, "Plug-ins"): a shared library that adds
 * model extensions to talus without rebuilding it. Plain C, so a plug-in can be written in C, C++
 * or anything that exports a C function; include this header and nothing else from talus.
 *
 * The library exports one function, TALUS_EFFECT_ENTRY, returning a pointer to a static
 * talus_effect_plugin_info whose abi_version is TALUS_EFFECT_ABI_VERSION. talus (dlopen, dlsym)
 * refuses a plug-in whose version differs from its own: the version changes whenever any struct
 * or function type below changes, so a stale plug-in is rejected instead of misread.
 *
 * Each effect type describes its parameters (name, default, range, unit, meaning) and creates
 * instances. talus checks every value against the range before set_parameter, and calls, every
 * step, in this order: on_commands (the operator's target speeds -> what the actuators get),
 * on_step (force limits, the driveline's power limit, extra forces on bodies for this step),
 * on_sensors (what the sensors report); and once before a run with particles, on_soil (the soil's
 * properties). Any hook may be NULL. Hooks must not throw (C++) or
 * keep pointers they are given beyond the call. Units: SI, as the channel contract (SPEC §2.4). */
#ifndef TALUS_EFFECT_ABI_H
#define TALUS_EFFECT_ABI_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TALUS_EFFECT_ABI_VERSION 3u
/* the name of the exported entry point */
#define TALUS_EFFECT_ENTRY "talus_effect_plugin_entry"

/* one sensor sample (vehicle/sensor_channels.hpp SensorSample, the same layout): forces [N],
 * speeds [m/s], strokes [m], angles [deg], positions [m], power [W]; lift_rate and tilt_rate are
 * the cylinders' extension rates [m/s] (not in the CSV contract) */
typedef struct talus_sensor_sample {
  double t;
  double f_lift, f_tilt, f_traction;
  double v_drive;
  double d_lift, d_tilt;
  double boom_deg, bucket_deg, pitch_deg;
  double x_vehicle;
  double bucket_tip_x, bucket_tip_z;
  double power;
  double lift_rate, tilt_rate;
} talus_sensor_sample;

/* the step a hook belongs to: time at its start (on_sensors: the sample's time) [s], timestep [s],
 * the true sensor sample before it (not what earlier effects made the sensors report), and
 * whether t lies in the run's digging phase [dig_start, dig_end) (1, else 0; 0 throughout a run
 * without one; since version 3) */
typedef struct talus_effect_context {
  double t;
  double h;
  const talus_sensor_sample* previous;
  int digging;
} talus_effect_context;

/* target speeds [m/s]: drive (forward positive), lift and tilt cylinders (extension positive) */
typedef struct talus_commands {
  double drive, lift, tilt;
} talus_commands;

/* the limits of this step, as earlier effects left them; a hook changes them in place.
 * Cylinder forces are per cylinder [N] (positive pushes the cylinder longer; each of the two lift
 * cylinders gets the lift range); drive_power_limit [W] must stay > 0. add_wrench adds a force [N]
 * at the body's centre of mass and a torque [N m], world frame, for this step only; bodies by
 * their name in the machine file (data/machines/wa320.json: rear_frame, front_frame, boom, ...,
 * not the bucket, whose wrench the particle coupling owns). It returns 0, or nonzero for an
 * unknown body. */
typedef struct talus_step_controls {
  double lift_force_min, lift_force_max;
  double tilt_force_min, tilt_force_max;
  double drive_power_limit;
  void* host;
  int (*add_wrench)(void* host, const char* body, const double force[3], const double torque[3]);
} talus_step_controls;

/* the soil's properties (vehicle/effect.hpp SoilProperties): what on_soil may change, once before a
 * run with particles; the baseline gravel is dry and cohesionless. cohesion: the bulk tensile
 * strength [Pa], finite and >= 0 */
typedef struct talus_soil_properties {
  double cohesion;
} talus_soil_properties;

typedef struct talus_effect_parameter {
  const char* name;     /* [a-z0-9_]+ */
  double value;         /* the default */
  double min, max;      /* the accepted range, inclusive */
  const char* unit;     /* e.g. "s", "N", "1" */
  const char* meaning;  /* one line */
} talus_effect_parameter;

typedef struct talus_effect_type {
  const char* name;     /* unique among built-in and loaded effects, [a-z0-9_]+ */
  const char* summary;  /* one line: what the effect models */
  int parameter_count;
  const talus_effect_parameter* parameters;
  /* a new instance with the defaults (NULL: out of memory), and its end */
  void* (*create)(void);
  void (*destroy)(void* self);
  /* a value already checked against the parameter's range */
  void (*set_parameter)(void* self, int index, double value);
  /* before a run: forget all state (the machine is at rest) */
  void (*reset)(void* self);
  void (*on_commands)(void* self, const talus_effect_context* context, talus_commands* commands);
  void (*on_step)(void* self, const talus_effect_context* context, talus_step_controls* controls);
  void (*on_sensors)(void* self, const talus_effect_context* context, talus_sensor_sample* sample);
  /* once before a run with particles (since version 2); an effect with this hook alone acts on
   * the soil only, so the diagnosis tries it on pile runs only */
  void (*on_soil)(void* self, talus_soil_properties* soil);
} talus_effect_type;

typedef struct talus_effect_plugin_info {
  uint32_t abi_version;  /* TALUS_EFFECT_ABI_VERSION */
  const char* name;      /* the plug-in, for messages */
  int effect_count;
  const talus_effect_type* effects;
} talus_effect_plugin_info;

/* the entry point every plug-in exports (its address never changes while loaded) */
typedef const talus_effect_plugin_info* (*talus_effect_entry_fn)(void);

#ifdef __cplusplus
}
#endif

#endif /* TALUS_EFFECT_ABI_H */
