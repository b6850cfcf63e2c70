"""The compiled parts of the rail input tables, without the GIL: a study builds the tables of
one chunk while the compiled stepper runs the next, and work that holds the GIL there keeps the
second core from it (docs/performance.md).

- `cubic_on_grid`: a random track's cubic splines (`railride.model.irregularity`) at the
  wheelsets, the rail heights and slopes. The same arithmetic as scipy's piecewise polynomials
  (``PPoly``): the interval x_i <= s < x_i+1 (the last one up to and past the end), and the
  polynomial in powers of s - x_i summed from the constant term up, so the values are scipy's
  to the last bit.
- `forcing_nodes`: the rail forcing at the table's nodes (`railride.run.inputs`), the products
  of the input matrices with the heights and rates, read by the steppers' interpolation. Each
  product's eight terms are summed as NumPy's ``einsum`` summed them on the machine that
  replaced it (even and odd terms apart, then together), so its tables are the same to the
  bit there; elsewhere they may differ in the last bit, as ``einsum``'s own did by machine.
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


@njit(cache=True, nogil=True)
def forcing_nodes(utab, Bw, Bwd, out):
    """``out`` (n, 4 J) = (Bw w, Bw w', Bwd w, Bwd w') at each of the n nodes of the input table
    ``utab`` (n, 16: w in columns 0-7, w' in 8-15); Bw, Bwd (J, 8). A zero term is skipped: it
    adds nothing to a finite sum."""
    n = utab.shape[0]
    J = Bw.shape[0]
    for r in range(n):
        for m in range(4):
            B = Bw if m < 2 else Bwd
            col = 8 * (m % 2)  # w, then w'
            for j in range(J):
                even = 0.0
                odd = 0.0
                for k in range(0, 8, 2):
                    if B[j, k] != 0.0:
                        even += utab[r, col + k] * B[j, k]
                    if B[j, k + 1] != 0.0:
                        odd += utab[r, col + k + 1] * B[j, k + 1]
                out[r, m * J + j] = even + odd
