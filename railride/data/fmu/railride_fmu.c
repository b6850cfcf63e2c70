/* railride's vehicle as an FMI 2.0 co-simulation FMU (docs/fmu.md).

   The vehicle (rigid, or with the carbody's first bending mode), its secondary (passive
   dashpots, Bouc-Wen MR dampers with the coil lag, or an ideal actuator) and the bump stops,
   stepped by the classical fixed-step RK4 of railride's engine at the step dt, with the same
   sub-steps where the dampers' states are stiff. model.h, written by railride.export_fmu,
   holds the vehicle's matrices, the damper's parameters and the value references.

   The FMI 2.0 types and functions below are declared here as the standard defines them
   (Functional Mock-up Interface 2.0.4, Modelica Association, sections 2.1 and 4.2); the
   modelDescription.xml beside these sources names every variable. */

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"

/* -- FMI 2.0 types ------------------------------------------------------------------------- */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
#define fmi2True 1
#define fmi2False 0
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);
typedef struct {
    const fmi2CallbackLogger logger;
    const fmi2CallbackAllocateMemory allocateMemory;
    const fmi2CallbackFreeMemory freeMemory;
    const fmi2StepFinished stepFinished;
    const fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#if defined(_WIN32)
#define RR_EXPORT __declspec(dllexport)
#else
#define RR_EXPORT __attribute__((visibility("default")))
#endif

/* -- the model ----------------------------------------------------------------------------- */
#define NQ RR_N_DOF               /* the vehicle's DOFs */
#define NY (2 * NQ + 4)           /* (q, q', corner forces): what q'' is a product of */
#define NS (2 * NQ + 8)           /* the state: q, q', then z and u of each MR damper */
#define DIVERGED 1.0e3            /* m or rad: a response beyond this has diverged */
#define RR_PI 3.14159265358979323846

enum { MODE_INSTANTIATED, MODE_INITIALISATION, MODE_STEPPING, MODE_TERMINATED, MODE_ERROR };

typedef struct {
    double r[RR_N_REAL];          /* every Real variable, by value reference */
    int i[RR_N_INTEGER];          /* every Integer variable, by value reference - RR_VR_INTEGER0 */
    double s[NS];                 /* the state */
    double time;
    double t_start;               /* the experiment's start time */
    long step;                    /* steps of dt since the start */
    int mode;
    int clipped_said;             /* a command outside the damper's range was said once */
    int stale;                    /* inputs set since the outputs were made */
    double vc[4];                 /* the command voltages the inner loop last set */
    long node;                    /* the sine's input-grid node whose values are kept, -1: none */
    double node_w[2][8], node_wd[2][8]; /* the values and rates at nodes node and node + 1 */
    double *track;                /* scenario 2: the random track's spline pieces (resources/track.bin) */
    long track_pieces;            /* its pieces: the realisation's samples - 1 */
    double track_ds;              /* its sample spacing [m] */
    char name[128];               /* the instance's name, copied (the host's string may go) */
    fmi2CallbackFunctions cb;
    int logging;
} Instance;

static void say(Instance *m, fmi2Status status, const char *category, const char *format, ...) {
    char text[512];
    va_list args;
    if (m == NULL || m->cb.logger == NULL) return;
    if (!m->logging && status == fmi2OK) return;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    m->cb.logger(m->cb.componentEnvironment, m->name, status, category, "%s", text);
}

/* The paper's sine at the wheelsets at time t, exactly: heights w and rates w' (order 1L, 1R,
   ..., 4R), with its raised-cosine entry taper (railride.model.track.SineTrack). */
static void sine(const Instance *m, double t, double *w, double *wd) {
    const double V = m->r[RR_VR_SPEED], A = m->r[RR_VR_AMPLITUDE], lam = m->r[RR_VR_WAVELENGTH];
    const double k = 2.0 * RR_PI / lam, psi = m->r[RR_VR_RAIL_PHASE] * RR_PI / 180.0;
    const double L = m->r[RR_VR_TAPER] * lam;
    int j;
    for (j = 0; j < 4; j++) {
        const double s = V * t - RR_LAG[j];
        double zl = 0.0, zr = 0.0, dzl = 0.0, dzr = 0.0;
        if (s > 0.0) {
            zl = A * sin(k * s);
            zr = A * sin(k * s - psi);
            dzl = A * k * cos(k * s);
            dzr = A * k * cos(k * s - psi);
            if (L > 0.0 && s < L) {
                const double r = 0.5 * (1.0 - cos(RR_PI * s / L)), dr = 0.5 * RR_PI / L * sin(RR_PI * s / L);
                dzl = r * dzl + dr * zl;
                dzr = r * dzr + dr * zr;
                zl *= r;
                zr *= r;
            }
        }
        w[2 * j] = zl;
        w[2 * j + 1] = zr;
        wd[2 * j] = V * dzl;
        wd[2 * j + 1] = V * dzr;
    }
}

/* The random track of the export (scenario 2) at the wheelsets at time t: heights and rates of
   its cubic spline pieces (scipy's CubicSpline of the realisation, railride.model.track.RandomTrack),
   level before s = 0, held (with no slope) past the realisation's end, as railride's input table. */
static void random_track(const Instance *m, double t, double *w, double *wd) {
    const double V = m->r[RR_VR_SPEED], end = m->track_pieces * m->track_ds;
    int j, r;
    for (j = 0; j < 4; j++) {
        const double s0 = V * t - RR_LAG[j], s = s0 < end ? s0 : end;
        long i = (long)floor(s / m->track_ds);
        double dx;
        if (i > m->track_pieces - 1) i = m->track_pieces - 1;
        if (i < 0) i = 0;
        dx = s - (double)i * m->track_ds;
        for (r = 0; r < 2; r++) { /* left, right */
            const double *c = m->track + 4 * (r * m->track_pieces + i);
            w[2 * j + r] = s0 > 0.0 ? ((c[0] * dx + c[1]) * dx + c[2]) * dx + c[3] : 0.0;
            wd[2 * j + r] = s0 > 0.0 && s0 <= end ? V * ((3.0 * c[0] * dx + 2.0 * c[1]) * dx + c[2]) : 0.0;
        }
    }
}

/* The rail heights w and rates w' at the wheelsets at time t (order 1L, 1R, ..., 4R).
   Scenario 0: the inputs, carried on from the communication step's start t0 with their rates
   (w' held). Scenario 1: the paper's sine as railride's engine sees it: its values and slopes at
   the nodes of the input grid (railride.model.track.input_table_nodes: a node every 2^j steps
   dt, about RR_NODES_PER_FEATURE a wavelength) joined by cubic Hermite pieces, and the rate the
   derivative of that curve (railride.engine.laws._hermite). */
static void rails(Instance *m, double t, double t0, double *w, double *wd) {
    int j;
    t -= m->t_start; /* the track starts with the experiment */
    t0 -= m->t_start;
    if (m->i[RR_VR_SCENARIO - RR_VR_INTEGER0] == 0) {
        for (j = 0; j < 8; j++) {
            wd[j] = m->r[RR_VR_RAIL_RATE + j];
            w[j] = m->r[RR_VR_RAIL_HEIGHT + j] + wd[j] * (t - t0);
        }
        return;
    }
    {
        const int random = m->i[RR_VR_SCENARIO - RR_VR_INTEGER0] == 2;
        const double dt = m->r[RR_VR_DT];
        const double spacing = random ? RR_TRACK_SPACING : m->r[RR_VR_WAVELENGTH] / RR_NODES_PER_FEATURE;
        const double ratio = spacing / (m->r[RR_VR_SPEED] * dt);
        const double interval = (ratio >= 1.0 ? ldexp(1.0, (int)floor(log2(fmin(ratio, 4503599627370496.0)))) : 1.0) * dt;
        const double u = t / interval;
        const long k = (long)u;
        double tau = u - (double)k, om, h00, h10, h01, h11, d00, d10, d11;
        const double *wa, *wda, *wb, *wdb;
        if (tau > 1.0) tau = 1.0;
        om = 1.0 - tau;
        h00 = (1.0 + 2.0 * tau) * om * om;
        h10 = tau * om * om * interval;
        h01 = tau * tau * (3.0 - 2.0 * tau);
        h11 = tau * tau * (tau - 1.0) * interval;
        d00 = 6.0 * tau * (tau - 1.0) / interval;
        d10 = om * (1.0 - 3.0 * tau);
        d11 = tau * (3.0 * tau - 2.0);
        if (k != m->node) { /* a node every 2^j steps: the sine is evaluated there once */
            if (k == m->node + 1) {
                memcpy(m->node_w[0], m->node_w[1], sizeof m->node_w[0]);
                memcpy(m->node_wd[0], m->node_wd[1], sizeof m->node_wd[0]);
            } else if (random) {
                random_track(m, (double)k * interval, m->node_w[0], m->node_wd[0]);
            } else {
                sine(m, (double)k * interval, m->node_w[0], m->node_wd[0]);
            }
            if (random)
                random_track(m, (double)(k + 1) * interval, m->node_w[1], m->node_wd[1]);
            else
                sine(m, (double)(k + 1) * interval, m->node_w[1], m->node_wd[1]);
            m->node = k;
        }
        wa = m->node_w[0];
        wda = m->node_wd[0];
        wb = m->node_w[1];
        wdb = m->node_wd[1];
        for (j = 0; j < 8; j++) {
            w[j] = h00 * wa[j] + h10 * wda[j] + h01 * wb[j] + h11 * wdb[j];
            wd[j] = d00 * (wa[j] - wb[j]) + d10 * wda[j] + d11 * wdb[j];
        }
    }
}

/* The force of a bump stop on the carbody at the deflection x (railride.engine.laws.stop_force). */
static double stop_force(double x) {
    if (x > RR_Z_STOP) return -RR_K_STOP * (x - RR_Z_STOP);
    if (x < -RR_Z_STOP) return -RR_K_STOP * (x + RR_Z_STOP);
    return 0.0;
}

#if RR_SECONDARY == RR_SECONDARY_MR
/* The Bouc-Wen rate z' (railride.engine.laws._bouc_wen_rate). */
static double bouc_wen_rate(double z, double w) {
    const double az = fabs(z);
    const double zn1 = RR_BW_N == 1.0 ? 1.0 : (RR_BW_N == 2.0 ? az : pow(az, RR_BW_N - 1.0));
    return -RR_BW_GAMMA * fabs(w) * z * zn1 - RR_BW_BETA * w * zn1 * az + RR_BW_A * w;
}
#endif

/* ds/dt at time t for the held commands v (volts, or newtons on the carbody for the actuator);
   f: each corner's damper force on the carbody (the stops not included, as a load cell on the
   damper would read it); x, xd: the corners' deflections and rates. */
static void derivative(Instance *m, const double *s, double t, double t0, const double *v, double *ds,
                       double *f, double *x, double *xd) {
    double y[NY], w[8], wd[8];
    int i, j, c;
    for (i = 0; i < NQ; i++) ds[i] = s[NQ + i];
    for (c = 0; c < 4; c++) {
        x[c] = 0.0;
        xd[c] = 0.0;
        for (j = 0; j < NQ; j++) {
            x[c] += RR_T[j][c] * s[j];
            xd[c] += RR_T[j][c] * s[NQ + j];
        }
    }
    for (j = 0; j < 2 * NQ; j++) y[j] = s[j];
    for (c = 0; c < 4; c++) {
#if RR_SECONDARY == RR_SECONDARY_MR
        const double z = s[2 * NQ + c], u = s[2 * NQ + 4 + c];
        const double alpha = RR_BW_ALPHA_A + RR_BW_ALPHA_B * u, c0 = RR_BW_C0A + RR_BW_C0B * u;
        const double F = c0 * xd[c] + RR_BW_K0 * x[c] + alpha * z;
        ds[2 * NQ + c] = bouc_wen_rate(z, xd[c]);
        ds[2 * NQ + 4 + c] = -RR_BW_ETA * (u - v[c]);
        f[c] = -F;
#elif RR_SECONDARY == RR_SECONDARY_ACTUATOR
        f[c] = v[c];
#else
        (void)v;
        f[c] = -RR_C_SEC * xd[c]; /* the dashpots sit in RR_A: reported, not added */
#endif
        y[2 * NQ + c] = RR_SECONDARY == RR_SECONDARY_PASSIVE ? 0.0 : f[c];
        if (RR_K_STOP > 0.0) y[2 * NQ + c] += stop_force(x[c]);
    }
    rails(m, t, t0, w, wd);
    rr_qdd(y, w, wd, ds + NQ); /* q'' = Bw w + Bwd w' + A^T y, its nonzero terms (model.h) */
}

/* Sub-steps for a step: a power of two resolving the fastest damper rate at the deflection
   rates xd (railride.engine.laws.damper_stiffness and substeps). */
static int substeps(const double *s, const double *xd, double dt) {
#if RR_SECONDARY == RR_SECONDARY_MR
    const double gb = fabs(RR_BW_GAMMA) + fabs(RR_BW_BETA);
    double lam = 0.0;
    int c, n = 1;
    for (c = 0; c < 4; c++) {
        const double az = fmax(fabs(s[2 * NQ + c]), RR_BW_Z_BOUND);
        const double l = RR_BW_N * gb * fabs(xd[c]) * (RR_BW_N == 1.0 ? 1.0 : pow(az, RR_BW_N - 1.0)) + RR_BW_ETA;
        if (l > lam) lam = l;
    }
    while ((lam * RR_SUBSTEP_DT_REF > RR_SUBSTEP_LIMIT * n || lam * dt > 2.0 * RR_SUBSTEP_LIMIT * n) &&
           n < RR_MAX_SUBSTEPS)
        n *= 2;
    return n;
#else
    (void)s;
    (void)xd;
    (void)dt;
    return 1;
#endif
}

/* The commands the dampers see: the inputs, an MR damper's within its voltage range. */
static int inner_loop(const Instance *m) {
    return RR_N_INNER_LOOP ? m->i[RR_VR_INNER_LOOP - RR_VR_INTEGER0] : 0;
}

static void commands(Instance *m, double *v) {
    int c;
    if (inner_loop(m)) { /* the voltages the inner loop set */
        for (c = 0; c < 4; c++) v[c] = m->vc[c];
        return;
    }
    for (c = 0; c < 4; c++) v[c] = RR_N_COMMAND ? m->r[RR_VR_COMMAND + c] : 0.0;
#if RR_SECONDARY == RR_SECONDARY_MR
    for (c = 0; c < 4; c++) {
        if (v[c] < RR_V_MIN || v[c] > RR_V_MAX) {
            if (!m->clipped_said)
                say(m, fmi2Warning, "logStatusWarning",
                    "%s = %g V is outside the damper's range %g..%g V: the coil driver saturates there "
                    "(said once)", RR_NAMES[RR_VR_COMMAND + c], v[c], RR_V_MIN, RR_V_MAX);
            m->clipped_said = 1;
            v[c] = v[c] < RR_V_MIN ? RR_V_MIN : RR_V_MAX;
        }
    }
#endif
}

/* The outputs at the state and time reached (t0: where the held rail inputs were given). */
static void outputs(Instance *m, double t0) {
    double ds[NS], f[4], x[4], xd[4], v[4];
    int i, j, c;
    memset(ds, 0, sizeof ds);
    commands(m, v);
    derivative(m, m->s, m->time, t0, v, ds, f, x, xd);
    for (i = 0; i < NQ; i++) {
        m->r[RR_VR_Q + i] = m->s[i];
        m->r[RR_VR_QD + i] = m->s[NQ + i];
        m->r[RR_VR_QDD + i] = ds[NQ + i];
    }
    for (i = 0; i < 3; i++) {
        double a = 0.0;
        for (j = 0; j < NQ; j++) a += RR_FLOOR[i][j] * ds[NQ + j];
        m->r[RR_VR_FLOOR + i] = a;
    }
    for (c = 0; c < 4; c++) {
        m->r[RR_VR_DEFLECTION + c] = x[c];
        m->r[RR_VR_DEFLECTION_RATE + c] = xd[c];
        m->r[RR_VR_FORCE + c] = f[c];
        if (RR_N_COIL) m->r[RR_VR_COIL + c] = m->s[2 * NQ + 4 + c];
        if (RR_N_HYSTERETIC) m->r[RR_VR_HYSTERETIC + c] = m->s[2 * NQ + c];
        if (RR_N_CLEARANCE) m->r[RR_VR_CLEARANCE + c] = RR_Z_STOP - fabs(x[c]);
    }
}

/* The inner loop's law (parameter inner_loop: 1 tracking, 2 on-off, 3 clipped;
   railride.engine.laws.voltage_law): the voltage from the damper force f on the carbody, the
   demand fd there and the deflection rate xd. */
static double voltage_law(int mode, double B, double G, double f, double fd, double xd) {
    double sgn;
    if (mode == 2) return fd * xd < 0.0 ? RR_V_MAX : RR_V_MIN;
    if (mode == 3) return (fd - f) * f > 0.0 ? RR_V_MAX : RR_V_MIN;
    sgn = f > 0.0 ? 1.0 : (f < 0.0 ? -1.0 : 0.0);
    return fmin(fmax(G * (fd - B * f) * sgn, RR_V_MIN), RR_V_MAX);
}

/* One step dt from step m->step with the held commands v: RK4 in sub-steps, as the engine.
   With the inner loop, v is first set from the demands fd at the step's start, and the first
   stage's coil rate follows it (railride.engine.sample_parts.inner_loop). */
static int step_once(Instance *m, double t0, double *v, const double *fd) {
    double K[4][NS], st[NS], f[4], x[4], xd[4];
    const double dt = m->r[RR_VR_DT], t = m->t_start + m->step * dt;
    int i, sub, n;
    double h;
    memset(K, 0, sizeof K);
    derivative(m, m->s, t, t0, v, K[0], f, x, xd);
    if (fd != NULL) {
        const int mode = m->i[RR_VR_INNER_LOOP - RR_VR_INTEGER0];
        int c;
        for (c = 0; c < 4; c++) {
            v[c] = voltage_law(mode, m->r[RR_VR_INNER_B], m->r[RR_VR_INNER_G], f[c], fd[c], xd[c]);
            K[0][2 * NQ + 4 + c] = -RR_BW_ETA * (m->s[2 * NQ + 4 + c] - v[c]);
        }
    }
    n = substeps(m->s, xd, dt);
    h = dt / n;
    for (sub = 0; sub < n; sub++) {
        const double ts = t + sub * h;
        if (sub > 0) derivative(m, m->s, ts, t0, v, K[0], f, x, xd);
        for (i = 0; i < NS; i++) st[i] = m->s[i] + 0.5 * h * K[0][i];
        derivative(m, st, ts + 0.5 * h, t0, v, K[1], f, x, xd);
        for (i = 0; i < NS; i++) st[i] = m->s[i] + 0.5 * h * K[1][i];
        derivative(m, st, ts + 0.5 * h, t0, v, K[2], f, x, xd);
        for (i = 0; i < NS; i++) st[i] = m->s[i] + h * K[2][i];
        derivative(m, st, ts + h, t0, v, K[3], f, x, xd);
        for (i = 0; i < NS; i++) m->s[i] += h / 6.0 * (K[0][i] + 2.0 * K[1][i] + 2.0 * K[2][i] + K[3][i]);
    }
    m->step += 1;
    m->time = m->t_start + m->step * dt;
    for (i = 0; i < NQ; i++)
        if (!(fabs(m->s[i]) < DIVERGED && fabs(m->s[NQ + i]) < 1e3 * DIVERGED)) return 0;
    for (i = 2 * NQ; i < NS; i++)
        if (!(fabs(m->s[i]) < DIVERGED)) return 0;
    return 1;
}

/* The state at the start: the initial q and q' of the parameters, the dampers' hysteretic
   states at 0 and their coils at the command (as railride.simulate starts them). */
static void start(Instance *m) {
    double v[4];
    int i, c;
    memset(m->s, 0, sizeof m->s);
    for (i = 0; i < NQ; i++) {
        m->s[i] = m->r[RR_VR_INITIAL_Q + i];
        m->s[NQ + i] = m->r[RR_VR_INITIAL_QD + i];
    }
    for (c = 0; c < 4; c++) m->vc[c] = RR_V_MIN; /* a closed loop's coils start at v_min */
    commands(m, v);
    for (c = 0; c < 4; c++)
        if (RR_SECONDARY == RR_SECONDARY_MR) m->s[2 * NQ + 4 + c] = v[c];
    m->step = 0;
    m->time = m->t_start;
    m->node = -1;
    outputs(m, m->t_start);
}

/* Whether the parameters make a run: said in the log where they do not. */
static int parameters_ok(Instance *m) {
    const double dt = m->r[RR_VR_DT];
    int i;
    if (!(dt > 0.0 && isfinite(dt))) {
        say(m, fmi2Error, "logStatusError", "dt = %g s: must be a finite number > 0", dt);
        return 0;
    }
    for (i = 0; i < RR_N_REAL; i++)
        if (RR_CAUSALITY[i] == 'p' && !isfinite(m->r[i])) {
            say(m, fmi2Error, "logStatusError", "%s = %g: must be a finite number", RR_NAMES[i], m->r[i]);
            return 0;
        }
    if (m->i[RR_VR_SCENARIO - RR_VR_INTEGER0] < 0 || m->i[RR_VR_SCENARIO - RR_VR_INTEGER0] > 2 ||
        (m->i[RR_VR_SCENARIO - RR_VR_INTEGER0] == 2 && m->track == NULL)) {
        say(m, fmi2Error, "logStatusError", "scenario = %d: allowed 0 (the rail inputs), 1 (the paper's sine)%s",
            m->i[RR_VR_SCENARIO - RR_VR_INTEGER0], RR_HAS_TRACK ? " or 2 (the random track of the export)" : "");
        return 0;
    }
    if (m->i[RR_VR_SCENARIO - RR_VR_INTEGER0] == 2 && !(m->r[RR_VR_SPEED] > 0.0)) {
        say(m, fmi2Error, "logStatusError", "the random track needs speed > 0 m/s");
        return 0;
    }
    if (inner_loop(m) < 0 || inner_loop(m) > 3) {
        say(m, fmi2Error, "logStatusError",
            "inner_loop = %d: allowed 0 (the coil commands are the inputs), 1 (tracking), 2 (on-off) or 3 (clipped)",
            inner_loop(m));
        return 0;
    }
    if (m->i[RR_VR_SCENARIO - RR_VR_INTEGER0] == 1) {
        if (!(m->r[RR_VR_SPEED] > 0.0) || !(m->r[RR_VR_WAVELENGTH] > 0.0) || !(m->r[RR_VR_AMPLITUDE] >= 0.0) ||
            !(m->r[RR_VR_TAPER] >= 0.0)) {
            say(m, fmi2Error, "logStatusError",
                "the paper's sine needs speed > 0 m/s, wavelength > 0 m, amplitude >= 0 m and taper >= 0");
            return 0;
        }
    }
    return 1;
}

/* -- the FMI 2.0 functions ----------------------------------------------------------------- */
RR_EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
RR_EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

RR_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String categories[]) {
    (void)n;
    (void)categories;
    if (c == NULL) return fmi2Error;
    ((Instance *)c)->logging = on;
    return fmi2OK;
}

