"""The first vertical bending mode of a free-free uniform Euler-Bernoulli beam: the carbody's
flexible mode (docs/model.md, Flexible carbody). Plain NumPy.

A uniform beam of length L, bending stiffness EI and mass m (m / L per metre), free at both
ends, bends first in a symmetric mode with two nodes. Its wavenumber beta solves
cos(beta L) cosh(beta L) = 1, the first root beta L = 4.730040745 (Blevins, *Formulas for
Natural Frequency and Mode Shape*, 1979, Table 8-1). With x measured from the beam's centre
(-L/2 <= x <= L/2) the mode is

    phi(x) = [cos(beta x) / cos(beta L/2) + cosh(beta x) / cosh(beta L/2)] / phi_0,
    phi_0 = 1 / cos(beta L/2) + 1 / cosh(beta L/2),

normalised to phi(0) = 1 at the centre, so that its modal coordinate eta is the bending
deflection of the centre in metres (up +: the centre rises against the ends, which move by
phi(+-L/2) = 2 / phi_0 = -1.645 times eta). Unnormalised (the bracket alone) it is the textbook
shape cosh + cos - sigma (sinh + sin) of x' = x + L/2 measured from an end, whose mean square
over the beam is 1: so the modal mass factor is mu = (1/L) int phi^2 dx = 1 / phi_0^2.
"""

from __future__ import annotations

import math

import numpy as np

#: the first root of cos(bL) cosh(bL) = 1 besides 0: the first free-free bending mode
BETA_L = 4.730040744862704
_HALF = BETA_L / 2.0
#: the unnormalised shape at the centre (the bracket of the module's docstring at x = 0)
_PHI_0 = 1.0 / math.cos(_HALF) + 1.0 / math.cosh(_HALF)


def frequency_equation(beta_l):
    """cos(bL) cosh(bL) - 1: zero at the wavenumbers of the free-free beam's bending modes."""
    beta_l = np.asarray(beta_l, dtype=float)
    return np.cos(beta_l) * np.cosh(beta_l) - 1.0


def mode_shape(x, length: float):
    """phi(x) of the first bending mode of a free-free beam of ``length`` L [m] at ``x`` [m]
    from its centre (-L/2 <= x <= L/2, an array or a number), normalised to phi(0) = 1; a
    ValueError for x beyond the ends."""
    x = np.asarray(x, dtype=float)
    if not length > 0.0:
        raise ValueError(f"length = {length!r}: must be a finite number > 0 (m)")
    if np.any(np.abs(x) > 0.5 * length * (1.0 + 1e-12)):
        raise ValueError(f"x = {x!r}: must lie on the beam, within +-{0.5 * length:g} m of its centre")
    u = BETA_L * x / length
    out = (np.cos(u) / math.cos(_HALF) + np.cosh(u) / math.cosh(_HALF)) / _PHI_0
    return float(out) if out.ndim == 0 else out


def mode_slope(x, length: float):
    """dphi/dx [1/m] of `mode_shape` at ``x`` [m] from the centre."""
    x = np.asarray(x, dtype=float)
    beta = BETA_L / length
    u = beta * x
    out = beta * (-np.sin(u) / math.cos(_HALF) + np.sinh(u) / math.cosh(_HALF)) / _PHI_0
    return float(out) if out.ndim == 0 else out


def modal_mass_factor() -> float:
    """mu = (1/L) int phi^2 dx of the shape normalised to phi(0) = 1: the modal mass is mu m for
    a beam of mass m spread evenly (about 0.677)."""
    return 1.0 / _PHI_0**2


def node_fraction() -> float:
    """Where the mode's nodes lie, as a fraction of L from each end (about 0.2242): the root of
    phi between the centre and an end, by bisection."""
    lo, hi = 0.0, 0.5  # phi(0) = 1 > 0, phi(L/2) < 0: x / L from the centre
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mode_shape(mid, 1.0) > 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 - 0.5 * (lo + hi)


def bending_frequency(EI: float, mass: float, length: float) -> float:
    """The first bending frequency [Hz] of a free-free uniform beam: f = (beta L)^2 / (2 pi)
    sqrt(EI / (m L^3)), from its bending stiffness ``EI`` [N m^2], ``mass`` m [kg] and
    ``length`` L [m]."""
    return BETA_L**2 / (2.0 * math.pi) * math.sqrt(EI / (mass * length**3))


def bending_stiffness(frequency_hz: float, mass: float, length: float) -> float:
    """EI [N m^2] of a free-free uniform beam of ``mass`` [kg] and ``length`` [m] whose first
    bending frequency is ``frequency_hz``: the inverse of `bending_frequency`."""
    return mass * length**3 * (2.0 * math.pi * frequency_hz / BETA_L**2) ** 2
