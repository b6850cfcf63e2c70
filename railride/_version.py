"""The one version number of railride (read by the build, `pyproject.toml`, without importing the package),
and `versions`, the versions of the software that made a result (recorded in every result's
document). This module imports nothing from railride, so that any layer may import it."""

from __future__ import annotations

import functools

__version__ = "0.4.0"

#: the packages whose versions a result records, besides railride and Python
_PACKAGES = ("numpy", "scipy", "numba", "pandas", "xarray")


def versions() -> dict[str, str | None]:
    """The versions of railride, Python, NumPy, SciPy, numba, pandas and xarray, by name
    (``railride``, ``python``, ``numpy``, ``scipy``, ``numba``, ``pandas``, ``xarray``); None for
    a package that is not installed. Looked up once a process (a new dict each call)."""
    return dict(_versions())


@functools.lru_cache(maxsize=1)
def _versions() -> dict[str, str | None]:
    import platform
    from importlib.metadata import PackageNotFoundError, version

    out: dict[str, str | None] = {"railride": __version__, "python": platform.python_version()}
    for name in _PACKAGES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:  # pragma: no cover - every install has them
            out[name] = None
    return out


def utc_now() -> str:
    """The time a result is made, UTC to the second, ISO 8601 ("2026-11-28T04:40:00Z")."""
    from datetime import datetime, timezone

    return datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")
