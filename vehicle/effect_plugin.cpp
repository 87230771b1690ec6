#include "vehicle/effect_plugin.hpp"

#include <dlfcn.h>

#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <sstream>
#include <utility>

#include "host/error.hpp"
#include "vehicle/learned_correction.hpp"

namespace talus::vehicle {

namespace {

bool is_identifier(const char* s) {
  if (!s || !*s) return false;
  for (; *s; ++s) {
    const unsigned char c = static_cast<unsigned char>(*s);
    if (!(std::islower(c) || std::isdigit(c) || c == '_')) return false;
  }
  return true;
}

const char* text_or_empty(const char* s) { return s ? s : ""; }

// the C ABI's sample mirrors SensorSample field for field (vehicle/sensor_channels.hpp, where the
// channels are defined); the compiler holds the two layouts together
#define TALUS_SAME_FIELD(f) \
  static_assert(offsetof(talus_sensor_sample, f) == offsetof(SensorSample, f), "ABI field " #f)
static_assert(sizeof(talus_sensor_sample) == sizeof(SensorSample), "ABI sample size");
TALUS_SAME_FIELD(t);
TALUS_SAME_FIELD(f_lift);
TALUS_SAME_FIELD(f_tilt);
TALUS_SAME_FIELD(f_traction);
TALUS_SAME_FIELD(v_drive);
TALUS_SAME_FIELD(d_lift);
TALUS_SAME_FIELD(d_tilt);
TALUS_SAME_FIELD(boom_deg);
TALUS_SAME_FIELD(bucket_deg);
TALUS_SAME_FIELD(pitch_deg);
TALUS_SAME_FIELD(x_vehicle);
TALUS_SAME_FIELD(bucket_tip_x);
TALUS_SAME_FIELD(bucket_tip_z);
TALUS_SAME_FIELD(power);
TALUS_SAME_FIELD(lift_rate);
TALUS_SAME_FIELD(tilt_rate);
#undef TALUS_SAME_FIELD

talus_sensor_sample to_c(const SensorSample& s) {
  return {s.t,         s.f_lift,    s.f_tilt,       s.f_traction,   s.v_drive, s.d_lift,    s.d_tilt,    s.boom_deg,
          s.bucket_deg, s.pitch_deg, s.x_vehicle, s.bucket_tip_x, s.bucket_tip_z, s.power, s.lift_rate, s.tilt_rate};
}

SensorSample from_c(const talus_sensor_sample& c) {
  SensorSample s;
  s.t = c.t;
  s.f_lift = c.f_lift;
  s.f_tilt = c.f_tilt;
  s.f_traction = c.f_traction;
  s.v_drive = c.v_drive;
  s.d_lift = c.d_lift;
  s.d_tilt = c.d_tilt;
  s.boom_deg = c.boom_deg;
  s.bucket_deg = c.bucket_deg;
  s.pitch_deg = c.pitch_deg;
  s.x_vehicle = c.x_vehicle;
  s.bucket_tip_x = c.bucket_tip_x;
  s.bucket_tip_z = c.bucket_tip_z;
  s.power = c.power;
  s.lift_rate = c.lift_rate;
  s.tilt_rate = c.tilt_rate;
  return s;
}

// what add_wrench's host pointer points at during one on_step call
struct WrenchHost {
  StepControls* controls;
  const WheelLoader* loader;
};

// the C callback: never lets an exception cross into the plug-in
int add_wrench_callback(void* host, const char* body, const double force[3], const double torque[3]) {
  try {
    auto* h = static_cast<WrenchHost*>(host);
    if (!h || !body || !force || !torque) return 1;
    Vec6 w;
    w << force[0], force[1], force[2], torque[0], torque[1], torque[2];
    if (!w.allFinite()) return 1;
    h->controls->add_wrench(h->loader->body(body), w);
    return 0;
  } catch (...) {
    return 1;
  }
}

// an effect whose hooks live in a plug-in
class PluginEffect : public Effect {
 public:
  // its state lives behind the C ABI, which has no way to hand it over yet
  bool savable() const override { return false; }
  PluginEffect(const talus_effect_type& type, std::string file, std::shared_ptr<void> handle)
      : Effect(type.name, text_or_empty(type.summary)), type_(type), file_(std::move(file)), handle_(std::move(handle)) {
    for (int i = 0; i < type.parameter_count; ++i) {
      const talus_effect_parameter& p = type.parameters[i];
      add_parameter({p.name, p.value, p.min, p.max, text_or_empty(p.unit), text_or_empty(p.meaning)});
    }
    self_ = type.create();
    if (!self_) throw Error(file_ + ": effect '" + name() + "': create() returned NULL (out of memory?)");
    // the instance starts from the table's defaults, whatever create() chose
    changed();
  }
  ~PluginEffect() override { type_.destroy(self_); }
  nlohmann::json to_json() const override {
    nlohmann::json j = Effect::to_json();
    j["plugin"] = file_;
    return j;
  }
  void changed() override {
    for (int i = 0; i < static_cast<int>(parameters().size()); ++i) type_.set_parameter(self_, i, value(i));
  }
  void reset(const WheelLoader& loader) override {
    (void)loader;
    if (type_.reset) type_.reset(self_);
  }
  void on_commands(const EffectContext& c, ActuatorCommands& u) override {
    if (!type_.on_commands) return;
    const talus_sensor_sample previous = to_c(c.previous);
    const talus_effect_context context{c.t, c.h, &previous, c.digging ? 1 : 0};
    talus_commands commands{u.drive, u.lift, u.tilt};
    type_.on_commands(self_, &context, &commands);
    if (!std::isfinite(commands.drive) || !std::isfinite(commands.lift) || !std::isfinite(commands.tilt))
      throw Error(file_ + ": effect '" + name() + "' made a command that is not finite; fix the plug-in");
    u = {commands.drive, commands.lift, commands.tilt};
  }
  void on_step(const EffectContext& c, StepControls& controls) override {
    if (!type_.on_step) return;
    const talus_sensor_sample previous = to_c(c.previous);
    const talus_effect_context context{c.t, c.h, &previous, c.digging ? 1 : 0};
    WrenchHost host{&controls, &c.loader};
    talus_step_controls s{controls.lift_force_min(),    controls.lift_force_max(), controls.tilt_force_min(),
                          controls.tilt_force_max(),    controls.drive_power_limit(), &host,
                          &add_wrench_callback};
    type_.on_step(self_, &context, &s);
    if (!(s.lift_force_min <= s.lift_force_max) || !(s.tilt_force_min <= s.tilt_force_max) ||
        !(s.drive_power_limit > 0.0) || !std::isfinite(s.drive_power_limit))
      throw Error(file_ + ": effect '" + name() +
                  "' left an empty force range or a power limit <= 0; fix the plug-in's on_step");
    controls.set_lift_force_range(s.lift_force_min, s.lift_force_max);
    controls.set_tilt_force_range(s.tilt_force_min, s.tilt_force_max);
    controls.set_drive_power_limit(s.drive_power_limit);
  }
  void on_soil(SoilProperties& soil) override {
    if (!type_.on_soil) return;
    talus_soil_properties s{soil.cohesion};
    type_.on_soil(self_, &s);
    if (!std::isfinite(s.cohesion) || s.cohesion < 0.0)
      throw Error(
          file_ + ": effect '" + name() +
          "' set a soil cohesion that is negative or not finite; fix the plug-in's on_soil");
    soil.cohesion = s.cohesion;
  }
  // an effect with on_soil alone shows only where there are particles
  bool soil_only() const override {
    return type_.on_soil && !type_.on_commands && !type_.on_step && !type_.on_sensors;
  }
  void on_sensors(const EffectContext& c, SensorSample& sample) override {
    if (!type_.on_sensors) return;
    const talus_sensor_sample previous = to_c(c.previous);
    const talus_effect_context context{c.t, c.h, &previous, c.digging ? 1 : 0};
    talus_sensor_sample s = to_c(sample);
    type_.on_sensors(self_, &context, &s);
    sample = from_c(s);
  }

 private:
  const talus_effect_type& type_;
  std::string file_;
  std::shared_ptr<void> handle_;  // keeps the library loaded while the effect lives
  void* self_ = nullptr;
};

// "a=1,b=2" -> pairs; InputError naming the specification
std::vector<std::pair<std::string, std::string>> parse_settings(const std::string& spec, const std::string& list) {
  std::vector<std::pair<std::string, std::string>> settings;
  if (list.empty()) return settings;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size())
      throw InputError("--effect '" + spec + "': '" + item + "' is not key=value; write NAME:key=value,key=value");
    settings.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  if (list.back() == ',') throw InputError("--effect '" + spec + "': ends with ','; remove it");
  return settings;
}

}  // namespace

std::shared_ptr<EffectPlugin> EffectPlugin::from_info(const talus_effect_plugin_info* info, const std::string& file,
                                                      std::shared_ptr<void> handle) {
  const std::string fix = "; rebuild the plug-in against this talus's vehicle/effect_abi.h (docs/effects.md)";
  if (!info) throw InputError(file + ": " + TALUS_EFFECT_ENTRY + "() returned NULL" + fix);
  if (info->abi_version != TALUS_EFFECT_ABI_VERSION) {
    throw InputError(file + ": effect plug-in ABI version " + std::to_string(info->abi_version) +
                     ", but this talus speaks version " + std::to_string(TALUS_EFFECT_ABI_VERSION) + fix);
  }
  if (!info->name || info->effect_count < 0 || (info->effect_count > 0 && !info->effects))
    throw InputError(file + ": the plug-in description lacks its name or its effects" + fix);
  for (int i = 0; i < info->effect_count; ++i) {
    const talus_effect_type& t = info->effects[i];
    const std::string where = file + ": effect " + std::to_string(i);
    if (!is_identifier(t.name)) throw InputError(where + ": its name is missing or not [a-z0-9_]+; fix the plug-in");
    const std::string named = file + ": effect '" + t.name + "'";
    if (!t.create || !t.destroy) throw InputError(named + ": create and destroy must be given; fix the plug-in");
    if (t.parameter_count < 0 || (t.parameter_count > 0 && (!t.parameters || !t.set_parameter)))
      throw InputError(named + ": has parameters but no parameter table or set_parameter; fix the plug-in");
    for (int k = 0; k < t.parameter_count; ++k) {
      const talus_effect_parameter& p = t.parameters[k];
      if (!is_identifier(p.name)) throw InputError(named + ": parameter " + std::to_string(k) + " has no valid name");
      if (!(p.min <= p.value && p.value <= p.max))
        throw InputError(named + ": parameter '" + p.name + "' has its default outside [min, max]; fix the plug-in");
    }
    for (int k = 0; k < i; ++k)
      if (std::string(info->effects[k].name) == t.name) throw InputError(named + ": named twice in the plug-in");
  }
  std::shared_ptr<EffectPlugin> plugin(new EffectPlugin());
  plugin->file_ = file;
  plugin->name_ = info->name;
  plugin->info_ = info;
  plugin->handle_ = std::move(handle);
  return plugin;
}

std::shared_ptr<EffectPlugin> EffectPlugin::load(const std::string& file) {
  // a bare name would make dlopen search the library path: a path names this file only
  const std::string path = file.find('/') == std::string::npos ? "./" + file : file;
  void* raw = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!raw) {
    const char* why = dlerror();
    throw InputError(file + ": cannot load the effect plug-in (" + text_or_empty(why) +
                     "); give the path of a shared library built as examples/effect_plugin is");
  }
  std::shared_ptr<void> handle(raw, [](void* h) { dlclose(h); });
  dlerror();
  void* symbol = dlsym(raw, TALUS_EFFECT_ENTRY);
  if (!symbol) {
    throw InputError(file + ": not an effect plug-in: it exports no function " + std::string(TALUS_EFFECT_ENTRY) +
                     " (declare it extern \"C\" in C++; docs/effects.md)");
  }
  talus_effect_entry_fn entry = nullptr;
  static_assert(sizeof(entry) == sizeof(symbol), "function and object pointers differ in size");
  std::memcpy(&entry, &symbol, sizeof(entry));
  return from_info(entry(), file, std::move(handle));
}

