"""Random track irregularity from standard spectra (docs/track.md): the FRA classes and the
German high-speed spectra (`spectrum`), a seeded realisation of one (`RandomTrack`), and the store
of realisations that the runs of a study meet again (`_random_track`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from railride.errors import InputError
from railride import validation
from railride._cache import MiB, BytesLRU
from railride.model import psd_table
from railride.model.profiles import RailProfile, _check

#: FRA track classes (Hamid and Yang 1981; the constants as in Garg and Dukkipati 1984,
#: "Dynamics of Railway Vehicle Systems"): A_v [cm^2 rad/m] per class, k = 0.25,
#: Omega_c = 0.8245 rad/m, Omega_s = 0.4380 rad/m.
FRA_AV = {1: 1.2107, 2: 1.0181, 3: 0.6816, 4: 0.5376, 5: 0.2095, 6: 0.0339}
FRA_K, FRA_OMEGA_C, FRA_OMEGA_S = 0.25, 0.8245, 0.4380
#: German high-speed spectra (ERRI B176 form): A_v [m^2 rad/m] for low and high interference,
#: Omega_c = 0.8246, Omega_r = 0.0206, Omega_s = 0.4380 rad/m.
GERMAN_AV = {"low": 4.032e-7, "high": 1.080e-6}
GERMAN_OMEGA_C, GERMAN_OMEGA_R, GERMAN_OMEGA_S = 0.8246, 0.0206, 0.4380
SPECTRA = tuple([f"fra{c}" for c in FRA_AV] + ["german-low", "german-high"])
#: every random track by name, as messages list them: the standard spectra and a user's table
RANDOM_NAMES = (*SPECTRA, f"{psd_table.PREFIX}PATH")


def is_random(name) -> bool:
    """Whether scenario ``name`` is a random track: a standard spectrum or a user's table
    (psd:PATH, `railride.model.psd_table`)."""
    return isinstance(name, str) and (name in SPECTRA or psd_table.is_table(name))


def spectrum(name: str, wavenumber, component: str = "vertical") -> np.ndarray:
    """One-sided displacement PSD [m^2/(rad/m)] of a standard track spectrum at wavenumbers
    [rad/m] (Omega = 2 pi / wavelength).

    ``component`` "vertical": the vertical profile z_v (mean of the two rails); "cross-level":
    the height difference z_x = z_L - z_R between the rails (z_L = z_v + z_x/2,
    z_R = z_v - z_x/2). Formulas (docs/track.md):

    * FRA class c: S_v = k A_v Omega_c^2 / (Omega^2 (Omega^2 + Omega_c^2)),
      S_x = 4 k A_v Omega_c^2 / ((Omega^2 + Omega_c^2)(Omega^2 + Omega_s^2)), in cm^2/(rad/m),
      converted here to m^2/(rad/m).
    * psd:PATH: a user's table, log-log between its rows (`railride.model.psd_table`); no
      values outside its range.
    * German low/high: S_v = A_v Omega_c^2 / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2)); the
      published cross-level form (A_v / b^2) Omega_c^2 Omega^2 / ((Omega^2 + Omega_r^2)(Omega^2 +
      Omega_c^2)(Omega^2 + Omega_s^2)) is the cross-level angle with b = 0.75 m half the contact
      distance; the height difference is that angle times 2b, so S_x = 4 A_v Omega_c^2 Omega^2 /
      (...), independent of b.
    """
    W = np.asarray(wavenumber, dtype=float)
    if not np.all(np.isfinite(W)) or np.any(W <= 0):
        raise InputError("wavenumber must be finite and > 0 rad/m")
    if component not in ("vertical", "cross-level"):
        raise InputError(f"component = {component!r}: allowed 'vertical', 'cross-level'")
    if psd_table.is_table(name):
        return psd_table.table(name)(W, component)
    W2 = W * W
    if name.startswith("fra") and name[3:].isdigit() and int(name[3:]) in FRA_AV:
        Av, k, Wc2, Ws2 = FRA_AV[int(name[3:])], FRA_K, FRA_OMEGA_C**2, FRA_OMEGA_S**2
        cm2 = (
            k * Av * Wc2 / (W2 * (W2 + Wc2))
            if component == "vertical"
            else 4 * k * Av * Wc2 / ((W2 + Wc2) * (W2 + Ws2))
        )
        return cm2 * 1e-4
    if name in ("german-low", "german-high"):
        Av = GERMAN_AV[name.split("-")[1]]
        Wc2, Wr2, Ws2 = GERMAN_OMEGA_C**2, GERMAN_OMEGA_R**2, GERMAN_OMEGA_S**2
        if component == "vertical":
            return Av * Wc2 / ((W2 + Wr2) * (W2 + Wc2))
        return 4 * Av * Wc2 * W2 / ((W2 + Wr2) * (W2 + Wc2) * (W2 + Ws2))
    raise InputError(f"unknown track spectrum {name!r}; allowed: {', '.join(RANDOM_NAMES)}")


@dataclass(frozen=True, eq=False)
class RandomTrack(RailProfile):
    """A seeded realisation of a standard spectrum: vertical profile and cross-level,
    independent, each a sum of harmonics on a uniform wavenumber grid over the band
    [2 pi / max_wavelength, 2 pi / min_wavelength] with amplitudes sqrt(2 S(Omega_k) dOmega)
    and random phases, synthesised by an inverse FFT on a uniform grid in s and interpolated by
    cubic splines. The realisation is ``length`` long (runs beyond it are refused); it fades in
    over the first ``lead_in`` metres (raised cosine) so the vehicle enters from level track
    smoothly."""

    name: str = "fra4"
    seed: int = 0
    min_wavelength: float = 1.0  # m
    max_wavelength: float = 100.0  # m
    length: float = 2000.0  # m, the realisation's period
    lead_in: float = 20.0  # m
    _interp: tuple = field(default=(), repr=False)
    #: a user's table the realisation was made from (psd:PATH), read once; None for a standard spectrum
    _table: psd_table.PsdTable | None = field(default=None, repr=False)

    def __post_init__(self):
        from scipy.interpolate import CubicSpline

        table = psd_table.table(self.name) if psd_table.is_table(self.name) else None
        object.__setattr__(self, "_table", table)
        if table is None:
            spectrum(self.name, 1.0)  # an unknown name fails here
        # a Python int, never through a float (which rounds seeds past 2**53)
        object.__setattr__(self, "seed", validation.seed("seed", self.seed))
        lo = _check("min_wavelength", self.min_wavelength, "positive", "a finite number > 0 (m)")
        hi = _check("max_wavelength", self.max_wavelength, "positive", "a finite number > 0 (m)")
        if not lo < hi:
            raise InputError(f"wavelength band [{lo:g}, {hi:g}] m: min_wavelength must be below max_wavelength")
        if table is not None and not (table.band()[0] <= lo * (1 + 1e-12) and hi <= table.band()[1] * (1 + 1e-12)):
            short, long = table.band()
            raise InputError(
                f"wavelength band [{lo:g}, {hi:g}] m: beyond the {short:.4g} to {long:.4g} m that the spectrum "
                f"table {self.name} covers; a spectrum is not extrapolated: give min_wavelength and max_wavelength "
                "within it, or extend the table"
            )
        length = _check("length", self.length, "positive", "a finite number > 0 (m)")
        if length < hi:
            raise InputError(f"length = {length:g} m: must be at least max_wavelength = {hi:g} m")
        lead = _check("lead_in", self.lead_in, "nonnegative", "a finite number >= 0 (m)")
        ds = lo / 20.0  # 20 samples on the shortest wavelength
        samples = length / ds  # checked before any int of it: it may be inf
        if not samples <= 2**24:
            raise InputError(
                f"the realisation needs {samples:.4g} samples ({length:.4g} m at {ds:.4g} m), more than "
                f"2**24: shorten it or raise min_wavelength"
            )
        n = int(2 ** math.ceil(math.log2(samples)))
        ds = length / n
        dW = 2 * np.pi / length
        k = np.arange(n // 2 + 1)
        W = k * dW
        band = (W >= 2 * np.pi / hi) & (W <= 2 * np.pi / lo)
        rng = np.random.default_rng(self.seed)
        s = np.arange(n) * ds
        profiles = []
        for component in ("vertical", "cross-level"):
            S = np.zeros_like(W)
            S[band] = table(W[band], component) if table is not None else spectrum(self.name, W[band], component)
            amp = np.sqrt(2 * S * dW)  # one-sided: variance = sum S dW
            phase = rng.uniform(0, 2 * np.pi, W.size)
            # z(s) = sum amp cos(W s + phase) as the real part of an inverse FFT
            profiles.append(np.fft.irfft(amp * np.exp(1j * phase) * (n / 2), n))
        zv, zx = profiles
        taper = np.where(s < lead, 0.5 * (1 - np.cos(np.pi * s / max(lead, 1e-12))), 1.0)
        zl, zr = taper * (zv + zx / 2), taper * (zv - zx / 2)
        # not periodic: a periodic spline would join the full-amplitude end to the faded-in
        # start and ring there; runs stay within the length (scenario() makes it long enough)
        splines = tuple(CubicSpline(s, z) for z in (zl, zr))
        object.__setattr__(self, "_interp", (splines, zv, zx, s))

    def end(self) -> float:
        return float(self._interp[3][-1])

    def _evaluate(self, s):
        from railride.engine.tables import cubic_on_grid

        (sl, sr), *_ = self._interp
        s = np.ascontiguousarray(s, dtype=float).ravel()
        out = np.empty((4, s.size))
        # scipy's values, compiled without the GIL: a study's chunks build tables beside the stepping
        cubic_on_grid(sl.x, sl.c, sr.c, s, out)
        return out[0], out[1], out[2], out[3]

    def splines(self) -> tuple:
        """The left and right rails' cubic splines of the realisation (scipy ``CubicSpline``, on
        the samples of `samples`): what `evaluate` reads, and what an FMU carries
        (`railride.frequency.fmu`)."""
        return self._interp[0]

    def samples(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(s, z_v, z_x) of the realisation before the lead-in taper, for checks."""
        _, zv, zx, s = self._interp
        return s, zv, zx

    def table_spacing(self):
        return self.min_wavelength / 20.0

    def describe(self):
        return {
            "profile": "random",
            "spectrum": self.name,
            "seed": int(self.seed),
            "min_wavelength_m": self.min_wavelength,
            "max_wavelength_m": self.max_wavelength,
            "length_m": self.length,
            "lead_in_m": self.lead_in,
            # a user's table: the values the realisation was made from (not the file as it is now)
            **({"spectrum_sha256": self._table.sha256} if self._table is not None else {}),
        }