static void defaults(Instance *m) {
    int i;
    for (i = 0; i < RR_N_REAL; i++) m->r[i] = RR_START[i];
    for (i = 0; i < RR_N_INTEGER; i++) m->i[i] = RR_START_INTEGER[i];
    m->t_start = 0.0;
    m->clipped_said = 0;
    m->mode = MODE_INSTANTIATED;
}

/* The random track's pieces from resources/track.bin (scenario 2), where the export has one:
   little-endian doubles, the number of pieces n and the spacing, then the left rail's n x 4
   coefficients and the right rail's. Returns whether they were read (or none were needed). */
static int load_track(Instance *m, fmi2String location) {
    char path[4096];
    const char *p = location;
    size_t k = 0;
    FILE *f;
    double head[2];
    long n;
    if (!RR_HAS_TRACK) return 1;
    if (p == NULL) return 0;
    if (strncmp(p, "file://", 7) == 0) p += 7; /* file:///dir, or file://host/dir: the path from / */
    else if (strncmp(p, "file:", 5) == 0) p += 5;
    if (*p != '/' && strchr(p, '/') != NULL) p = strchr(p, '/');
    while (*p && k + 16 < sizeof path) { /* %XX escapes, as a URI writes spaces */
        if (p[0] == '%' && p[1] && p[2]) {
            char hex[3];
            hex[0] = p[1];
            hex[1] = p[2];
            hex[2] = 0;
            path[k++] = (char)strtol(hex, NULL, 16);
            p += 3;
        } else {
            path[k++] = *p++;
        }
    }
    if (k > 0 && path[k - 1] == '/') k--;
    path[k] = 0;
    strcat(path, "/track.bin");
    f = fopen(path, "rb");
    if (f == NULL) return 0;
    if (fread(head, sizeof(double), 2, f) != 2 || !(head[0] >= 1.0) || !(head[1] > 0.0)) {
        fclose(f);
        return 0;
    }
    n = (long)head[0];
    m->track = (double *)malloc(sizeof(double) * 8 * (size_t)n);
    if (m->track == NULL || fread(m->track, sizeof(double), 8 * (size_t)n, f) != 8 * (size_t)n) {
        free(m->track);
        m->track = NULL;
        fclose(f);
        return 0;
    }
    fclose(f);
    m->track_pieces = n;
    m->track_ds = head[1];
    return 1;
}

