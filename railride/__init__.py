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
    rr.design()                                       # which law: tuned on some tracks, judged on others
    rr.run_sweep(rr.sweep.grid(["passive", "pid"], speed=[20, 40, 60]))  # every combination
    rr.frequency_responses(params)                    # carbody FRFs, their peaks, the modes
    rr.modes(params)                                  # the passive vehicle's modes
    rr.linear_model(params, rr.Suspension.named("pid", damper="ideal"))  # (A, B, C, D) of a linear loop
    rr.ride_spectrum("fra4")                          # the ride on a random track in the frequency domain
    rr.write_report(rr.compare(sc), "ride.html")      # any result as one HTML page
    rr.export_fmu("vehicle.fmu")                      # the vehicle for Simulink, SIMPACK, FMPy (FMI 2.0)
"""

from railride._version import __version__ as __version__

#: typing.TYPE_CHECKING without importing typing: the package's face imports nothing else, so that
#: a Ctrl-C in the command line's first milliseconds lands in its own handling (status 130)
TYPE_CHECKING = False

#: the module that holds each public name. They are imported on first use (PEP 562), so that
#: ``import railride`` and the command line start in a fraction of a second (the engine, xarray
#: and pandas come with the first name that needs them) and Ctrl-C during the command line's
#: start-up is its own to report (status 130), not a traceback in this import.
_HOMES = {
    "Comparison": "studies.comparison",
    "compare": "studies.comparison",
    "GainSet": "secondary.control",
    "FrfResult": "frequency.frf",
    "frequency_responses": "frequency.frf",
    "LinearModel": "frequency.linear",
    "linear_model": "frequency.linear",
    "Modes": "model.modes",
    "modes": "model.modes",
    "RideSpectrum": "frequency.ride_spectrum",
    "ride_spectrum": "frequency.ride_spectrum",
    "VehicleParams": "model.params",
    "ParetoResult": "studies.pareto",
    "pareto": "studies.pareto",
    "RideResult": "run.ride",
    "Result": "results",
    "DamperFault": "secondary.faults",
    "simulate": "run.simulation",
    "StudyResult": "studies.study",
    "study": "studies.study",
    "DesignResult": "studies.design_result",
    "design": "studies.design",
    "SolverSettings": "run.solver",
    "Suspension": "secondary.suspension",
    "SweepResult": "studies.sweep",
    "run_sweep": "studies.sweep",
    "Scenario": "model.track",
    "scenario": "model.track",
    "Objective": "studies.objectives",
    "tune": "studies.tuning",
    "Vehicle": "model.vehicle",
    "dampers": "secondary.dampers",
    "write_report": "output.report",
    "export_fmu": "frequency.fmu",
}


#: where the modules of the flat layout (0.4.0) live now: ``railride.sweep.grid`` still works as an
#: attribute of the package (``import railride.sweep`` does not; the new path does)
_MOVED = {
    "comfort": "analysis.comfort",
    "comparison": "studies.comparison",
    "compiled": "engine.compiled",
    "control": "secondary.control",
    "controllers": "secondary.controllers",
    "discrete": "engine.discrete",
    "executors": "studies.executors",
    "faults": "secondary.faults",
    "files": "output.files",
    "frf": "frequency.frf",
    "kernels": "engine.kernels",
    "labels": "analysis.labels",
    "league": "studies.league",
    "linear": "frequency.linear",
    "metrics": "analysis.metrics",
    "objectives": "studies.objectives",
    "optimise": "studies.optimise",
    "params": "model.params",
    "plausible": "model.plausible",
    "report": "output.report",
    "ride": "run.ride",
    "rig": "run.rig",
    "sensing": "secondary.sensing",
    "simulation": "run.simulation",
    "solver": "run.solver",
    "suspension": "secondary.suspension",
    "sweep": "studies.sweep",
    "sweep_grid": "studies.grid",
    "tables": "output.tables",
    "track": "model.track",
    "tune_result": "studies.tune_result",
    "tuning": "studies.tuning",
    "vehicle": "model.vehicle",
}

if TYPE_CHECKING:
    from railride.secondary import dampers
    from railride.studies.comparison import Comparison, compare
    from railride.secondary.control import GainSet
    from railride.secondary.faults import DamperFault
    from railride.frequency.frf import FrfResult, frequency_responses
    from railride.frequency.fmu import export_fmu
    from railride.frequency.linear import LinearModel, linear_model
    from railride.frequency.ride_spectrum import RideSpectrum, ride_spectrum
    from railride.model.modes import Modes, modes
    from railride.studies.objectives import Objective
    from railride.model.params import VehicleParams
    from railride.studies.pareto import ParetoResult, pareto
    from railride.output.report import write_report
    from railride.run.ride import RideResult
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings
    from railride.studies.study import StudyResult, study
    from railride.studies.design import design
    from railride.studies.design_result import DesignResult
    from railride.secondary.suspension import Suspension
    from railride.studies.sweep import SweepResult, run_sweep
    from railride.model.track import Scenario, scenario
    from railride.studies.tuning import tune
    from railride.model.vehicle import Vehicle


def __getattr__(name: str):
    """A public name (`_HOMES`), imported on first use, or a submodule (``railride.model``, or a
    module by its 0.4.0 name, `_MOVED`)."""
    import importlib

    if name.startswith("_"):
        raise AttributeError(f"module 'railride' has no attribute {name!r}")
    home = _HOMES.get(name)
    if home is None:
        try:
            value = importlib.import_module(f".{_MOVED.get(name, name)}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{_MOVED.get(name, name)}":
                raise
            raise AttributeError(f"module 'railride' has no attribute {name!r}") from None
        if name in _MOVED:
            globals()[name] = value
        return value
    module = importlib.import_module(f".{home}", __name__)
    value = module if name == "dampers" else getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOMES})


__all__ = [
    "Comparison",
    "DamperFault",
    "DesignResult",
    "FrfResult",
    "GainSet",
    "LinearModel",
    "Modes",
    "Objective",
    "ParetoResult",
    "Result",
    "RideResult",
    "RideSpectrum",
    "Scenario",
    "SolverSettings",
    "StudyResult",
    "Suspension",
    "SweepResult",
    "Vehicle",
    "VehicleParams",
    "compare",
    "dampers",
    "design",
    "export_fmu",
    "frequency_responses",
    "linear_model",
    "modes",
    "pareto",
    "ride_spectrum",
    "scenario",
    "run_sweep",
    "simulate",
    "study",
    "tune",
    "write_report",
]
