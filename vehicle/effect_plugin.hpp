// Effects from shared libraries (`--effect-plugin lib.so`) through the versioned C interface of
// vehicle/effect_abi.h, and effects by specification "NAME:param=value,param=value" (the CLI's
// --effect). docs/effects.md has the how-to; examples/effect_plugin/ a complete plug-in.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "vehicle/effect.hpp"
#include "vehicle/effect_abi.h"

namespace talus::vehicle {

class EffectPlugin {
 public:
  // dlopen the library and check its entry point; talus::InputError naming the file when it does
  // not load, lacks TALUS_EFFECT_ENTRY, speaks another ABI version or describes its effects badly
  static std::shared_ptr<EffectPlugin> load(const std::string& file);
  // the same checks on a plug-in description already in memory (a statically linked plug-in, a
  // test); `handle` keeps the library loaded as long as the plug-in or its effects live
  static std::shared_ptr<EffectPlugin> from_info(const talus_effect_plugin_info* info, const std::string& file,
                                                 std::shared_ptr<void> handle = nullptr);

  const std::string& file() const { return file_; }
  const std::string& name() const { return name_; }
  std::vector<std::string> effect_names() const;
  bool has(const std::string& effect) const;
  // a new instance with its defaults; talus::InputError when the plug-in has no such effect
  std::unique_ptr<Effect> make(const std::string& effect) const;

 private:
  EffectPlugin() = default;
  std::string file_, name_;
  const talus_effect_plugin_info* info_ = nullptr;
  std::shared_ptr<void> handle_;
};

using EffectPlugins = std::vector<std::shared_ptr<EffectPlugin>>;

// load every file; InputError when a plug-in's effect has the name of a built-in effect or of an
// effect of an earlier plug-in
EffectPlugins load_effect_plugins(const std::vector<std::string>& files);

// an effect from "NAME" or "NAME:key=value,key=value" (options such as channel=f_lift first, then
// numbers): built-in effects first, then the plug-ins' effects. InputError naming the
// specification and the fix for a malformed one, an unknown name or parameter, a value out of range
std::unique_ptr<Effect> make_effect(const std::string& spec, const EffectPlugins& plugins = {});

// a run's model extensions: the plug-ins' libraries stay loaded while their effects live
struct LoadedEffects {
  EffectPlugins plugins;
  EffectSet set;
};
// the effects of `specs` (make_effect's), in their order, with the plug-ins of `plugin_files`, for
// a run of `scenario`: InputError for a bad specification or file, and for an effect on the
// soil's particles in a scenario without a pile, naming `option` (the flag or field that gave the
// specification) and the fix. What talus run --effect and the facade's SimulationOptions::effects
// both go through
std::unique_ptr<LoadedEffects> load_effects(const std::vector<std::string>& specs,
                                            const std::vector<std::string>& plugin_files,
                                            const Scenario& scenario, const std::string& option);

}  // namespace talus::vehicle
