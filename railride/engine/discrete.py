"""Exact discretisation of the linear vehicle: one step per output sample (passive), or per
stretch between rail nodes, controller samples and outputs (an outer loop on the ideal
actuator, `ClosedStepper`); no integration error (docs/model.md, Integration).

With the passive viscous secondary the vehicle is linear, x' = A x + r(t), x = (q, q'), and its
forcing r = Bw w + Bwd w' comes from rail inputs w that are cubic Hermite polynomials between
the nodes of the input table (`railride.model.track.wheelset_input_table`; w' is their derivative,
as the RK4 stepper takes it). Over a stretch of length L on which w is a cubic,

    x(L) = e^{AL} x(0) + sum_k Gamma_k r_k,   Gamma_k = int_0^L e^{A(L-s)} s^k ds,

r_k the coefficients of r in powers of the time s since the stretch began. e^{AL} and every
Gamma_k come from one matrix exponential of an augmented matrix (Van Loan, 1978), by scipy. An
output interval that spans nodes is split at them; the pattern of splits repeats, so each kind
of output step gets one matrix from the nodes it touches to the state increment, and a run is
x_{n+1} = Phi x_n + maps[n % period] (the nodes of step n), compiled (`exact_kernels.exact_run`).
"""

from __future__ import annotations

import math
import functools
from functools import lru_cache

import numpy as np
import scipy.linalg

from railride.engine.kernels import run_each
from railride.engine.layout import N_DOF

#: the cubic Hermite basis as powers of tau in [0, 1]: rows tau^0..tau^3, columns the node data
#: (y_k, I y'_k, y_k+1, I y'_k+1), I the node interval
HERMITE = np.array(
    [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [-3.0, -2.0, 3.0, -1.0],
        [2.0, 1.0, -2.0, 1.0],
    ]
)
N_STATE = 2 * N_DOF
N_INPUT = 16  # per node: the 8 rail heights, then their 8 rates


