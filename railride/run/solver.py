"""How a run is integrated: the `SolverSettings` value (docs/model.md, Integration), and what
its output rate can resolve (`check_resolution`).

A module of its own, not a part of `railride.run.simulation`: the studies and the command line check
and record these settings without loading the compiled stepper.
"""

from __future__ import annotations

from dataclasses import dataclass

from railride.errors import InputError
from railride import validation
from railride.defaults import DEFAULT_CONTROL_RATE, DEFAULT_DT, DEFAULT_OUTPUT_RATE

#: how `railride.simulate` integrates: "auto" (exact discretisation where the suspension is
#: linear, the passive viscous dampers; RK4 otherwise), "rk4" (always the fixed-step RK4) or
#: "exact" (refused where the suspension is not linear)
METHODS = ("auto", "rk4", "exact")
#: where `railride.simulate` steps a batch: "cpu" (the compiled CPU steppers, on every core),
#: "gpu" (the GPU kernel, `railride.engine.gpu`; an input error where there is none) or "auto"
#: (the GPU where one is usable and a batch would step sooner there, `gpu_pays`; else the CPU)
BACKENDS = ("auto", "cpu", "gpu")
#: what "auto" weighs (`gpu_pays`; docs/gpu.md, "When auto takes the GPU"), measured on one H100
#: beside 16 CPU cores: a GPU thread's time a step while the device is far from full (1,024 SAS
#: closed loops, the special-lean build: so the GPU's time a call hardly grows with its runs), the
#: host's share of a call (tables, transfers, results: a 1,024-run call's 0.50 s less its kernels'
#: 0.29 s) and one CPU thread's sample-steps a second (32,768 SAS closed loops at 4.24e7 on the
#: 16 threads)
GPU_STEP_S = 18.9e-6
GPU_CALL_S = 0.21
CPU_THREAD_RATE = 2.65e6
#: the smallest batch "auto" sends to numba's CUDA simulator, which tests the GPU's path, not its
#: speed (thousands of times a device's time): the test suite's studies stay on the CPU
SIMULATOR_MIN_BATCH = 4096
#: a fixed smallest batch for "auto" instead of `gpu_pays` (benchmarks/bench_design.py sets it)
GPU_MIN_BATCH: int | None = None
#: a random track's shortest wavelength must pass at speed / min_wavelength <= output_rate /
#: RESOLUTION: a component above that shows in the stored histories only as a few samples a cycle
RESOLUTION = 2.5


def _steps(steps: float) -> int | None:
    """``steps`` as a whole number >= 1, or None when it is not one (to a part in a million)."""
    if not steps <= 2**53:  # inf, nan or beyond what a float counts exactly: no whole number
        return None
    whole = int(round(steps))
    return whole if whole >= 1 and abs(whole - steps) <= 1e-6 * steps else None


@dataclass(frozen=True)
class SolverSettings:
    """The fixed step ``dt`` [s] (RK4's; where a run goes by the exact discretisation, only the
    spacing of its rail-input grid), the rate of the stored time histories ``output_rate``
    [Hz], the sample rate of the outer-loop controllers ``control_rate`` [Hz] and the
    integration ``method`` (`METHODS`; default "auto": exact discretisation for the passive
    viscous suspension, one step per output sample, where dt only sets the input grid), and the
    ``backend`` that steps a batch (`BACKENDS`; default "auto": a GPU where one is usable for
    batches that would step sooner there, `gpu_pays`; "gpu" is refused at construction where
    none is, saying whether the extra or the device is missing).

    Checked at construction: each a finite number > 0, and the output interval 1/output_rate
    a whole number of steps (at most one output sample per step). The controller period
    1/control_rate must be a whole number of steps too, but only a closed loop samples it:
    `control_steps` checks it when one runs (a passive run at dt = 4e-4 s keeps the default
    control rate, 2.5 steps per period, without an error). Whether ``dt`` is small enough for
    the vehicle is checked by `railride.run.simulation.simulate`, which knows the vehicle.
    """

    dt: float = DEFAULT_DT
    output_rate: float = DEFAULT_OUTPUT_RATE
    control_rate: float = DEFAULT_CONTROL_RATE
    method: str = "auto"
    backend: str = "auto"

    def __post_init__(self):
        for name, unit in (("dt", "s"), ("output_rate", "Hz"), ("control_rate", "Hz")):
            object.__setattr__(self, name, validation.number(name, getattr(self, name), "positive", unit))
        validation.choice("method", self.method, METHODS)
        validation.choice("backend", self.backend, BACKENDS)
        if self.backend == "gpu":
            missing = gpu_missing()
            if missing is not None:
                raise InputError(
                    f"backend = 'gpu': {missing}; use backend 'cpu', or 'auto' (the GPU where there is one)"
                )
        if self.dt * self.output_rate > 1.0 + 1e-6:
            raise InputError(
                f"dt = {self.dt:g} s is too large for output_rate = {self.output_rate:g} Hz: "
                f"at most one output sample per step; use dt <= {1.0 / self.output_rate:g} s "
                "or a lower output_rate"
            )
        if _steps(1.0 / (self.output_rate * self.dt)) is None:
            raise InputError(
                f"output_rate = {self.output_rate:g} Hz with dt = {self.dt:g} s: the output "
                "interval 1/output_rate must be a whole number of steps (at most one "
                "sample per step)"
            )

    @property
    def output_steps(self) -> int:
        """Steps per output sample."""
        steps = _steps(1.0 / (self.output_rate * self.dt))
        assert steps is not None  # checked at construction
        return steps

    def control_steps(self, duration: float | None = None) -> int:
        """Steps per controller period; a ValueError naming control_rate and dt when the period
        is not a whole number of steps (the check a closed loop needs), or, given the run's
        ``duration`` [s], when the controller would not sample again within it."""
        if duration is not None and self.control_rate * duration < 1.0:
            raise InputError(
                f"control_rate = {self.control_rate:.4g} Hz: the controller would sample once every "
                f"{1.0 / self.control_rate:.4g} s, not once within the run's {duration:.4g} s; use "
                f"control_rate >= {1.0 / duration:.4g} Hz"
            )
        steps = _steps(1.0 / (self.control_rate * self.dt))
        if steps is None:
            raise InputError(
                f"control_rate = {self.control_rate:g} Hz with dt = {self.dt:g} s: the "
                "controller period must be a whole number of steps"
            )
        return steps

    def to_dict(self) -> dict:
        """The settings as a result records them (SI units in the names); the method only when
        it is not "auto", so that records of runs before it existed stay as they were."""
        out: dict = {"dt_s": self.dt, "output_rate_hz": self.output_rate, "control_rate_hz": self.control_rate}
        if self.method != "auto":
            out["method"] = self.method
        return {**out, **self.backend_record()}

    def backend_record(self) -> dict:
        """``{"backend": ...}`` for a result's settings where it is not "auto", else nothing (the
        records of runs before it existed stay as they were). Not part of any run's key: the
        backends' results agree to rounding."""
        return {"backend": self.backend} if self.backend != "auto" else {}

    def backend_for(self, n: int, duration: float | None = None) -> str:
        """ "cpu" or "gpu": where a batch of n samples of ``duration`` [s] each (None: long runs)
        steps under these settings (`BACKENDS`). "auto" with a batch that would step sooner on a
        GPU (`gpu_pays`) and no usable GPU warns once (`railride.errors.BackendWarning`) and takes
        the CPU."""
        if self.backend != "auto":
            return self.backend
        if not auto_takes(n, None if duration is None else duration / self.dt):
            return "cpu"
        missing = gpu_missing()
        if missing is None:
            return "gpu"
        import warnings

        from railride.errors import BackendWarning

        warnings.warn(f"backend auto: {missing}; large batches run on the CPU", BackendWarning, 2)
        return "cpu"

    @classmethod
    def of(cls, solver) -> "SolverSettings":
        """``solver`` itself, or the defaults for None."""
        if solver is None:
            return cls()
        if not isinstance(solver, cls):
            raise InputError(f"solver = {solver!r}: must be a railride.SolverSettings or None (the defaults)")
        return solver


