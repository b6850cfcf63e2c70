"""Rail profiles, scenarios and the wheelset delays (docs/model.md, Track input).

A profile gives the left and right rail heights z_L(s), z_R(s) [m] and their slopes along the
track. Before s = 0 every profile is 0: the vehicle starts at rest on level track. Wheelset j is at
s_j(t) = V t - (x1 - x_j), so it sees the leading wheelset's input delayed by (x1 - x_j)/V, and its
rail velocity is w' = V dz/ds.

For the compiled stepper the inputs are sampled once per run on a time grid t_k = k Delta,
Delta = m dt (m the largest power of two with Delta <= `RailProfile.table_spacing` / V), for
each wheelset: heights w_k and rail velocities w'_k. Between nodes the stepper interpolates
with cubic Hermite polynomials, which reproduce heights to O(Delta^4) and velocities to
O(Delta^3). Because the nodes fall on step boundaries, every Runge-Kutta step sees a single
smooth cubic and keeps its fourth order; halving dt doubles m and leaves the input unchanged.
A profile that does not start at zero height (a measured profile, or the paper sine with its
taper turned off) is 0 up to s = 0 and rises to its value within the first interval after a
wheelset passes s = 0, as a smooth cubic ramp instead of an infinitely steep step. The paper sine
by default enters through a raised-cosine taper over its first wavelength (`SineTrack`).
"""

from __future__ import annotations

import csv
import dataclasses
import functools
import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from railride.errors import InputError
from railride import limits
from railride.validation import shown
from railride.defaults import DEFAULT_DURATION, DEFAULT_SPEED
from railride.model.profiles import (  # noqa: F401 (the profiles' constants: their home before)
    MAX_RAIL_AMPLITUDE,
    MAX_RAIL_PHASE,
    MAX_RANDOM_LENGTH,
    MAX_SPEED,
    MAX_TABLE_NODES,
    MAX_WAVELENGTH,
    NODES_PER_FEATURE,
    RailProfile,
    _check,
    _within,
)
from railride.model.irregularity import (  # noqa: F401 (the random irregularity: its home before)
    FRA_AV,
    FRA_K,
    FRA_OMEGA_C,
    FRA_OMEGA_S,
    GERMAN_AV,
    GERMAN_OMEGA_C,
    GERMAN_OMEGA_R,
    GERMAN_OMEGA_S,
    RANDOM_NAMES,
    SPECTRA,
    TRACK_CACHE_BYTES,
    is_random,
    RandomTrack,
    _TRACKS,
    _random_track,
    spectrum,
)


@dataclass(frozen=True)
class SineTrack(RailProfile):
    """The paper's sine, entering through a raised-cosine taper of its amplitude:
    z_L = r(s) A sin(2 pi s / lambda), z_R = r(s) A sin(2 pi s / lambda - psi), with
    r(s) = (1 - cos(pi s / L)) / 2 for s < L = taper x lambda and r = 1 beyond.

    The taper is what a vehicle sees running onto a section of periodic track: with psi = 90 deg
    the right rail would otherwise start at -A, a 5 cm step at s = 0 that dominates peak values
    and damper forces. r and r' vanish at s = 0, so heights and slopes are continuous there.
    ``taper`` = 0 keeps the step (ramped over one input-grid interval, see the module notes).
    """

    amplitude: float = 0.05  # m
    wavelength: float = 60.0  # m
    rail_phase_deg: float = 90.0  # deg, psi: right rail lags the left
    taper: float = 1.0  # length of the entry taper, in wavelengths

    def __post_init__(self):
        checks = (
            ("amplitude", "amplitude", "nonnegative", "a finite number >= 0 (m)"),
            ("wavelength", "wavelength", "positive", "a finite number > 0 (m)"),
            ("rail_phase_deg", "rail_phase", "finite", "a finite angle in degrees"),
            ("taper", "taper", "nonnegative", "a finite number >= 0 (wavelengths)"),
        )
        for field_name, name, rule, allowed in checks:
            object.__setattr__(self, field_name, _check(name, getattr(self, field_name), rule, allowed))
        _within("amplitude", self.amplitude, MAX_RAIL_AMPLITUDE, "m", "a rail a metre out of line is no track")
        _within("rail_phase", self.rail_phase_deg, MAX_RAIL_PHASE, "deg", "a phase is an angle of one turn")
        _within(
            "wavelength", self.wavelength, MAX_WAVELENGTH, "m", "a sine 100 km long is a gradient, not a ride input"
        )

    def _evaluate(self, s):
        k = 2 * np.pi / self.wavelength
        psi = np.deg2rad(self.rail_phase_deg)
        A = self.amplitude
        zl, zr = A * np.sin(k * s), A * np.sin(k * s - psi)
        dzl, dzr = A * k * np.cos(k * s), A * k * np.cos(k * s - psi)
        L = self.taper * self.wavelength
        if L > 0:
            inside = s < L
            r = np.where(inside, 0.5 * (1 - np.cos(np.pi * s / L)), 1.0)
            dr = np.where(inside, 0.5 * np.pi / L * np.sin(np.pi * s / L), 0.0)
            zl, zr, dzl, dzr = r * zl, r * zr, r * dzl + dr * zl, r * dzr + dr * zr
        return zl, zr, dzl, dzr

    def table_spacing(self):
        return self.wavelength / NODES_PER_FEATURE

    def describe(self):
        return {
            "profile": "sine",
            "amplitude_m": self.amplitude,
            "wavelength_m": self.wavelength,
            "rail_phase_deg": self.rail_phase_deg,
            "taper_wavelengths": self.taper,
        }


