"""How far two runs of the same batch are apart: what the tests of a second stepper (the lane
stepper, the GPU kernel) measure against the first."""

from __future__ import annotations

import numpy as np


def histories(result) -> dict[str, np.ndarray]:
    """The float time histories of a batch's Dataset, by name (those with a ``sample`` axis)."""
    ds = result.dataset
    return {k: ds[k].values for k in ds.data_vars if ds[k].dtype.kind == "f" and "sample" in ds[k].dims}


def worst_difference(a: dict, b: dict) -> float:
    """The largest difference of any history of ``a`` from ``b``'s, over that history's largest
    value in ``b``; inf where the NaNs (a diverged sample's tail) differ."""
    worst = 0.0
    for k in b:
        if not np.array_equal(np.isnan(a[k]), np.isnan(b[k])):
            return np.inf
        scale = np.nanmax(np.abs(b[k])) if np.any(np.isfinite(b[k])) else 0.0
        if scale > 0.0:
            worst = max(worst, float(np.nanmax(np.abs(a[k] - b[k]))) / scale)
    return worst