RR_EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                                        const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                        fmi2Boolean logging) {
    Instance *m;
    (void)visible;
    if (functions == NULL) return NULL;
    if (type != fmi2CoSimulation || guid == NULL || strcmp(guid, RR_GUID) != 0) {
        if (functions->logger != NULL)
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              type != fmi2CoSimulation ? "this FMU is for co-simulation only"
                                                       : "the GUID is not this FMU's: its modelDescription.xml "
                                                         "belongs to another export");
        return NULL;
    }
    m = (Instance *)calloc(1, sizeof(Instance));
    if (m == NULL) return NULL;
    memcpy((void *)&m->cb, functions, sizeof(fmi2CallbackFunctions));
    snprintf(m->name, sizeof m->name, "%s", name != NULL ? name : "");
    m->logging = logging;
    defaults(m);
    if (!load_track(m, location)) {
        if (functions->logger != NULL)
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "the random track (resources/track.bin) could not be read from %s",
                              location != NULL ? location : "(no resource location)");
        free(m);
        return NULL;
    }
    return m;
}

RR_EXPORT void fmi2FreeInstance(fmi2Component c) {
    if (c != NULL) free(((Instance *)c)->track);
    free(c);
}

RR_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance,
                                         fmi2Real start_time, fmi2Boolean stop_defined, fmi2Real stop_time) {
    Instance *m = (Instance *)c;
    (void)tolerance_defined;
    (void)tolerance;
    (void)stop_defined;
    (void)stop_time;
    if (m == NULL || m->mode != MODE_INSTANTIATED) return fmi2Error;
    m->t_start = start_time;
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance *m = (Instance *)c;
    if (m == NULL || m->mode != MODE_INSTANTIATED) return fmi2Error;
    m->mode = MODE_INITIALISATION;
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *m = (Instance *)c;
    if (m == NULL || m->mode != MODE_INITIALISATION) return fmi2Error;
    if (!parameters_ok(m)) {
        m->mode = MODE_ERROR;
        return fmi2Error;
    }
    start(m);
    m->mode = MODE_STEPPING;
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2Terminate(fmi2Component c) {
    if (c == NULL) return fmi2Error;
    ((Instance *)c)->mode = MODE_TERMINATED;
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2Reset(fmi2Component c) {
    if (c == NULL) return fmi2Error;
    defaults((Instance *)c);
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance *m = (Instance *)c;
    size_t k;
    if (m == NULL) return fmi2Error;
    if (m->mode == MODE_INITIALISATION && parameters_ok(m)) start(m); /* the initial unknowns */
    if (m->mode == MODE_STEPPING && m->stale) { /* the outputs that feed through from the inputs */
        outputs(m, m->time);
        m->stale = 0;
    }
    for (k = 0; k < nvr; k++) {
        if (vr[k] >= RR_N_REAL) {
            say(m, fmi2Error, "logStatusError", "no Real variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        value[k] = m->r[vr[k]];
    }
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance *m = (Instance *)c;
    size_t k;
    if (m == NULL) return fmi2Error;
    for (k = 0; k < nvr; k++) {
        const char kind = vr[k] < RR_N_REAL ? RR_CAUSALITY[vr[k]] : 'x';
        if (kind != 'p' && kind != 'i') {
            say(m, fmi2Error, "logStatusError", "value reference %u is not a Real parameter or input", vr[k]);
            return fmi2Error;
        }
        if (kind == 'p' && m->mode != MODE_INSTANTIATED && m->mode != MODE_INITIALISATION) {
            say(m, fmi2Error, "logStatusError", "%s is a fixed parameter: set it before the initialization ends",
                RR_NAMES[vr[k]]);
            return fmi2Error;
        }
        if (!isfinite(value[k])) {
            say(m, fmi2Error, "logStatusError", "%s = %g: must be a finite number", RR_NAMES[vr[k]], value[k]);
            return fmi2Error;
        }
        m->r[vr[k]] = value[k];
        m->stale = 1;
    }
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                    fmi2Integer value[]) {
    Instance *m = (Instance *)c;
    size_t k;
    if (m == NULL) return fmi2Error;
    for (k = 0; k < nvr; k++) {
        if (vr[k] < RR_VR_INTEGER0 || vr[k] >= RR_VR_INTEGER0 + RR_N_INTEGER) return fmi2Error;
        value[k] = m->i[vr[k] - RR_VR_INTEGER0];
    }
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                    const fmi2Integer value[]) {
    Instance *m = (Instance *)c;
    size_t k;
    if (m == NULL) return fmi2Error;
    for (k = 0; k < nvr; k++) {
        if (vr[k] < RR_VR_INTEGER0 || vr[k] >= RR_VR_INTEGER0 + RR_N_INTEGER) return fmi2Error;
        if (m->mode != MODE_INSTANTIATED && m->mode != MODE_INITIALISATION) {
            say(m, fmi2Error, "logStatusError", "%s is a fixed parameter: set it before the initialization ends",
                RR_NAMES[vr[k]]);
            return fmi2Error;
        }
        m->i[vr[k] - RR_VR_INTEGER0] = value[k];
    }
    return fmi2OK;
}

/* no Boolean or String variables */
RR_EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                    fmi2Boolean value[]) {
    (void)c;
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}
RR_EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                    const fmi2Boolean value[]) {
    (void)c;
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}
RR_EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)c;
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}
RR_EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2String value[]) {
    (void)c;
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

/* not provided (modelDescription.xml says so) */
RR_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)c;
    (void)state;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    (void)c;
    (void)state;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)c;
    (void)state;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)c;
    (void)state;
    (void)size;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    (void)c;
    (void)state;
    (void)bytes;
    (void)size;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                             fmi2FMUstate *state) {
    (void)c;
    (void)bytes;
    (void)size;
    (void)state;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                                  const fmi2ValueReference z[], size_t nz, const fmi2Real du[],
                                                  fmi2Real dz[]) {
    (void)c;
    (void)u;
    (void)nu;
    (void)z;
    (void)nz;
    (void)du;
    (void)dz;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                 const fmi2Integer order[], const fmi2Real value[]) {
    (void)c;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                  const fmi2Integer order[], fmi2Real value[]) {
    (void)c;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return fmi2Error;
}
RR_EXPORT fmi2Status fmi2CancelStep(fmi2Component c) {
    (void)c;
    return fmi2Error;
}

