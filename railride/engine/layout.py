"""The engine's layout: sizes, codes and compile options shared by the compiled kernels and the
Python layers above them. Plain numbers only: importing this module loads no numba, so the
parameter classes (dampers, faults, sensing, the suspension) take their codes from here without
compiling anything. numba reads module-level integers as compile-time constants, so a named
slot (``P[ETA]``) compiles to the same machine code as a number (``P[9]``).
"""

from __future__ import annotations

# -- the vehicle -----------------------------------------------------------------------------------
#: carbody and two bogies in bounce, pitch and roll, then the carbody's first vertical bending
#: mode (`railride.model.beam`): a rigid carbody's vehicle is padded with a bending row and
#: column of zeros, so that its bending stays 0 (`railride.run.inputs`)
N_DOF = 10
N_RIGID = 9
ROW_BENDING = 9
#: the bogies' six rows (front then rear: bounce, pitch, roll) from this one: the only rows of q''
#: that the rail inputs reach, through the primary suspension
ROW_BOGIES = 3
N_CORNER = 4  # secondary suspension corners (dampers): 1R, 1L, 2R, 2L
N_RAIL = 8  # rail inputs: four wheelsets, two rails each
NY = 2 * N_DOF + N_CORNER  # length of the stage vector (q, q', f)
#: a displacement or rotation beyond this (m or rad) is taken as divergence
DIVERGED = 1.0e3

# -- dampers ---------------------------------------------------------------------------------------
#: damper laws: passive dashpots kept inside the damping matrix, or one of the laws of
#: railride.secondary.dampers (forces computed at every stage)
LAW_VISCOUS_IN_C = 0
LAW_VISCOUS = 1
LAW_BOUC_WEN = 2
LAW_SPENCER = 3
LAW_IDEAL = 4
#: internal states per damper in the stepper: z, y (Spencer only), u
N_DAMPER_STATES = 3
#: the slots of a damper's packed parameter vector (`railride.secondary.dampers`, ``pack``):
#: alpha = P_ALPHA_A + P_ALPHA_B u, c0 = P_C0A + P_C0B u (a viscous damper: c in P_C0A), the
#: spring P_K0, the Bouc-Wen P_A, P_N, P_GAMMA, P_BETA, the coil rate P_ETA, the voltage range
#: P_V_MIN..P_V_MAX, Spencer's c1 = P_C1A + P_C1B u and P_K1, and P_Z_BOUND, the bound of |z|.
#: An ideal device keeps its dissipative flag (1 or 0) in slot P_DISSIPATIVE.
(
    P_ALPHA_A,
    P_ALPHA_B,
    P_C0A,
    P_C0B,
    P_K0,
    P_A,
    P_N,
    P_GAMMA,
    P_BETA,
    P_ETA,
    P_V_MIN,
    P_V_MAX,
    P_C1A,
    P_C1B,
    P_K1,
    P_Z_BOUND,
) = range(16)
P_DISSIPATIVE = P_ALPHA_A
N_PACKED = 16

# -- voltage laws and faults ---------------------------------------------------------------------
#: how the closed loop sets an MR damper's voltage from the demand f_d (on the carbody) at a
#: corner; the index is the engine's code (docs/control.md, Voltage laws):
#: "tracking": the paper's inner loop, v = clip(G (f_d - B f) sgn f, v_min, v_max);
#: "on-off": v_max where f_d x' < 0 (a force the damper gives while dissipating), else v_min;
#: "clipped": Dyke et al. (1996), v_max where (f_d - f) f > 0, else v_min
VOLTAGE_LAWS = ("tracking", "on-off", "clipped")
VOLTAGE_TRACKING, VOLTAGE_ON_OFF, VOLTAGE_CLIPPED = range(3)
#: damper faults (railride.secondary.faults): none, held at v_min ("off"), stuck at v_max ("on"),
#: no force
FAULT_NONE = 0
FAULT_OFF = 1
FAULT_ON = 2
FAULT_DISCONNECTED = 3
#: the columns of a sample's row of the fault table (`railride.secondary.faults.fault_table`, int64):
#: corner c's mode (FAULT_*) in F_MODE + c, the step it fails at in F_STEP + c
F_MODE = 0
F_STEP = N_CORNER
N_FAULT_COLS = 2 * N_CORNER