def gpu_pays(n: int, steps: float | None = None, threads: int | None = None) -> bool:
    """Whether a batch of n runs of ``steps`` steps each (None: so many that a call's host share
    does not count) would step sooner on a GPU than on ``threads`` CPU threads (default numba's),
    by the rates measured on one machine (`GPU_STEP_S`, `GPU_CALL_S`, `CPU_THREAD_RATE`). A GPU
    call takes about GPU_CALL_S + steps GPU_STEP_S however few its runs, while they fill less than
    the device (a wave of some 33,000 threads on an H100); the CPU takes n steps / (threads
    CPU_THREAD_RATE). For long runs that is n >= GPU_STEP_S CPU_THREAD_RATE threads, about 50
    runs a CPU thread: 802 on 16 threads. Past one wave both grow with n (on the H100 a
    32,768-run call was 1.7 times as fast as the 16 cores, docs/gpu.md)."""
    if threads is None:
        import numba

        threads = numba.get_num_threads()
    cpu_rate = CPU_THREAD_RATE * max(int(threads), 1)
    if steps is None:
        return n >= GPU_STEP_S * cpu_rate
    return GPU_CALL_S + steps * GPU_STEP_S <= n * steps / cpu_rate


def auto_takes(n: int, steps: float | None) -> bool:
    """Whether "auto" would give a batch of n runs of ``steps`` steps to a GPU, were one usable."""
    if GPU_MIN_BATCH is not None:
        return n >= GPU_MIN_BATCH
    from numba.core import config

    if getattr(config, "ENABLE_CUDASIM", False):
        return n >= SIMULATOR_MIN_BATCH
    return gpu_pays(n, steps)


def gpu_missing() -> str | None:
    """None where the GPU stepper can run; otherwise what is missing (the gpu extra, or a CUDA
    device and driver), in words."""
    from railride.engine.gpu import why_not

    return why_not()


def shortest_wavelength(track) -> tuple[str, float] | None:
    """(field, metres) of the shortest wavelength a profile holds on purpose: the sine's
    wavelength, the bump's length, the random track's min_wavelength; None for a measured
    profile, whose samples are what was measured."""
    for name in ("min_wavelength", "wavelength", "length"):
        lam = getattr(track, name, None)
        if lam is not None:
            return name, float(lam)
    return None


def check_resolution(scenario, output_rate: float) -> None:
    """ValueError when the stored time histories at ``output_rate`` [Hz] cannot resolve the
    shortest wavelength of ``scenario``'s profile (`shortest_wavelength`, `RESOLUTION`): a sine
    or bump shorter than that would be aliased into a slow input that is not on the track. The
    simulation checks every scenario it runs; the studies and the command line ask before their
    first run."""
    found = shortest_wavelength(scenario.track)
    if found is None or not scenario.speed / found[1] > output_rate / RESOLUTION:
        return
    name, lam = found
    shortest = RESOLUTION * scenario.speed / output_rate
    raise InputError(
        f"{name} = {lam:.4g} m at speed {scenario.speed:.4g} m/s passes at "
        f"{scenario.speed / lam:.4g} Hz, more than output_rate {output_rate:.4g} Hz / {RESOLUTION:g} = "
        f"{output_rate / RESOLUTION:.4g} Hz can resolve: the shortest {name} allowed is {shortest:.4g} m; "
        "raise it, lower the speed or raise output_rate"
    )