std::vector<std::string> EffectPlugin::effect_names() const {
  std::vector<std::string> names;
  for (int i = 0; i < info_->effect_count; ++i) names.emplace_back(info_->effects[i].name);
  return names;
}

bool EffectPlugin::has(const std::string& effect) const {
  for (const auto& n : effect_names())
    if (n == effect) return true;
  return false;
}

std::unique_ptr<Effect> EffectPlugin::make(const std::string& effect) const {
  for (int i = 0; i < info_->effect_count; ++i) {
    if (effect == info_->effects[i].name) return std::make_unique<PluginEffect>(info_->effects[i], file_, handle_);
  }
  throw InputError(file_ + ": the plug-in has no effect '" + effect + "'");
}

EffectPlugins load_effect_plugins(const std::vector<std::string>& files) {
  EffectPlugins plugins;
  std::vector<std::string> builtins = builtin_effect_names();
  for (const auto& l : learned_effect_names()) builtins.push_back(l);
  for (const auto& file : files) {
    auto plugin = EffectPlugin::load(file);
    for (const auto& name : plugin->effect_names()) {
      for (const auto& b : builtins)
        if (b == name) throw InputError(file + ": effect '" + name + "' is a built-in effect's name; rename it");
      for (const auto& earlier : plugins)
        if (earlier->has(name))
          throw InputError(file + ": effect '" + name + "' is also in " + earlier->file() + "; rename one of them");
    }
    plugins.push_back(std::move(plugin));
  }
  return plugins;
}

