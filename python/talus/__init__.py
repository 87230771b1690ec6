"""talus: a wheel loader digging in granular terrain (docs/python.md).

The simulator is the C++ library's embedding facade (embed/talus.hpp), bound as ``talus._talus``:

>>> import talus
>>> sim = talus.Simulation(scenario="hd27", level="D400")
>>> while not sim.done:
...     sim.step()
>>> sim.loaded_mass                      # kg in the bucket
>>> sim.sensor_log()                     # (samples, 14) array, columns talus.CHANNELS

The Gymnasium environment for bucket filling is ``talus.envs.BucketFillingEnv`` (registered as
``talus/BucketFilling-v0`` when Gymnasium is installed).
"""
import os

from ._talus import (CycleSummary, Error, InputError, SimulationOptions, Targets)
from ._talus import Simulation as _Simulation

__all__ = ["Simulation", "SimulationOptions", "Targets", "CycleSummary", "Error", "InputError",
           "CHANNELS", "UNITS", "DATA_DIR", "check_output_path", "check_output_arguments"]

# the package's own data (machines, scenarios, piles): the installed wheel carries a copy, the
# build tree links the repository's; $TALUS_DATA_DIR still comes first (embed/talus.hpp)
DATA_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")

# SimulationOptions' fields (embed/talus.hpp), as the binding declares them
_OPTION_FIELDS = tuple(name for name in dir(SimulationOptions) if not name.startswith("_"))


def check_output_path(path, option, folder=False):
    """Checks before a long run that `path` (a file, or with `folder` a folder) can be written:
    its folder is created and a probe file written and removed. InputError naming `option` and
    the path otherwise, as the command-line tool checks its outputs (docs/reliability.md)."""
    directory = path if folder else (os.path.dirname(os.path.abspath(path)) or ".")
    probe = os.path.join(directory, f".talus-probe-{os.getpid()}")
    try:
        os.makedirs(directory, exist_ok=True)
        with open(probe, "w"):
            pass
        os.remove(probe)
    except OSError as e:
        raise InputError(f"{option} {path}: cannot write there ({e.strerror}); give a writable path") from None


def check_output_arguments(parser, files=(), folders=()):
    """A script's output options, (option, path) pairs, checked with check_output_path before it
    simulates; a path of None is skipped; a refusal ends the script through parser.error (exit 2)."""
    for pairs, folder in ((files, False), (folders, True)):
        for option, path in pairs:
            if path is None:
                continue
            try:
                check_output_path(path, option, folder=folder)
            except InputError as e:
                parser.error(str(e))


class Simulation(_Simulation):
    """A scenario's run, stepped by the caller (embed/talus.hpp, talus::Simulation).

    ``Simulation(scenario="hd27", level="D400", seed=1, ...)`` takes the fields of
    SimulationOptions as keywords; ``Simulation(options)`` a SimulationOptions. The data folder
    defaults to the package's own.
    """

    def __init__(self, options=None, **kwargs):
        if options is not None:
            if kwargs:
                raise TypeError("talus.Simulation: give a SimulationOptions or keywords, not both")
            if not options.data_dir:
                # a copy with the package's data folder; the caller's options stay as they were
                own = SimulationOptions()
                for name in _OPTION_FIELDS:
                    setattr(own, name, getattr(options, name))
                own.data_dir = DATA_DIR
                options = own
            super().__init__(options)
        else:
            kwargs.setdefault("data_dir", DATA_DIR)
            super().__init__(**kwargs)


# the run contract's channels (SPEC §2.4) and their SI units, the columns of sensor_log()
CHANNELS = tuple(_Simulation.channel_names)
UNITS = tuple(_Simulation.channel_units)

try:  # the environment's registration, when Gymnasium is there and imports
    import gymnasium as _gymnasium
except Exception:  # pragma: no cover - the bindings work without it
    _gymnasium = None
if _gymnasium is not None and "talus/BucketFilling-v0" not in _gymnasium.registry:
    _gymnasium.register(id="talus/BucketFilling-v0", entry_point="talus.envs:BucketFillingEnv")
