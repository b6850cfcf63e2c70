"""Compiled evaluation of the random tracks' cubic splines (`railride.model.irregularity`): the
rail heights and slopes at the wheelsets for the input tables, without the GIL.

scipy's spline evaluation holds the GIL, and in a study it ran beside the compiled stepper of the
next chunk, where it kept a second core from the Python work of the chunk before
(docs/performance.md). This is the same arithmetic as scipy's piecewise polynomials (``PPoly``):
the interval x_i <= s < x_i+1 (the last one up to and past the end), and the polynomial in
powers of s - x_i summed from the constant term up, so the values are scipy's to the last bit.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, nogil=True)
def cubic_on_grid(x, c_left, c_right, s, out):
    """The two rails' cubics at the positions ``s`` (1-D): ``out`` (4, len(s)) gets z_L, z_R,
    dz_L/ds and dz_R/ds. ``x``: the breakpoints, uniform (x_i = x_0 + i h); ``c_left``,
    ``c_right``: the coefficients (4, len(x) - 1), highest power first, as ``PPoly.c``."""
    m = x.shape[0] - 1  # intervals
    x0 = x[0]
    h = (x[m] - x0) / m
    for k in range(s.shape[0]):
        sk = s[k]
        # the uniform grid's guess, then the interval of scipy's search (x_i <= s < x_i+1)
        i = int((sk - x0) / h) if sk > x0 else 0
        if i > m - 1:
            i = m - 1
        while i > 0 and sk < x[i]:
            i -= 1
        while i < m - 1 and sk >= x[i + 1]:
            i += 1
        t = sk - x[i]
        t2 = t * t
        t3 = t2 * t
        # value: c3 + c2 t + c1 t^2 + c0 t^3; slope: c2 + 2 c1 t + 3 c0 t^2 (PPoly's order)
        out[0, k] = c_left[3, i] + c_left[2, i] * t + c_left[1, i] * t2 + c_left[0, i] * t3
        out[1, k] = c_right[3, i] + c_right[2, i] * t + c_right[1, i] * t2 + c_right[0, i] * t3
        out[2, k] = c_left[2, i] + c_left[1, i] * t * 2.0 + c_left[0, i] * t2 * 3.0
        out[3, k] = c_right[2, i] + c_right[1, i] * t * 2.0 + c_right[0, i] * t2 * 3.0