# -- the closed loop's settings ------------------------------------------------------------------
#: the columns of a sample's inner-loop row: the tracking law's B and G, the voltage law
#: (VOLTAGE_*), and the delay from a controller sample to its demand taking effect, in controller
#: periods (1 to MAX_DELAY)
I_B, I_G, I_LAW, I_DELAY = range(4)
N_INNER = 4
#: the columns of the sensor-noise table (a row per controller sample): the carbody's (z, phi,
#: theta) from NOISE_Q, their rates from NOISE_V
NOISE_Q = 0
NOISE_V = 3
NOISE_COLS = 6

# -- the state array of a sample -------------------------------------------------------------------
N_DS = N_CORNER * N_DAMPER_STATES  # damper states of the vehicle
NS_MAX = 2 * N_DOF + N_DS  # state (q, q', damper states)
XI = NS_MAX  # controller: integral of the sampled (z, phi, theta) ...
FD_HELD = XI + 3  # ... the corner force demands in effect ...
#: the longest computation delay, in controller periods
MAX_DELAY = 64
FD_NEXT = FD_HELD + N_CORNER  # ... and those computed at the last MAX_DELAY samples (a ring)
#: realistic sensing (railride.secondary.sensing): per corner the accelerometer's anti-alias
#: filter output, the last sample, and the two band-limited integration stages (high-pass,
#: leaky integral)
SENS = FD_NEXT + MAX_DELAY * N_CORNER
#: a corner's sensing states, from SENS + N_SENS_STATES c: the anti-alias filter's output, the
#: last sample, the first high-pass, the velocity estimate, its last value, the second
#: high-pass, the displacement estimate
SS_FILTERED, SS_LAST, SS_HP1, SS_VEL, SS_VEL_LAST, SS_HP2, SS_DISP = range(7)
N_SENS_STATES = 7
NX = SENS + N_SENS_STATES * N_CORNER  # columns of the state array x
#: the columns of a sample's sensing settings (`railride.secondary.sensing.Sensing.pack`): on (1)
#: or ideal states (0), the anti-alias filter and estimator corner rates [rad/s], the bias of
#: each corner [m/s^2] from S_BIAS, the 3 x 4 map from corner values to the carbody's (z, phi,
#: theta), row by row, from S_MAP
S_ON, S_W_AA, S_W_C = range(3)
S_BIAS = 3
S_MAP = S_BIAS + N_CORNER
SENSING_COLS = S_MAP + 3 * N_CORNER

# -- sub-steps, the rig, status ----------------------------------------------------------------------
#: sub-steps resolve the fastest damper rate: rate x SUBSTEP_DT_REF / (sub-steps) <= this
SUBSTEP_LIMIT = 0.5
SUBSTEP_DT_REF = 1e-4
MAX_SUBSTEPS = 1024
#: how the damper rig sets the command voltage (`kernels.rig_batch`)
RIG_CONSTANT = 0
RIG_COMMANDED = 1
RIG_TRACKING = 2
#: the columns of the rig's output rows: time, extension and its rate, force, the damper states
#: z, y, u, the command voltage and the energy dissipated
RIG_COLUMNS = ("t", "x", "xd", "F", "z", "y", "u", "v", "E")
R_T, R_X, R_XD, R_F, R_Z, R_Y, R_U, R_V, R_E = range(9)
STATUS_OK = 0
STATUS_DIVERGED = 1

# -- compile options -------------------------------------------------------------------------------
#: reassociation lets LLVM vectorise the dot products; NaN/inf semantics stay IEEE so the
#: divergence check still sees them
FASTMATH = {"reassoc", "contract", "nsz", "arcp"}
#: numba's parallel pipeline with every parfor conversion off: it creates no parallel region
#: (so threads may call the kernels at once), yet the stepper it compiles runs 2.5 times faster
#: than with the plain pipeline (19 ms against 50 ms for 10 s of the passive vehicle; measured,
#: the responsible pass not traced). ``parallel=True`` with ``prange`` compiled in 12 s against
#: 6 s; see docs/performance.md.
NO_PARFORS = dict(
    comprehension=False,
    reduction=False,
    inplace_binop=False,
    setitem=False,
    numpy=False,
    stencil=False,
    fusion=False,
    prange=False,
)
