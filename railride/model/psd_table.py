"""A user's own track irregularity spectrum as a table (docs/track.md, "Your own spectrum"): a
CSV of one-sided displacement PSDs of the vertical profile and the cross-level against
wavenumber, read once, interpolated linearly in log-log between its rows, and synthesised into a
random track like the standard spectra (scenario ``psd:PATH``).

The file's first line names its columns:

* ``wavenumber_rad_per_m`` (Omega = 2 pi / wavelength, PSDs in m^2/(rad/m)) or
  ``spatial_frequency_per_m`` (cycles per metre, 1 / wavelength, PSDs in m^2/(1/m), which
  are 2 pi times the same PSD per rad/m);
* ``vertical``: the PSD of the vertical profile z_v (mean of the two rails);
* ``cross_level`` (optional): the PSD of the height difference z_x = z_L - z_R; without it the
  two rails are the same (no roll input).

Lines starting with ``#`` are comments. Wavenumbers rise strictly; PSDs are > 0 (log-log)."""

from __future__ import annotations

import csv
import functools
import hashlib
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from railride.errors import InputError

#: the scenario names of a user's spectrum: psd:PATH
PREFIX = "psd:"
#: the first column's names, and the factor from its unit to rad/m
ABSCISSAE = {"wavenumber_rad_per_m": 1.0, "spatial_frequency_per_m": 2.0 * math.pi}


@dataclass(frozen=True, eq=False)
class PsdTable:
    """A spectrum read from a table: wavenumbers [rad/m] and the one-sided PSDs there
    [m^2/(rad/m)] (``cross_level`` None: the rails the same), with the file's path and the
    SHA-256 of those values (what a result records of it: the same spectrum, the same hash,
    whatever the file's comments or number formats)."""

    path: str
    wavenumber: np.ndarray
    vertical: np.ndarray
    cross_level: np.ndarray | None
    sha256: str

    def __call__(self, wavenumber, component: str = "vertical") -> np.ndarray:
        """The PSD at ``wavenumber`` [rad/m], log-log between the rows; an InputError outside
        the table's range (a spectrum is not extrapolated)."""
        W = np.asarray(wavenumber, dtype=float)
        lo, hi = self.wavenumber[0], self.wavenumber[-1]
        if W.size and (W.min() < lo * (1 - 1e-12) or W.max() > hi * (1 + 1e-12)):
            outside = W.min() if W.min() < lo else W.max()
            raise InputError(
                f"scenario {PREFIX + self.path!r}: wavenumber {outside:.4g} rad/m (wavelength "
                f"{2 * math.pi / outside:.4g} m) is outside the table's {lo:.4g} to {hi:.4g} rad/m (wavelengths "
                f"{2 * math.pi / hi:.4g} to "
                f"{2 * math.pi / lo:.4g} m); a spectrum is not extrapolated: narrow the wavelength band "
                "(min_wavelength, max_wavelength) or extend the table"
            )
        S = self.vertical if component == "vertical" else self.cross_level
        if S is None:  # no cross-level column: the rails are one profile
            return np.zeros_like(W)
        logW = np.log(np.clip(W, lo, hi))
        return np.exp(np.interp(logW, np.log(self.wavenumber), np.log(S)))

    def band(self) -> tuple[float, float]:
        """(shortest, longest) wavelength [m] the table covers."""
        return 2 * math.pi / float(self.wavenumber[-1]), 2 * math.pi / float(self.wavenumber[0])


def is_table(name) -> bool:
    """Whether a scenario name is a user's spectrum table (psd:PATH)."""
    return isinstance(name, str) and name.startswith(PREFIX)


def table(name: str) -> PsdTable:
    """The `PsdTable` of scenario ``name`` (psd:PATH), read once per version of the file."""
    path = Path(name[len(PREFIX) :])
    if not str(path) or name == PREFIX:
        raise InputError(f"scenario {PREFIX!r} needs a path, as in {PREFIX}my_line.csv")
    try:
        stat = path.stat()
    except OSError:
        raise InputError(f"scenario {name!r}: no such spectrum table {str(path)!r}") from None
    if path.is_dir():
        raise InputError(f"scenario {name!r}: a folder, not a spectrum table (a CSV file)")
    return _read(str(path), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=16)
def _read(path: str, mtime_ns: int, size: int) -> PsdTable:
    where = f"scenario {PREFIX + path!r}"
    try:
        raw = Path(path).read_bytes()
        text = raw.decode("utf-8-sig")  # a spreadsheet's byte-order mark is no part of the header
    except OSError as exc:
        raise InputError(f"{where}: cannot read the spectrum table: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"{where}: not a UTF-8 text CSV file") from None
    lines = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    if not rows:
        raise InputError(f"{where}: empty; give a header line and at least two rows")
    head = [h.strip() for h in rows[0]]
    allowed = f"{' or '.join(ABSCISSAE)}, then vertical, and optionally cross_level"
    if not head or head[0] not in ABSCISSAE or head[1:] not in (["vertical"], ["vertical", "cross_level"]):
        raise InputError(f"{where}: header {','.join(head)!r}: the columns must be {allowed}")
    values = []
    for k, row in enumerate(rows[1:], 2):
        if len(row) != len(head):
            raise InputError(f"{where}: row {k} has {len(row)} values, the header {len(head)}")
        try:
            values.append([float(x) for x in row])
        except ValueError:
            raise InputError(f"{where}: row {k} = {','.join(row)!r}: not numbers") from None
    x = np.array(values, dtype=float).reshape(-1, len(head))
    if x.shape[0] < 2:
        raise InputError(f"{where}: {x.shape[0]} row(s); a spectrum needs at least two")
    if not np.isfinite(x).all() or (x <= 0).any():
        k = int(np.argwhere(~np.isfinite(x) | (x <= 0))[0][0]) + 2
        raise InputError(f"{where}: row {k}: every value must be a finite number > 0 (PSDs are read in log-log)")
    if not (np.diff(x[:, 0]) > 0).all():
        k = int(np.argwhere(np.diff(x[:, 0]) <= 0)[0][0]) + 3
        raise InputError(f"{where}: row {k}: the {head[0]} must rise strictly from row to row")
    factor = ABSCISSAE[head[0]]
    # S per rad/m = S per (1/m) / (2 pi): the same variance over the same band
    W, S = x[:, 0] * factor, x[:, 1:] / factor
    return PsdTable(
        path=path,
        wavenumber=W,
        vertical=S[:, 0],
        cross_level=S[:, 1] if S.shape[1] > 1 else None,
        # of the values read, in rad/m (a comment or a reformatted number is the same spectrum)
        sha256=hashlib.sha256(np.ascontiguousarray(np.column_stack([W, S])).tobytes()).hexdigest(),
    )
