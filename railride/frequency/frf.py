"""Frequency responses and modes of the passive vehicle, as studies with result objects.

`frequency_responses` computes the steady-state response of the carbody to rails moving as
z(t) = 1 m x sin(2 pi f t) on a log-spaced grid of frequencies, for in-phase rails (z_L = z_R:
bounce and pitch) and anti-phase rails (z_L = -z_R: roll), every wheelset seeing the pattern
delayed by its distance behind the leading one divided by the speed
(`railride.model.vehicle.Vehicle.frequency_response`). It returns an `FrfResult`: the responses, their
table and peaks (`railride.analysis.spectra.frf_frame`, `frf_peaks`) and the `Modes` of the vehicle.

`modes` gives the `Modes` alone: the modes of `Vehicle.modes` (nine, ten where the carbody
bends), by undamped frequency.

The vehicle is named as the command line names it: a preset name, a parameters file (TOML, see
`VehicleParams.load`) or the `VehicleParams` themselves; the documents record which.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from railride.errors import InputError
from railride import limits, validation
from railride.analysis.spectra import FRF_MAGNITUDES, FRF_PATTERNS, frf_frame, frf_peaks
from railride.output.files import FRF_FILES
from railride.defaults import DEFAULT_SPEED
from railride.model.modes import Modes as Modes, checked_modes, modes as modes  # the modes as frf's, too
from railride.model.params import VehicleParams, resolve_argument, vehicle_record
from railride.model.track import frequency_speed
from railride.plots import PNG_DPI, FigureOptions

SCHEMA = "railride.frf/1"
#: the ``rails`` of `frequency_responses`: one rail pattern, or both
RAILS = (*FRF_PATTERNS, "both")
#: the files `FrfResult.save` writes, in this order
FILES = FRF_FILES

#: the highest fmax a frequency response takes [Hz]
FMAX_LIMIT = 1e4


@dataclass(frozen=True, eq=False)
class FrfResult:
    """The carbody frequency responses of `frequency_responses`: ``responses`` per rail pattern
    (the complex Datasets of `Vehicle.frequency_response` over ``frequency`` [Hz], per metre of
    rail amplitude) at ``speed`` [m/s], the log grid they were computed on (``fmin``, ``fmax``
    [Hz], ``points``), the vehicle ``params`` (with its load) and where they came from
    (``source``: a preset name, a parameters file, or None for values not equal to a preset),
    its ``modes`` and ``vehicle``, the record of its name, load and values
    (`railride.model.params.vehicle_record`; None: made from ``params`` and ``source``).

    The result protocol: `to_dict` (the ``railride.frf/1`` document), `to_pandas` (the table of
    magnitudes and phases, frf.csv), `plot` (magnitudes against frequency with the modes
    marked), `save` (frf.csv, frf.json, frf.png, modes.csv); `peaks` the peak of each response.
    """

    params: VehicleParams
    source: str | Path | None
    speed: float
    frequency: np.ndarray
    responses: dict[str, xr.Dataset]
    modes: Modes
    fmin: float
    fmax: float
    points: int
    vehicle: dict | None = None

    @property
    def patterns(self) -> tuple[str, ...]:
        return tuple(self.responses)

    @property
    def vehicle_name(self) -> str:
        """The preset name or the parameters file, as the figure's title gives the vehicle."""
        name = "custom parameters" if self.source is None else str(self.source)
        load = self.record()["load"]
        return name if load == 1.0 else f"{name} at load {load:g}"

    def record(self) -> dict:
        """The vehicle's record: name, load and values (`railride.model.params.vehicle_record`)."""
        return vehicle_record(self.params, self.source) if self.vehicle is None else self.vehicle

    def to_pandas(self):
        """One row per rail pattern and frequency: magnitudes and phases of the carbody
        responses (`railride.analysis.spectra.frf_frame`)."""
        return frf_frame(self.responses)

    def peaks(self) -> dict:
        """Per pattern and magnitude column, the largest magnitude on the grid and its frequency
        (None where the pattern does not excite the response; `railride.analysis.spectra.frf_peaks`)."""
        return frf_peaks(self.to_pandas())

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import frf_contents

        return frf_contents(self)

    def to_dict(self) -> dict:
        """The ``railride.frf/1`` document (docs/cli.md): the vehicle, the settings, the grid,
        the magnitudes per pattern, the peaks and the modes."""
        from railride._version import __version__, versions
        from railride.model.plausible import notes

        frame = frf_frame(self.responses)
        vehicle: dict[str, object]
        if isinstance(self.source, str):
            vehicle = {"vehicle_preset": self.source}
        elif self.source is not None:
            vehicle = {"vehicle_params_file": str(self.source)}
        else:
            vehicle = {"vehicle_params": self.params.to_dict()}
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            **vehicle,
            "vehicle": self.record(),
            "settings": {
                "speed_m_s": self.speed,
                "rails": list(self.patterns),
                "fmin_hz": self.fmin,
                "fmax_hz": self.fmax,
                "points": self.points,
            },
            "frequency_hz": [float(f) for f in self.frequency],
            "responses": {
                p: {c: [float(v) for v in frame.loc[frame["pattern"] == p, c]] for c in FRF_MAGNITUDES}
                for p in self.patterns
            },
            "peaks": frf_peaks(frame),
            "modes": self.modes.to_list(),
            # the vehicle's values outside the typical ranges, as the command line warns of them
            **({"warnings": warned} if (warned := notes(self.params)) else {}),
        }

    def title(self) -> str:
        """The title of the figure: the speed, the vehicle and the suspension."""
        return (
            f"Carbody frequency responses per metre of rail amplitude - V = {self.speed:g} m/s, "
            f"vehicle {self.vehicle_name}, passive suspension"
        )

    def plot(self, ax=None):
        """Magnitudes and phases against frequency, two panels per response, with the modes
        marked (`railride.plots.frf.plot_frf`); ``ax`` None for a new figure, or eight Axes (per
        response its magnitude, then its phase). Returns the figure."""
        from railride.plots.frf import plot_frf

        return plot_frf(self.to_pandas(), self.modes.to_pandas(), ax=ax, title=self.title())

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
        """frf.csv, frf.json, frf.png and modes.csv into ``folder``, all or nothing (other files
        stay); the figure in each of ``figure_formats`` (png, pdf, svg), PNG at ``dpi``.
        Returns the paths."""
        from railride.output.files import write_frf_outputs

        figures = FigureOptions(figure_formats, dpi)
        frame, modes = self.to_pandas(), self.modes.to_list()
        return write_frf_outputs(frame, modes, folder, self.to_dict(), title=self.title(), figures=figures)