def _exponentials(A: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """(e^{AL}, Gamma) with Gamma[k] = int_0^L e^{A(L-s)} E s^k ds for k = 0..3, E the lower
    half (the accelerations): (4, 18, 9). From exp(M L), M = [[A, E, 0, 0, 0], [0, 0, I, 0, 0],
    [0, 0, 0, I, 0], [0, 0, 0, 0, I], 0], whose top row holds int e^{A(L-s)} E s^k / k! ds."""
    n, m = N_STATE, N_DOF
    size = n + 4 * m
    M = np.zeros((size, size))
    M[:n, :n] = A
    M[N_DOF:n, n : n + m] = np.eye(m)
    for k in range(3):
        M[n + k * m : n + (k + 1) * m, n + (k + 1) * m : n + (k + 2) * m] = np.eye(m)
    E = scipy.linalg.expm(M * L)
    gamma = np.stack([math.factorial(k) * E[:n, n + k * m : n + (k + 1) * m] for k in range(4)])
    return E[:n, :n], gamma


def _segment_map(gamma: np.ndarray, Bw: np.ndarray, Bwd: np.ndarray, tau0: float, interval: float) -> np.ndarray:
    """(18, 32): the state increment over a stretch that starts at tau0 of a node interval of
    length ``interval`` [s], from the data of its two nodes (w_k, w'_k, w_k+1, w'_k+1; 8 each).
    ``gamma`` from `_exponentials` for the stretch's length."""
    # w(s) = sum_j c_j s^j: re-expand the Hermite polynomial in tau = tau0 + s / interval
    scale = np.array([1.0, interval, 1.0, interval])  # the slopes enter as I y'
    coef = np.zeros((4, 4))  # power of s x node datum
    for j in range(4):
        for k in range(j + 1):
            coef[k] += math.comb(j, k) * tau0 ** (j - k) * interval ** (-k) * HERMITE[j] * scale
    out = np.zeros((N_STATE, 32))
    for k in range(4):
        # r_k = Bw c_k + (k + 1) Bwd c_(k+1): each c is a combination of the node data
        for d in range(4):
            block = coef[k, d] * Bw + ((k + 1) * coef[k + 1, d] * Bwd if k < 3 else 0.0)
            out[:, 8 * d : 8 * (d + 1)] += gamma[k] @ block
    return out


class ExactStepper:
    """The one-step-per-output map of the linear vehicle ``A`` (18 x 18) with rail forcing
    ``Bw``, ``Bwd`` (9 x 8) for output steps of ``stride`` time steps ``dt`` and an input table
    with a node every ``m`` time steps: ``Phi`` = e^{A stride dt} and ``maps[p]``, the state
    increment of an output step of phase p from the input-table rows it touches (`padded`)."""

    def __init__(self, A, Bw, Bwd, dt: float, stride: int, m: int):
        self.stride, self.m = stride, m
        by_length = _by_length(A, dt)
        self.Phi = by_length(stride)[0]
        period = math.lcm(stride, m) // stride  # output steps before the pattern of splits repeats
        #: nodes an output step touches, from the first node at or before its start
        self.span = (stride + m - 1) // m + 2
        maps = np.zeros((period, N_STATE, self.span * N_INPUT))
        for p in range(period):
            a, b = p * stride, (p + 1) * stride  # in time steps, from a node at 0
            base = a // m
            s = a
            while s < b:
                node = s // m
                end = min(b, (node + 1) * m)
                phi_rest = by_length(b - end)[0]
                gamma = by_length(end - s)[1]
                seg = phi_rest @ _segment_map(gamma, Bw, Bwd, (s - node * m) / m, m * dt)
                first = (node - base) * N_INPUT
                # node data order: w_k, w'_k, w_k+1, w'_k+1 -> the table rows k, k+1 (w then w')
                maps[p, :, first : first + 2 * N_INPUT] += seg
                s = end
        self.maps = maps
        self.period = period
        #: per phase, how many table rows its steps touch (the map is zero beyond them)
        blocks = np.abs(maps).reshape(period, N_STATE, self.span, N_INPUT).max(axis=(1, 3))
        self.used = np.array([int(np.flatnonzero(b > 0).max()) + 1 if np.any(b > 0) else 0 for b in blocks])

    def padded(self, utab: np.ndarray, n_out: int) -> np.ndarray:
        """``utab`` with its last row repeated where the last output step's span runs past it."""
        return _padded(utab, ((n_out - 1) * self.stride) // self.m + self.span)


def _by_length(A: np.ndarray, dt: float):
    """steps -> (e^{AL}, Gamma) for L = steps * dt (`_exponentials`), each length computed once:
    a pattern of stretches repeats few lengths."""

    @functools.cache
    def exponentials(steps: int) -> tuple[np.ndarray, np.ndarray]:
        return _exponentials(A, steps * dt)

    return exponentials


@lru_cache(maxsize=16)
def stepper(A_bytes: bytes, Bw_bytes: bytes, Bwd_bytes: bytes, dt: float, stride: int, m: int) -> ExactStepper:
    """An `ExactStepper`, kept for the next run with the same vehicle and grids (the matrices
    come as bytes: hashable keys of the cache)."""
    return ExactStepper(
        _matrix(A_bytes, (N_STATE, N_STATE)),
        _matrix(Bw_bytes, (N_DOF, 8)),
        _matrix(Bwd_bytes, (N_DOF, 8)),
        dt,
        stride,
        m,
    )


def _matrix(data: bytes, shape) -> np.ndarray:
    return np.frombuffer(data).reshape(shape).copy()


def _padded(utab: np.ndarray, rows: int) -> np.ndarray:
    """``utab`` with its last row repeated up to ``rows`` rows (the steps at the end of a run
    may reach a node past the table; the rail is held there)."""
    if len(utab) >= rows:
        return utab
    return np.vstack([utab, np.repeat(utab[-1:], rows - len(utab), axis=0)])


def hermite_at(utab: np.ndarray, times: np.ndarray, interval: float) -> tuple[np.ndarray, np.ndarray]:
    """Rail heights and rates (len(times), 8) at ``times`` [s] from the input table, as the
    stepper interpolates them (cubic Hermite; the rate is the derivative of the height)."""
    u = times / interval
    k = np.minimum(u.astype(np.int64), len(utab) - 2)
    tau = np.minimum(u - k, 1.0)[:, None]
    om = 1.0 - tau
    w0, d0, w1, d1 = utab[k, :8], utab[k, 8:], utab[k + 1, :8], utab[k + 1, 8:]
    w = (1 + 2 * tau) * om * om * w0 + tau * om * om * interval * d0 + tau * tau * (3 - 2 * tau) * w1
    w = w + tau * tau * (tau - 1) * interval * d1
    wd = 6 * tau * (tau - 1) / interval * (w0 - w1) + om * (1 - 3 * tau) * d0 + tau * (3 * tau - 2) * d1
    return w, wd


def run_exact(out: dict, samples: list, x0: np.ndarray, dt: float, stride: int, n_out: int):
    """Fill the stepper's output arrays ``out`` (q, v, a, f, w, wd: (n, rows, .)) for the
    passive samples: each of ``samples`` is (A, Bw, Bwd, T, c_sz, utab, interval) of one
    sample; ``x0`` (n, 18) the states at t = 0. Returns (status, fail_step) as the stepper's."""
    from railride.engine import exact_kernels as kernels

    n = len(samples)
    status = np.zeros(n, dtype=np.int64)
    fail_step = np.full(n, -1, dtype=np.int64)

    # made (or found) before the threads start: a batch's samples share a few vehicles
    steppers = [
        stepper(A.tobytes(), Bw.tobytes(), Bwd.tobytes(), float(dt), int(stride), int(round(interval / dt)))
        for A, Bw, Bwd, _, _, _, interval in samples
    ]

    def one(i: int) -> None:
        A, Bw, Bwd, T, c_sz, utab, interval = samples[i]
        st, m = steppers[i], int(round(interval / dt))
        kernels.exact_run(
            st.Phi,
            st.maps,
            st.used,
            stride,
            m,
            np.ascontiguousarray(st.padded(utab, n_out)),
            float(interval),
            np.ascontiguousarray(x0[i]),
            A,
            Bw,
            Bwd,
            np.ascontiguousarray(T),
            np.full(4, float(c_sz)),
            out["q"][i],
            out["v"][i],
            out["a"][i],
            out["f"][i],
            out["w"][i],
            out["wd"][i],
        )
        x = out["q"][i]
        bad = ~(
            np.all(np.abs(x) < kernels.DIVERGED, axis=1) & np.all(np.abs(out["v"][i]) < 1e3 * kernels.DIVERGED, axis=1)
        )
        if np.any(bad):
            status[i] = kernels.STATUS_DIVERGED
            fail_step[i] = int(np.argmax(bad)) * stride

    run_each(one, n)  # on numba's threads: the kernels release the GIL, the samples are independent
    return status, fail_step


class ClosedStepper:
    """The exact steps of the plant (``A`` without the secondary dashpots) under an outer loop on
    the ideal actuator: the force is the held demand, constant between controller samples, so
    the run splits at every rail node (every ``m`` steps), controller sample (``ctrl``) and output
    sample (``stride``); the pattern repeats every lcm of the three. For each stretch of the
    pattern: ``phi`` = e^{AL}, ``rail`` (18 x 32) from the data of its node interval's two table
    rows, and ``force`` (18 x 4) = Gamma_0 M^-1 T from the held corner forces; ``start`` its first
    step in the pattern."""

    def __init__(self, A, Bw, Bwd, Bf, dt: float, stride: int, ctrl: int, m: int):
        by_length = _by_length(A, dt)
        period = math.lcm(stride, ctrl, m)
        marks = sorted(set(range(0, period, stride)) | set(range(0, period, ctrl)) | set(range(0, period, m)))
        ends = marks[1:] + [period]
        n = len(marks)
        self.period = period
        self.start = np.array(marks, dtype=np.int64)
        self.phi = np.empty((n, N_STATE, N_STATE))
        self.rail = np.empty((n, N_STATE, 32))
        self.force = np.empty((n, N_STATE, 4))
        for i, (a, b) in enumerate(zip(marks, ends)):
            phi, gamma = by_length(b - a)
            self.phi[i] = phi
            self.rail[i] = _segment_map(gamma, Bw, Bwd, (a % m) / m, m * dt)
            self.force[i] = gamma[0] @ Bf


@lru_cache(maxsize=16)
def closed_stepper(A_bytes, Bw_bytes, Bwd_bytes, Bf_bytes, dt, stride, ctrl, m) -> ClosedStepper:
    """A `ClosedStepper`, kept for the next run with the same vehicle and grids."""
    return ClosedStepper(
        _matrix(A_bytes, (N_STATE, N_STATE)),
        _matrix(Bw_bytes, (N_DOF, 8)),
        _matrix(Bwd_bytes, (N_DOF, 8)),
        _matrix(Bf_bytes, (N_DOF, 4)),
        dt,
        stride,
        ctrl,
        m,
    )


def run_exact_closed(out: dict, samples: list, x0: np.ndarray, dt: float, stride: int, ctrl: int, n_out: int):
    """Fill the stepper's output arrays (q, v, a, f, w, wd, fd, vc) for samples of an outer loop
    on the ideal actuator: each of ``samples`` is (A of the plant, Bw, Bwd, Bf = M^-1 T, G (4 x
    18), H (4 x 3), delay in controller periods, utab, interval). Returns (status, fail_step)."""
    from railride.engine import exact_kernels as kernels

    n = len(samples)
    status = np.zeros(n, dtype=np.int64)
    fail_step = np.full(n, -1, dtype=np.int64)
    steppers = [  # made (or found) before the threads start, as run_exact's
        closed_stepper(
            A.tobytes(), Bw.tobytes(), Bwd.tobytes(), Bf.tobytes(), float(dt), stride, ctrl, int(round(interval / dt))
        )
        for A, Bw, Bwd, Bf, _, _, _, _, interval in samples
    ]

    def one(i: int) -> None:
        A, Bw, Bwd, Bf, G, H, delay, utab, interval = samples[i]
        st, m = steppers[i], int(round(interval / dt))
        utab = _padded(utab, (n_out * stride) // m + 2)
        status[i], fail_step[i] = kernels.exact_closed_run(
            st.phi,
            st.rail,
            st.force,
            st.start,
            st.period,
            m,
            stride,
            ctrl,
            ctrl * dt,
            np.ascontiguousarray(utab),
            float(interval),
            np.ascontiguousarray(x0[i]),
            A,
            Bw,
            Bwd,
            np.ascontiguousarray(Bf),
            np.ascontiguousarray(G),
            np.ascontiguousarray(H),
            int(delay),
            n_out,
            out["q"][i],
            out["v"][i],
            out["a"][i],
            out["f"][i],
            out["w"][i],
            out["wd"][i],
            out["fd"][i],
            out["vc"][i],
        )

    run_each(one, n)  # on numba's threads: the kernels release the GIL, the samples are independent
    return status, fail_step