#: the random-track realisations kept for the next runs (`_random_track`): 6.8 MB each for the
#: default band over 2000 m, so nine. A study takes its runs realisation by realisation
#: (`railride.studies.sweep.run_cases`), so it needs one or two at a time; a design's tuning
#: rounds read the same six (fra4 and fra5, three seeds: 41 MB) every round, and a store of four
#: built each of them again every round
TRACK_CACHE_BYTES = 64 * MiB


def _track_bytes(track: RandomTrack) -> int:
    splines, *arrays = track._interp
    return sum(sp.x.nbytes + sp.c.nbytes for sp in splines) + sum(a.nbytes for a in arrays)


_TRACKS: BytesLRU[RandomTrack] = BytesLRU("random tracks", TRACK_CACHE_BYTES, _track_bytes)


def _random_track(name, seed, min_wavelength, max_wavelength, length) -> RandomTrack:
    """The `RandomTrack` of these settings, kept while the realisations fit `TRACK_CACHE_BYTES`:
    a study at several speeds (or passive beside a controller) meets the same realisation many
    times, and synthesising it is most of a short run's set-up. A value that cannot be a key is
    checked by RandomTrack."""

    def build() -> RandomTrack:
        return RandomTrack(name, seed=seed, min_wavelength=min_wavelength, max_wavelength=max_wavelength, length=length)

    if isinstance(seed, bool):  # True would hash as seed 1: let the constructor refuse it
        return build()
    # a user's table by its contents too: an edited file is another spectrum
    version = psd_table.table(name).sha256 if psd_table.is_table(name) else None
    return _TRACKS.get((name, version, seed, min_wavelength, max_wavelength, length), build)