def frequency_responses(
    vehicle=None,
    *,
    params=None,
    load: float = 1.0,
    speed: float | None = None,
    rails: str = "both",
    fmin: float = 0.1,
    fmax: float = 30.0,
    points: int = 400,
) -> FrfResult:
    """The carbody frequency responses of the passive ``vehicle`` (``params`` is an alias:
    `VehicleParams`, a preset name or the path of a parameters file; default "paper"), with the
    load factor ``load`` on its carbody (`VehicleParams.loaded`), at ``speed`` [m/s] (default
    the scenarios' default speed), for ``rails`` "in-phase", "anti-phase" or "both", on
    ``points`` (>= 2) frequencies log-spaced from ``fmin`` to ``fmax`` [Hz] (both exactly on the
    grid). Returns an `FrfResult` with the vehicle's modes."""
    from railride.model.vehicle import Vehicle

    speed = DEFAULT_SPEED if speed is None else frequency_speed(speed)
    validation.choice("rails", rails, RAILS)
    fmin = validation.number("fmin", fmin, "positive", "Hz")
    fmax = validation.number("fmax", fmax, "positive", "Hz")
    if not fmax > fmin:
        raise InputError(f"fmax = {fmax:g} Hz: must be above fmin = {fmin:g} Hz")
    if fmax > FMAX_LIMIT:  # far beyond the model's modes the products overflow to inf and nan
        raise InputError(
            f"fmax = {fmax:g} Hz: at most {FMAX_LIMIT:g} Hz (the vehicle's modes are below 100 Hz, the "
            "rigid-body model means nothing far above them)"
        )
    points = validation.integer("points", points, 2, 10**6, "400 resolve every mode of the vehicle")
    patterns = list(FRF_PATTERNS) if rails == "both" else [rails]
    base, source = resolve_argument(vehicle, params)
    record = vehicle_record(base, source, load)
    vehicle_params = base if record["load"] == 1.0 else base.loaded(record["load"])
    car = Vehicle(vehicle_params)
    # per point and pattern: the DOF responses (9, 10 where the carbody bends), the carbody
    # acceleration, 3 floor points and 8 corner values (complex), and as much again while the
    # Dataset and its table are built
    limits.check(
        8 * points * (1 + len(patterns) * 2 * (car.n_dof + 12) * 2),  # an int: points may have 400 digits
        f"the frequency responses on {points} points",
        "use fewer points (400 resolve every mode of the vehicle)",
    )
    frequency = np.geomspace(fmin, fmax, points)
    frequency[0], frequency[-1] = fmin, fmax  # exactly, without rounding
    responses = {p: car.frequency_response(frequency, speed, p) for p in patterns}
    found = checked_modes(car, record)
    return FrfResult(vehicle_params, source, speed, frequency, responses, found, fmin, fmax, points, record)