@dataclass(frozen=True)
class CosineBump(RailProfile):
    """One cosine bump (height > 0) or dip (height < 0): z = h/2 (1 - cos(2 pi (s - s0) / L))
    for s0 <= s <= s0 + L, on both rails or on one."""

    height: float = 0.02  # m
    length: float = 10.0  # m
    start: float = 10.0  # m, s0
    rails: str = "both"  # "both", "left" or "right"

    def __post_init__(self):
        object.__setattr__(
            self, "height", _check("height", self.height, "finite", "a finite number (m; < 0 for a dip)")
        )
        _within("height", self.height, MAX_RAIL_AMPLITUDE, "m", "a rail a metre out of line is no track")
        object.__setattr__(self, "length", _check("length", self.length, "positive", "a finite number > 0 (m)"))
        object.__setattr__(self, "start", _check("start", self.start, "nonnegative", "a finite number >= 0 (m)"))
        if self.rails not in ("both", "left", "right"):
            raise InputError(f"rails = {self.rails!r}: allowed 'both', 'left', 'right'")

    def _evaluate(self, s):
        x = (s - self.start) / self.length
        inside = (x >= 0) & (x <= 1)
        z = np.where(inside, 0.5 * self.height * (1 - np.cos(2 * np.pi * x)), 0.0)
        dz = np.where(inside, 0.5 * self.height * 2 * np.pi / self.length * np.sin(2 * np.pi * x), 0.0)
        zero = np.zeros_like(s)
        left = self.rails in ("both", "left")
        right = self.rails in ("both", "right")
        return (z if left else zero, z if right else zero, dz if left else zero, dz if right else zero)

    def table_spacing(self):
        return self.length / NODES_PER_FEATURE

    def describe(self):
        return {
            "profile": "cosine-bump",
            "height_m": self.height,
            "length_m": self.length,
            "start_m": self.start,
            "rails": self.rails,
        }


#: the units a measured profile's columns may give in their header ("s [mm]"): metres per unit
_LENGTH_UNITS = {"": 1.0, "m": 1.0, "mm": 1e-3}
#: a measured profile whose height at s = 0 is further than this from level [m] is warned of
#: (the vehicle starts on level track and meets a step there)
START_STEP_WARNING = 5e-4


