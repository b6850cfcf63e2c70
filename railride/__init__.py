"""railride: vertical ride of a railway vehicle with a semi-active secondary suspension.

The public API, in the order a run needs it::

    import railride as rr
    params = rr.VehicleParams.preset("paper")          # parameters (the paper's appendix)
    vehicle = rr.Vehicle(params)                      # M, C, K, modes, frequency response
    sc = rr.scenario("paper-sine", speed=55.56)        # track and run (docs/model.md, Track input)
    result = rr.simulate(sc, params)                  # time histories (xarray) + metrics
    rr.simulate(sc, params, rr.Suspension.named("sas-attitude-ride"))  # a controlled secondary
    result.metrics()                                  # RMS, peak-to-peak (docs/model.md, Metrics)
    rr.compare(sc)                                    # the paper's comparison, with the bounds
    rr.tune()                                         # every law tuned alike (shipped gains)
    rr.study(["pid"], scenario="fra4", loads=[1, 1.3], faults=["none", "1R-off"])  # over many tracks
    rr.run_sweep(rr.sweep.grid(["passive", "pid"], speed=[20, 40, 60]))  # every combination
    rr.frequency_responses(params)                    # carbody FRFs, their peaks, the modes
    rr.write_report(rr.compare(sc), "ride.html")      # any result as one HTML page
"""

__version__ = "0.4.0"

import sys
import types
from typing import TYPE_CHECKING

#: the module that holds each public name. They are imported on first use (PEP 562), so that
#: ``import railride`` and the command line start in a fraction of a second (the engine, xarray
#: and pandas come with the first name that needs them) and Ctrl-C during the command line's
#: start-up is its own to report (status 130), not a traceback in this import.
_HOMES = {
    "Comparison": "comparison",
    "compare": "comparison",
    "GainSet": "control",
    "FrfResult": "frf",
    "frequency_responses": "frf",
    "VehicleParams": "params",
    "ParetoResult": "pareto",
    "pareto": "pareto",
    "RideResult": "ride",
    "DamperFault": "faults",
    "simulate": "simulation",
    "StudyResult": "study",
    "study": "study",
    "SolverSettings": "solver",
    "Suspension": "suspension",
    "SweepResult": "sweep",
    "run_sweep": "sweep",
    "Scenario": "track",
    "scenario": "track",
    "Objective": "objectives",
    "tune": "tuning",
    "Vehicle": "vehicle",
    "dampers": "dampers",
    "write_report": "report",
}

if TYPE_CHECKING:
    from . import dampers
    from .comparison import Comparison, compare
    from .control import GainSet
    from .faults import DamperFault
    from .frf import FrfResult, frequency_responses
    from .objectives import Objective
    from .params import VehicleParams
    from .pareto import ParetoResult, pareto
    from .report import write_report
    from .ride import RideResult
    from .simulation import simulate
    from .solver import SolverSettings
    from .study import StudyResult, study
    from .suspension import Suspension
    from .sweep import SweepResult, run_sweep
    from .track import Scenario, scenario
    from .tuning import tune
    from .vehicle import Vehicle


def __getattr__(name: str):
    """A public name (`_HOMES`), imported on first use, or a submodule (``railride.sweep``)."""
    import importlib

    if name.startswith("_"):
        raise AttributeError(f"module 'railride' has no attribute {name!r}")
    home = _HOMES.get(name)
    if home is None:
        try:
            return importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module 'railride' has no attribute {name!r}") from None
    module = importlib.import_module(f".{home}", __name__)
    value = module if name == "dampers" else getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOMES})


class _Package(types.ModuleType):
    """The package's module type: importing the submodules ``railride.study`` and
    ``railride.pareto`` must not hide the functions ``study`` and ``pareto`` of the same names
    (the import system sets a submodule as an attribute of its package)."""

    def __setattr__(self, name: str, value) -> None:
        if isinstance(value, types.ModuleType) and name in _HOMES and name != "dampers":
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package

__all__ = [
    "Comparison",
    "DamperFault",
    "FrfResult",
    "GainSet",
    "Objective",
    "ParetoResult",
    "RideResult",
    "Scenario",
    "SolverSettings",
    "StudyResult",
    "Suspension",
    "SweepResult",
    "Vehicle",
    "VehicleParams",
    "compare",
    "dampers",
    "frequency_responses",
    "pareto",
    "scenario",
    "run_sweep",
    "simulate",
    "study",
    "tune",
    "write_report",
]