RR_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real now, fmi2Real size, fmi2Boolean no_prior) {
    Instance *m = (Instance *)c;
    double v[4], fd[4], dt, t0, steps;
    long n, k;
    int j;
    (void)no_prior;
    if (m == NULL) return fmi2Error;
    if (m->mode != MODE_STEPPING) {
        say(m, fmi2Error, "logStatusError", "fmi2DoStep: the FMU is not initialized, or stopped after an error");
        return fmi2Error;
    }
    dt = m->r[RR_VR_DT];
    steps = size / dt;
    n = (long)floor(steps + 0.5);
    if (!(size > 0.0) || n < 1 || fabs(n - steps) > 1e-6 * steps) {
        say(m, fmi2Error, "logStatusError",
            "the communication step %g s is not a whole multiple of the FMU's step dt = %g s: use a multiple, "
            "or export with another dt", size, dt);
        return fmi2Error;
    }
    if (fabs(now - m->time) > 1e-9 * fmax(1.0, fabs(now))) {
        say(m, fmi2Error, "logStatusError", "fmi2DoStep from t = %g s, but the FMU stands at t = %g s", now,
            m->time);
        return fmi2Error;
    }
    t0 = m->time;
    commands(m, v);
    for (j = 0; j < 4; j++) fd[j] = RR_N_FORCE_DEMAND ? m->r[RR_VR_FORCE_DEMAND + j] : 0.0;
    for (k = 0; k < n; k++) {
        if (!step_once(m, t0, v, inner_loop(m) ? fd : NULL)) {
            say(m, fmi2Error, "logStatusError",
                "the vehicle diverged at t = %g s: a response left +-%g (m or rad) or stopped being finite; "
                "check the inputs and parameters, or export with a smaller dt", m->time, DIVERGED);
            m->mode = MODE_ERROR;
            return fmi2Error;
        }
    }
    for (j = 0; j < 4; j++) m->vc[j] = v[j];
    outputs(m, t0);
    m->stale = 0;
    return fmi2OK;
}

RR_EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)c;
    (void)s;
    (void)value;
    return fmi2Discard;
}
RR_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Instance *m = (Instance *)c;
    if (m == NULL || s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = m->time;
    return fmi2OK;
}
RR_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)c;
    (void)s;
    (void)value;
    return fmi2Discard;
}
RR_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Instance *m = (Instance *)c;
    if (m == NULL || s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;
    return fmi2OK;
}
RR_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)c;
    (void)s;
    (void)value;
    return fmi2Discard;
}
