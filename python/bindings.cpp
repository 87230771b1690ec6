// talus._talus: the embedding facade (embed/talus.hpp) for Python, with pybind11.
//
// The binding adds no simulation of its own: every call goes to talus::Simulation. What it adds
// is the Python shape of the results: NumPy arrays that own the facade's vectors (moved, not
// copied, into the array's base object), keyword construction, and the library's two error types
// as Python exceptions (talus.InputError is a ValueError, talus.Error a RuntimeError). The GIL is
// released while a step runs, so other Python threads go on meanwhile.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <utility>
#include <vector>

#include "embed/talus.hpp"

namespace py = pybind11;

namespace {

// a reading is the contract's 14 channels, one double each, in channel_names() order: the log's
// vector of readings is then a (samples, 14) array in place
static_assert(sizeof(talus::SensorReading) == 14 * sizeof(double),
              "SensorReading must be 14 packed doubles to be viewed as a NumPy row");

// a NumPy array over `data`, owning the vector it lives in (moved into the array's base object)
template <typename T>
py::array_t<double> owning_array(std::vector<T>&& data, std::vector<py::ssize_t> shape) {
  auto* owner = new std::vector<T>(std::move(data));
  py::capsule base(owner, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<double>(shape, reinterpret_cast<const double*>(owner->data()), base);
}

// a reading as a flat array of its 14 channels
py::array_t<double> reading_array(const talus::SensorReading& r) {
  return owning_array(std::vector<talus::SensorReading>{r}, {14});
}

// the options from Python keywords: each keyword is an attribute of SimulationOptions (an unknown
// one is a TypeError naming it and the known ones)
talus::SimulationOptions options_from(const py::kwargs& kwargs) {
  talus::SimulationOptions options;
  py::object o = py::cast(&options, py::return_value_policy::reference);
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (!py::hasattr(o, name.c_str()) || (!name.empty() && name[0] == '_')) {
      // the known options, read from the class itself
      std::string known;
      for (const auto& attribute : py::reinterpret_steal<py::list>(PyObject_Dir(o.ptr()))) {
        const std::string a = py::str(attribute);
        if (!a.empty() && a[0] != '_') known += (known.empty() ? "" : ", ") + a;
      }
      throw py::type_error("talus.Simulation: unknown option '" + name + "'; the options are " +
                           known + " (help(talus.SimulationOptions))");
    }
    o.attr(name.c_str()) = value;
  }
  return options;
}

}  // namespace