std::unique_ptr<Effect> make_effect(const std::string& spec, const EffectPlugins& plugins) {
  const size_t colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  if (name.empty()) throw InputError("--effect '" + spec + "': no effect name; write NAME or NAME:key=value,...");
  const auto settings = parse_settings(spec, colon == std::string::npos ? "" : spec.substr(colon + 1));
  std::unique_ptr<Effect> effect;
  for (const auto& b : builtin_effect_names())
    if (b == name) effect = make_builtin_effect(name);
  for (const auto& l : learned_effect_names())
    if (l == name) effect = make_learned_effect(name);
  for (const auto& p : plugins)
    if (!effect && p->has(name)) effect = p->make(name);
  if (!effect && name == "soil_cohesion") effect = make_builtin_effect(name);  // its "not yet"
  if (!effect) {
    std::string list;
    for (const auto& b : builtin_effect_names()) list += (list.empty() ? "" : ", ") + b;
    for (const auto& l : learned_effect_names()) list += ", " + l;
    for (const auto& p : plugins)
      for (const auto& n : p->effect_names()) list += ", " + n + " (" + p->file() + ")";
    throw InputError("--effect '" + spec + "': no effect named '" + name + "'; known effects: " + list +
                     "; load others with --effect-plugin FILE");
  }
  // options first (a channel fixes the unit and range of a bias), then numbers
  for (int pass = 0; pass < 2; ++pass) {
    for (const auto& [key, text] : settings) {
      bool is_option = false;
      for (const auto& o : effect->options()) is_option = is_option || o.name == key;
      if (is_option == (pass == 0)) effect->set_text(key, text);
    }
  }
  return effect;
}

std::unique_ptr<LoadedEffects> load_effects(const std::vector<std::string>& specs,
                                            const std::vector<std::string>& plugin_files,
                                            const Scenario& scenario, const std::string& option) {
  auto e = std::make_unique<LoadedEffects>();
  e->plugins = load_effect_plugins(plugin_files);
  for (const auto& spec : specs) e->set.add(make_effect(spec, e->plugins));
  // an effect on the particles needs particles
  for (size_t i = 0; i < e->set.size(); ++i) {
    if (!scenario.pile && e->set[i].soil_only())
      throw InputError(option + " " + e->set[i].name() +
                       ": acts on the soil's particles, and scenario '" + scenario.name +
                       "' has none; use it with a pile scenario (fb35, hd27, rd21)");
  }
  return e;
}

}  // namespace talus::vehicle