@dataclass(frozen=True, eq=False)
class MeasuredTrack(RailProfile):
    """A sampled profile (s, z_L, z_R), interpolated by shape-preserving cubics (PCHIP).

    PCHIP gives continuous heights and slopes without overshoot at steps in the data, so the
    rail velocity V dz/ds stays bounded by the data's own slopes.
    """

    s: np.ndarray
    z_L: np.ndarray
    z_R: np.ndarray
    source: str = "<array>"
    #: a section's start on the file's profile [m] (`section`); None: the profile as read
    start_m: float | None = None
    #: SHA-256 of the profile's values as read (s, z_L, z_R in metres); a section keeps its
    #: profile's, so that gains tuned on a section know the file it came from
    sha256: str = ""
    _interp: tuple = field(default=(), repr=False)

    def __post_init__(self):
        from scipy.interpolate import PchipInterpolator

        s = np.asarray(self.s, dtype=float)
        zl = np.asarray(self.z_L, dtype=float)
        zr = np.asarray(self.z_R, dtype=float)
        src = self.source
        if s.ndim != 1 or s.shape != zl.shape or s.shape != zr.shape:
            raise InputError(f"{src}: s, z_L and z_R must be 1-D columns of equal length")
        if s.size < 2:
            raise InputError(f"{src}: a measured profile needs at least 2 rows, got {s.size}")
        for name, col in (("s", s), ("z_L", zl), ("z_R", zr)):
            bad = np.flatnonzero(~np.isfinite(col))
            if bad.size:
                raise InputError(
                    f"{src}: column {name} has a non-finite value {shown(col[bad[0]])} at data row {bad[0] + 1}"
                )
        steps = np.diff(s)
        if np.any(steps <= 0):
            i = int(np.flatnonzero(steps <= 0)[0])
            raise InputError(
                f"{src}: s must increase strictly; data row {i + 2} has s = {shown(s[i + 1])} after {shown(s[i])}"
            )
        if s[0] > 0:
            raise InputError(
                f"{src}: the profile must start at s <= 0 m (the vehicle starts at s = 0); it starts at {shown(s[0])} m"
            )
        object.__setattr__(self, "s", s)
        object.__setattr__(self, "z_L", zl)
        object.__setattr__(self, "z_R", zr)
        if not self.sha256:
            values = np.ascontiguousarray(np.column_stack([s, zl, zr]))
            object.__setattr__(self, "sha256", hashlib.sha256(values.tobytes()).hexdigest())
        pl, pr = PchipInterpolator(s, zl), PchipInterpolator(s, zr)
        object.__setattr__(self, "_interp", (pl, pr, pl.derivative(), pr.derivative()))

    @classmethod
    def from_csv(cls, path: str | Path) -> "MeasuredTrack":
        """Read a CSV with a header naming the columns s, z_L, z_R (metres; a unit suffix such
        as "s [m]" is allowed, other columns are ignored)."""
        path = Path(path)
        try:
            limits.check_file(path, "track file", limits.MAX_TRACK_FILE_BYTES)
            with path.open(newline="", encoding="utf-8") as fh:
                rows = list(csv.reader(fh))
        except OSError as exc:
            raise InputError(f"cannot read track file {path}: {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise InputError(f"track file {path}: not a UTF-8 text CSV") from None
        # keep file line numbers for the messages; skip blank and comment lines
        numbered = [
            (n, r)
            for n, r in enumerate(rows, start=1)
            if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")
        ]
        if not numbered:
            raise InputError(f"track file {path}: empty; expected a header 's,z_L,z_R' and data rows")
        head = numbered[0][1]
        header = [c.split("[")[0].strip().lower() for c in head]
        units = [c.split("[", 1)[1].split("]")[0].strip() if "[" in c else "" for c in head]
        idx = {}
        for want in ("s", "z_l", "z_r"):
            if want not in header:
                raise InputError(
                    f"track file {path}: no column {want.replace('_l', '_L').replace('_r', '_R')!r} in the header "
                    f"{head!r}; expected columns s [m], z_L [m], z_R [m]"
                )
            idx[want] = header.index(want)
        scale = {}
        for k, j in idx.items():  # recording cars often give millimetres: said in the header, converted
            if units[j] not in _LENGTH_UNITS:
                raise InputError(
                    f"track file {path}: column {head[j].strip()!r} is in {units[j]!r}; allowed units: m or mm "
                    "(none: metres)"
                )
            scale[k] = _LENGTH_UNITS[units[j]]
        data: dict[str, list[float]] = {k: [] for k in idx}
        for lineno, row in numbered[1:]:
            for k, j in idx.items():
                try:
                    data[k].append(float(row[j]))
                except (IndexError, ValueError):
                    cell = row[j] if j < len(row) else "<missing>"
                    raise InputError(
                        f"track file {path}, line {lineno}: column {head[j].strip()!r} = {cell!r} is not a number"
                    ) from None
        s, zl, zr = (scale[k] * np.array(data[k]) for k in ("s", "z_l", "z_r"))
        return cls(s, zl, zr, source=str(path))

    def section(self, start: float, lead_in: float = 20.0) -> "MeasuredTrack":
        """The profile from ``start`` [m] of this one on, as a profile that starts at s = 0 and
        fades in over its first ``lead_in`` metres (raised cosine, as `RandomTrack`), so the
        vehicle enters a stretch of the line from level track. A section of a line is another
        track of the same kind: what `railride.design` holds out of a measured profile."""
        start = _check("start", start, "nonnegative", "a finite number >= 0 (m)")
        if not self.s[0] <= start < self.s[-1]:
            raise InputError(
                f"start = {start:g} m: outside the profile {self.source}, which runs from s = {self.s[0]:g} "
                f"to {self.s[-1]:g} m"
            )
        keep = self.s > start  # and the height at start itself, interpolated
        s = np.concatenate([[0.0], self.s[keep] - start])
        z0 = self._evaluate(np.array([start]))
        zl, zr = np.concatenate([z0[0], self.z_L[keep]]), np.concatenate([z0[1], self.z_R[keep]])
        r = np.where(s < lead_in, 0.5 * (1.0 - np.cos(np.pi * np.clip(s / max(lead_in, 1e-300), 0.0, 1.0))), 1.0)
        return MeasuredTrack(
            s,
            r * zl,
            r * zr,
            source=f"{self.source} from s = {start:g} m",
            start_m=(self.start_m or 0.0) + start,
            sha256=self.sha256,
        )

    def _evaluate(self, s):
        if np.any(s > self.s[-1] + 1e-9):
            raise InputError(
                f"{self.source}: the profile ends at s = {self.s[-1]:g} m but the run "
                f"reaches s = {float(np.max(s)):.1f} m"
            )
        return tuple(f(s) for f in self._interp)

    def end(self):
        return float(self.s[-1])

    def table_spacing(self):
        return float(np.min(np.diff(self.s))) / 2

    def describe(self):
        return {
            "profile": "measured",
            "source": self.source,
            "rows": int(self.s.size),
            "s_end_m": float(self.s[-1]),
            **({"start_m": float(self.start_m)} if self.start_m is not None else {}),
            "profile_sha256": self.sha256,
        }


def _check_speed(value) -> float:
    speed = _check("speed", value, "positive", "a finite number > 0 (m/s)")
    if speed > MAX_SPEED:
        raise InputError(
            f"speed = {speed:.4g} m/s: above the plausible {MAX_SPEED:g} m/s (the rail speed "
            "record is 159.7 m/s; the model's linear suspension means nothing far beyond it)"
        )
    return speed


#: the slowest speed of the frequency-domain results [m/s]: the wheelsets behind the leading one
#: see the rail input their distance / speed later, half an hour at this speed; far slower the
#: delays and the spectra's wavenumbers overflow (1e-308 m/s gave NaN)
MIN_FREQUENCY_SPEED = 0.01


def frequency_speed(value) -> float:
    """A speed [m/s] for `railride.frequency`: within the plausible range of a run, and at least
    `MIN_FREQUENCY_SPEED`; ValueError naming ``speed`` otherwise."""
    speed = _check_speed(value)
    if speed < MIN_FREQUENCY_SPEED:
        raise InputError(
            f"speed = {speed:.4g} m/s: at least {MIN_FREQUENCY_SPEED:g} m/s (slower, the rail input "
            "reaches the rear wheelsets over half an hour after the front)"
        )
    return speed


@dataclass(frozen=True)
class Scenario:
    """A run: a rail profile passed at constant speed for a duration."""

    track: RailProfile = field(default_factory=SineTrack)
    speed: float = DEFAULT_SPEED  # m/s, V (the paper's value)
    duration: float = DEFAULT_DURATION  # s
    name: str = "paper-sine"

    def __post_init__(self):
        object.__setattr__(self, "speed", _check_speed(self.speed))
        object.__setattr__(self, "duration", _check("duration", self.duration, "positive", "a finite number > 0 (s)"))
        if not isinstance(self.track, RailProfile):
            raise InputError(f"track = {self.track!r}: must be a RailProfile")
        needed = self.speed * self.duration
        start = getattr(self.track, "start_m", None)
        if needed > self.track.end() + 1e-9 and start is not None:  # a section: in the file's metres
            raise InputError(
                f"start = {start:g} m: the run covers {needed:.1f} m (speed {self.speed:g} m/s x {self.duration:g} s) "
                f"but the profile runs {self.track.end():g} m from there, to s = {start + self.track.end():g} m; "
                f"give a start of at most {start + self.track.end() - needed:g} m, or shorten the run"
            )
        if needed > self.track.end() + 1e-9:
            raise InputError(
                f"the run covers s = 0 to {needed:.1f} m (speed {self.speed:g} m/s x {self.duration:g} s) "
                f"but the profile ends at s = {self.track.end():g} m: shorten the duration or lower the speed"
            )

    def describe(self) -> dict:
        return {"name": self.name, "speed_m_s": self.speed, "duration_s": self.duration, **self.track.describe()}


SCENARIOS = ("paper-sine", "bump", "file:PATH", "fra1..fra6", "german-low", "german-high", "psd:PATH")


def scenario(
    name: str = "paper-sine",
    *,
    amplitude: float | None = None,
    wavelength: float | None = None,
    rail_phase: float | None = None,
    speed: float | None = None,
    duration: float | None = None,
    seed: int | None = None,
    min_wavelength: float | None = None,
    max_wavelength: float | None = None,
    taper: float | None = None,
    start: float | None = None,
) -> Scenario:
    """A named scenario with optional overrides.

    ``paper-sine``: amplitude [m], wavelength [m], rail_phase [deg] of the sine (defaults 0.05 m,
    60 m, 90 deg) and the length of its entry taper in wavelengths (default 1; 0 for none).
    ``bump``: amplitude is the bump height [m] (negative for a dip, default 0.02 m)
    and wavelength its length [m] (default 10 m), starting at s = 10 m on both rails.
    ``file:PATH``: a measured CSV profile (s, z_L, z_R); with ``start`` [m], its section from
    there on, faded in over 20 m (`MeasuredTrack.section`). ``fra1`` ... ``fra6``, ``german-low``,
    ``german-high``, ``psd:PATH`` (a user's spectrum table, `railride.model.psd_table`): a random
    realisation of that spectrum (`RandomTrack`) with ``seed`` (default
    0) over the wavelength band [min_wavelength, max_wavelength] (default 1 to 100 m). Speed
    defaults to 55.56 m/s and duration to 10 s for every scenario.
    """
    if isinstance(name, Path):  # a measured profile's path
        name = f"file:{name}"
    if not isinstance(name, str):
        raise InputError(f"scenario = {name!r}: must be a scenario name ({', '.join(SCENARIOS)}) or a Path")
    common = {
        "speed": DEFAULT_SPEED if speed is None else speed,
        "duration": DEFAULT_DURATION if duration is None else duration,
    }
    random_only = [
        k
        for k, v in (("seed", seed), ("min_wavelength", min_wavelength), ("max_wavelength", max_wavelength))
        if v is not None
    ]
    if random_only and not is_random(name):
        raise InputError(
            f"{', '.join(random_only)} applies to the random tracks ({', '.join(RANDOM_NAMES)}) only, not to {name}"
        )
    if taper is not None and name != "paper-sine":
        raise InputError(f"taper applies to paper-sine only, not to {name}")
    if start is not None and not name.startswith("file:"):
        raise InputError(f"start = {start!r}: applies to a measured profile (file:PATH) only, not to {name}")
    track: RailProfile
    if name == "paper-sine":
        track = SineTrack(
            amplitude=0.05 if amplitude is None else amplitude,
            wavelength=60.0 if wavelength is None else wavelength,
            rail_phase_deg=90.0 if rail_phase is None else rail_phase,
            taper=1.0 if taper is None else taper,
        )
    elif name == "bump":
        if rail_phase is not None:
            raise InputError("rail_phase applies to paper-sine only, not to the bump scenario")
        track = CosineBump(
            height=0.02 if amplitude is None else amplitude, length=10.0 if wavelength is None else wavelength
        )
    elif is_random(name):
        given = [
            k
            for k, v in (("amplitude", amplitude), ("wavelength", wavelength), ("rail_phase", rail_phase))
            if v is not None
        ]
        if given:
            raise InputError(
                f"{', '.join(given)} cannot be set for a random track ({name}); "
                "use min_wavelength, max_wavelength and seed"
            )
        V = _check_speed(common["speed"])  # before the track, whose length it sets
        T = _check("duration", common["duration"], "positive", "a finite number > 0 (s)")
        if not V * T <= MAX_RANDOM_LENGTH:  # before a length of inf m is made a track
            raise InputError(
                f"duration = {T:g} s: at {V:g} m/s the run covers {V * T:.4g} m of random track, more than "
                f"the {MAX_RANDOM_LENGTH:g} m allowed (ten times the longest railway line); shorten the run"
            )
        # long enough that the realisation does not repeat within the run
        length = max(2000.0, V * T + 100.0)
        if max_wavelength is not None:  # the realisation's length is no option: name the limit it sets
            hi = _check("max_wavelength", max_wavelength, "positive", "a finite number > 0 (m)")
            if hi > length:
                raise InputError(
                    f"max_wavelength = {hi:g} m: must be at most {length:g} m, the length of the random track "
                    f"this run synthesises (the run's {V * T:g} m plus 100 m, and at least 2000 m)"
                )
        track = _random_track(
            name,
            0 if seed is None else seed,
            1.0 if min_wavelength is None else min_wavelength,
            100.0 if max_wavelength is None else max_wavelength,
            length,
        )
    elif name.startswith("file:"):
        given = [
            k
            for k, v in (("amplitude", amplitude), ("wavelength", wavelength), ("rail_phase", rail_phase))
            if v is not None
        ]
        if given:
            raise InputError(f"{', '.join(given)} cannot be set for a measured profile ({name})")
        path = name[len("file:") :]
        if not path:
            raise InputError("scenario 'file:' needs a path, as in file:track.csv")
        track = measured(path)
        if start is not None:
            track = track.section(start)
        else:
            _warn_of_a_start_step(track, name)
    else:
        raise InputError(f"unknown scenario {name!r}; allowed: {', '.join(SCENARIOS)}")
    return Scenario(track=track, name=name, **common)


def input_table_nodes(scenario: Scenario, dt: float, duration: float | None = None) -> tuple[int, float]:
    """(rows, interval [s]) of `wheelset_input_table`'s table, without building it (the size
    checks ask first)."""
    duration = scenario.duration if duration is None else duration
    # m is a power of two, so halving dt doubles m and leaves the grid (and the input) alone
    ratio = scenario.track.table_spacing() / (scenario.speed * dt)
    # (at most 2**52 steps between nodes: a speed near 0 would make the ratio infinite)
    m = 1 << int(math.floor(math.log2(min(ratio, 2.0**52)))) if ratio >= 1 else 1
    interval = m * dt
    return int(math.ceil((duration + dt) / interval)) + 2, interval


def wheelset_input_table(
    scenario: Scenario, lag_distance: np.ndarray, dt: float, duration: float | None = None
) -> tuple[np.ndarray, float]:
    """Rail inputs at the wheelsets on the stepper's time grid.

    Returns ``(table, interval)``: table (n, 16) holds at t_k = k * interval the heights
    w = (z_1L, z_1R, ..., z_4R) [m] in columns 0-7 and their rates w' = V dz/ds [m/s] in
    columns 8-15; interval is a whole number of steps dt. ``lag_distance`` is x1 - x_j [m]
    per wheelset.
    """
    duration = scenario.duration if duration is None else duration
    V = scenario.speed
    n, interval = input_table_nodes(scenario, dt, duration)
    if n > MAX_TABLE_NODES:
        raise InputError(
            f"the rail input table would need {n} nodes ({duration:g} s at one node per "
            f"{interval:.3g} s); at most {MAX_TABLE_NODES} are allowed: shorten the run"
        )
    s = V * (np.arange(n) * interval)[:, None] - np.asarray(lag_distance)[None, :]  # (n, 4)
    zl, zr, dzl, dzr = scenario.track.evaluate(np.minimum(s, scenario.track.end()))
    past_end = s > scenario.track.end()  # margin nodes past a measured end: held flat
    dzl[past_end] = 0.0
    dzr[past_end] = 0.0
    table = np.empty((n, 16))
    table[:, 0:8:2], table[:, 1:8:2] = zl, zr
    table[:, 8:16:2], table[:, 9:16:2] = V * dzl, V * dzr
    return table, interval


def measured(path) -> MeasuredTrack:
    """The measured profile of the CSV at ``path`` (`MeasuredTrack.from_csv`), read once per
    version of the file (its size and modification time), as a spectrum table is."""
    try:
        stat = Path(path).stat()
    except OSError:
        return MeasuredTrack.from_csv(path)  # its own message of the file that is not there
    return _measured(str(path), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=4)  # a long profile holds its rows and their splines: keep a few, not many
def _measured(path: str, mtime_ns: int, size: int) -> MeasuredTrack:
    return MeasuredTrack.from_csv(path)


def _warn_of_a_start_step(track: MeasuredTrack, name: str) -> None:
    """A `PlausibilityWarning` where a whole profile starts off level: the vehicle, at rest on
    level track, meets a step at s = 0 (smoothed over one input interval, docs/model.md), a
    transient no line has. A section (``start``) fades in over 20 m and has none."""
    import warnings

    from railride.validation import PlausibilityWarning, caller_level

    z = [float(rail[0]) for rail in track._evaluate(np.zeros(1))[:2]]  # z_L, z_R at s = 0
    if max(abs(z[0]), abs(z[1])) > START_STEP_WARNING:
        warnings.warn(
            f"{name} starts at z_L = {1e3 * z[0]:.3g} mm, z_R = {1e3 * z[1]:.3g} mm at s = 0, not level: the vehicle "
            "meets a step there, a transient in every response; start 0 (--start 0) fades the profile in over "
            "20 m",
            PlausibilityWarning,
            stacklevel=caller_level(),
        )


def source_sha256(name) -> str | None:
    """The SHA-256 of the values a scenario reads from a file: a spectrum table's (psd:PATH) or
    a measured profile's (file:PATH); None for a scenario of settings alone. A study's run keys
    hold it (`railride.studies.case.Case.key`), so a table resumed after the file changed
    does not reuse rows of the old file."""
    if isinstance(name, Path):
        name = f"file:{name}"
    if not isinstance(name, str):
        return None
    from railride.model import psd_table

    if psd_table.is_table(name):
        return psd_table.table(name).sha256
    if name.startswith("file:") and name != "file:":
        return measured(name[len("file:") :]).sha256
    return None


def table_key(sc: Scenario):
    """``sc`` as a plain value for the caches of its tables (`railride.run.simulation`): equal
    settings give equal keys (a realisation built again, a profile read again, compared by its
    numbers), and a key holds no track, so a kept table does not keep its track alive. None for
    a profile that is not a dataclass of plain values."""
    track = sc.track
    if not dataclasses.is_dataclass(track):
        return None
    parts = []
    for f in dataclasses.fields(track):
        if f.name.startswith("_"):  # what the settings build (splines), not a setting
            continue
        value = getattr(track, f.name)
        if isinstance(value, np.ndarray):
            data = np.ascontiguousarray(value)
            value = (data.shape, data.dtype.str, hashlib.sha1(data.tobytes()).hexdigest())
        parts.append((f.name, value))
    key = (type(track).__qualname__, tuple(parts), sc.name, sc.speed, sc.duration)
    try:
        hash(key)
    except TypeError:
        return None
    return key


def as_scenario(value) -> Scenario:
    """``value`` as a scenario: None (`paper-sine`), a scenario name, or a `Scenario`."""
    if value is None:
        return scenario("paper-sine")
    if isinstance(value, str):
        return scenario(value)
    if isinstance(value, Scenario):
        return value
    raise InputError(f"scenario = {value!r}: must be a Scenario or a scenario name")