PYBIND11_MODULE(_talus, m) {
  m.doc() = "talus: a wheel loader digging in gravel (the C++ facade, embed/talus.hpp)";

  // the library's errors: InputError (bad options or data files) is a talus.Error, as in C++, and
  // a ValueError; translated before Error, its base. Module-lifetime objects, as pybind11 shows
  static py::exception<talus::Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<talus::InputError> input_error(
      m, "InputError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)));
  py::register_local_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const talus::InputError& e) {
      input_error(e.what());
    } catch (const talus::Error& e) {
      error(e.what());
    }
  });

  py::class_<talus::SimulationOptions>(m, "SimulationOptions",
                                       "what to simulate (embed/talus.hpp, SimulationOptions)")
      .def(py::init<>())
      .def_readwrite(
          "scenario", &talus::SimulationOptions::scenario,
          "a shipped scenario's name (hd27, fb35, rd21, flat-lift, load-carry) or a path")
      .def_readwrite("level", &talus::SimulationOptions::level,
                     "particle level D400, D200, D100, D50, or multiscale G400, G200, G100, G50")
      .def_readwrite("seed", &talus::SimulationOptions::seed, "the pile's random seed")
      .def_readwrite("progress", &talus::SimulationOptions::progress, "progress lines on stderr")
      .def_readwrite("data_dir", &talus::SimulationOptions::data_dir,
                     "folder with machines/, scenarios/, piles/")
      .def_readwrite("pile_cache", &talus::SimulationOptions::pile_cache,
                     "read and save settled piles")
      .def_readwrite("loading_cycle", &talus::SimulationOptions::loading_cycle,
                     "the paper's loading cycle (section 7) instead of the scenario's replay")
      .def_readwrite("cycle_approach", &talus::SimulationOptions::cycle_approach,
                     "distance from the bucket tip to the pile at the cycle's start [m]")
      .def_readwrite("cycle_max_time", &talus::SimulationOptions::cycle_max_time,
                     "the cycle's time limit [s]")
      .def_readwrite("cycle_s", &talus::SimulationOptions::cycle_s,
                     "the force-feedback controller's search parameter, in [0, 1]")
      .def_readwrite("effects", &talus::SimulationOptions::effects,
                     "model extensions as talus run --effect takes them, a list of "
                     "'NAME:key=value,...' (docs/effects.md)")
      .def_readwrite("effect_plugins", &talus::SimulationOptions::effect_plugins,
                     "shared libraries with more effects, as talus run --effect-plugin");

  py::class_<talus::Targets>(m, "Targets", "target speeds [m/s]: drive, lift and tilt strokes")
      .def(py::init([](double drive, double lift, double tilt) {
             return talus::Targets{drive, lift, tilt};
           }),
           py::arg("drive") = 0.0, py::arg("lift") = 0.0, py::arg("tilt") = 0.0)
      .def_readwrite("drive", &talus::Targets::drive)
      .def_readwrite("lift", &talus::Targets::lift)
      .def_readwrite("tilt", &talus::Targets::tilt)
      .def("__repr__", [](const talus::Targets& t) {
        return "Targets(drive=" + std::to_string(t.drive) + ", lift=" + std::to_string(t.lift) +
               ", tilt=" + std::to_string(t.tilt) + ")";
      });

  py::class_<talus::CycleSummary>(m, "CycleSummary", "the paper's measures of a loading cycle")
      .def_readonly("loaded_mass", &talus::CycleSummary::loaded_mass, "M [kg]")
      .def_readonly("cycle_time", &talus::CycleSummary::cycle_time, "T [s]")
      .def_readonly("work", &talus::CycleSummary::work, "W [J]")
      .def_readonly("completed", &talus::CycleSummary::completed)
      .def_readonly("broke_out", &talus::CycleSummary::broke_out)
      .def_readonly("fill_start", &talus::CycleSummary::fill_start, "[s], -1 before")
      .def_readonly("fill_end", &talus::CycleSummary::fill_end, "[s], -1 before")
      .def_property_readonly(
          "productivity",
          [](const talus::CycleSummary& c) {
            return c.cycle_time > 0.0 ? c.loaded_mass / c.cycle_time : 0.0;
          },
          "M/T [kg/s]");

  py::class_<talus::Simulation>(m, "Simulation", R"(a scenario's run, stepped by the caller

Simulation(scenario="hd27", level="D400", seed=1, ...) or Simulation(options): builds and settles
the scenario's pile (or runs the machine alone) and starts at time 0. Keywords are the fields of
SimulationOptions. Errors: talus.InputError (ValueError) for bad options or data, talus.Error
(RuntimeError) for a failing simulation.)")
      .def(py::init<const talus::SimulationOptions&>(), py::arg("options"),
           py::call_guard<py::gil_scoped_release>())
      .def(py::init([](const py::kwargs& kwargs) {
        const talus::SimulationOptions options = options_from(kwargs);
        py::gil_scoped_release release;
        return std::make_unique<talus::Simulation>(options);
      }))
      // stepping
      .def("step", py::overload_cast<>(&talus::Simulation::step),
           py::call_guard<py::gil_scoped_release>(),
           "one step with the scenario's (or the loading cycle's) own targets")
      .def("step", py::overload_cast<const talus::Targets&>(&talus::Simulation::step),
           py::arg("targets"), py::call_guard<py::gil_scoped_release>(),
           "one step with the caller's targets")
      .def(
          "step",
          [](talus::Simulation& s, double drive, double lift, double tilt) {
            py::gil_scoped_release release;
            s.step(talus::Targets{drive, lift, tilt});
          },
          py::kw_only(), py::arg("drive"), py::arg("lift"), py::arg("tilt"),
          "one step with the caller's target speeds [m/s]")
      .def("scenario_targets", &talus::Simulation::scenario_targets)
      .def("top_speeds", &talus::Simulation::top_speeds)
      // time
      .def_property_readonly("time", &talus::Simulation::time, "[s]")
      .def_property_readonly("timestep", &talus::Simulation::timestep, "[s]")
      .def_property_readonly("duration", &talus::Simulation::duration, "[s]")
      .def_property_readonly("done", &talus::Simulation::done)
      // the loading cycle
      .def_property_readonly("cycle_phase", &talus::Simulation::cycle_phase,
                             "approach, fill, hold, retreat, done; empty for a replay")
      .def("cycle_summary", &talus::Simulation::cycle_summary)
      // readings
      .def(
          "sensors", [](const talus::Simulation& s) { return reading_array(s.sensors()); },
          "the 14 channels now, as a float64 array in channel_names() order")
      .def("channels", &talus::Simulation::channels, "the channels now, name -> value")
      .def(
          "sensor_log",
          [](const talus::Simulation& s) {
            std::vector<talus::SensorReading> log = s.sensor_log();
            const auto n = static_cast<py::ssize_t>(log.size());
            return owning_array(std::move(log), {n, 14});
          },
          "the 100 Hz log since the start, a (samples, 14) float64 array")
      .def_property_readonly_static("channel_names",
                                    [](py::object) { return talus::Simulation::channel_names(); })
      .def_property_readonly_static("channel_units",
                                    [](py::object) { return talus::Simulation::channel_units(); })
      .def_property_readonly("loaded_mass", &talus::Simulation::loaded_mass, "[kg]")
      .def_property_readonly("work", &talus::Simulation::work, "[J] since the start")
      .def_property_readonly("pile_from_cache", &talus::Simulation::pile_from_cache)
      // particles
      .def_property_readonly("has_particles", &talus::Simulation::has_particles)
      .def_property_readonly("particle_count", &talus::Simulation::particle_count)
      .def(
          "particles",
          [](const talus::Simulation& s) {
            talus::ParticleState p = s.particles();
            const auto n = static_cast<py::ssize_t>(p.size());
            py::dict d;
            d["position"] = owning_array(std::move(p.position), {n, 3});
            d["velocity"] = owning_array(std::move(p.velocity), {n, 3});
            d["angular_velocity"] = owning_array(std::move(p.angular_velocity), {n, 3});
            d["radius"] = owning_array(std::move(p.radius), {n});
            return d;
          },
          "the particles now: position, velocity, angular_velocity (N, 3) and radius (N,) [SI]")
      .def_property_readonly(
          "soil_mass",
          [](const talus::Simulation& s) {
            const talus::SoilMass m = s.soil_mass();
            py::dict d;
            d["solid"] = m.solid;
            d["pool"] = m.pool;
            d["particles"] = m.particles;
            d["total"] = m.total();
            return d;
          },
          "the soil's mass by where it is [kg]: solid and pool (type G's voxels and excavated "
          "soil), particles, and their total, constant over a run to round-off")
      // saved states (docs/embedding.md "Saved states")
      .def(
          "state",
          [](const talus::Simulation& s) {
            std::string bytes;
            {
              py::gil_scoped_release release;
              bytes = s.state();
            }
            return py::bytes(bytes);
          },
          "the whole state between two steps as bytes: restore it with set_state to continue "
          "bit for bit from here (a rewind point)")
      .def(
          "set_state",
          [](talus::Simulation& s, const py::bytes& state) {
            std::string bytes = state;
            py::gil_scoped_release release;
            s.set_state(bytes);
          },
          py::arg("state"),
          "restores bytes from state() into a simulation made with the same options")
      .def("save_state", &talus::Simulation::save_state, py::arg("path"),
           py::call_guard<py::gil_scoped_release>(), "writes state() to a file, atomically")
      .def("restore_state", &talus::Simulation::restore_state, py::arg("path"),
           py::call_guard<py::gil_scoped_release>(), "restores a file save_state wrote")
      // names
      .def_property_readonly("scenario_name", &talus::Simulation::scenario_name)
      .def_property_readonly("level", &talus::Simulation::level)
      .def_property_readonly("device", &talus::Simulation::device);
}
