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
"""

__version__ = "0.4.0"

from . import dampers
from .comparison import Comparison, compare
from .control import GainSet
from .frf import FrfResult, frequency_responses
from .params import VehicleParams
from .pareto import ParetoResult, pareto
from .ride import RideResult
from .faults import DamperFault
from .simulation import simulate
from .study import StudyResult, study
from .solver import SolverSettings
from .suspension import Suspension
from .sweep import SweepResult, run_sweep
from .track import Scenario, scenario
from .objectives import Objective
from .tuning import tune
from .vehicle import Vehicle

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
]
