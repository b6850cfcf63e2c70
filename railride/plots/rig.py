"""The damper rig (`railride.run.rig`): hysteresis cycles and force tracking."""

from __future__ import annotations

import math

from railride.errors import InputError
from railride.analysis.labels import damper_model_name
from railride.plots._style import PAGE_WIDTH, frame_window, given_axes, new_figure, save_to, set_title, styled


def _expect(value, name: str, kind: str, needs: str):
    """``value`` has the attribute ``needs`` of a rig's ``kind`` (plots import no result module)."""
    if not hasattr(value, "dataset") or not hasattr(value, needs):
        raise InputError(f"{name}: expected a railride.run.rig.{kind}, got {type(value).__name__}")


@styled
def plot_hysteresis(cycles, path=None, *, title: str | None = None, ax=None):
    """Force-displacement and force-velocity loops of the `railride.run.rig.Cycles` of
    `railride.run.rig.cycles`: the steady-state (last) cycle at each voltage, one line per voltage,
    force in kN (tension +), extension in mm, extension rate in m/s.

    ``ax``: two Axes to draw in (no title then), or None for a new figure titled ``title``
    (default: the damper, the motion and the cycle shown, as `railride damper --out` has it).
    Saved at ``path`` when given (format from its suffix, else PNG; atomically). Returns the
    `Figure`.
    """
    from matplotlib import colormaps

    _expect(cycles, "cycles", "Cycles", "n_cycles")
    ds = cycles.dataset
    missing = [c for c in ("x", "xd", "F") if c not in ds.variables]
    if missing or "voltage" not in ds.dims:
        raise InputError("expected the result of railride.run.rig.cycles (dims voltage, time; x, xd, F)")
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 3.2))
        ax_x, ax_v = fig.subplots(1, 2, sharey=True)
    else:
        ax_x, ax_v = given_axes(ax, 2, "force against displacement, against velocity")
        fig = ax_x.figure
    volts = [float(v) for v in ds["voltage"].values]
    cmap = colormaps["viridis"]
    for i, v in enumerate(volts):
        cyc = ds.isel(voltage=i)
        colour = cmap(0.85 * i / max(1, len(volts) - 1))
        force = cyc["F"].values / 1e3
        ax_x.plot(cyc["x"].values * 1e3, force, color=colour, label=f"{v:g} V")
        ax_v.plot(cyc["xd"].values, force, color=colour, label=f"{v:g} V")
    ax_x.set_xlabel("extension x (mm)")
    ax_v.set_xlabel("extension rate x' (m/s)")
    ax_x.set_ylabel("damper force F (kN, tension +)")
    ax_x.set_title("force - displacement")
    ax_v.set_title("force - velocity")
    for a in (ax_x, ax_v):
        a.axhline(0.0, color="0.6", linewidth=0.5)
        a.axvline(0.0, color="0.6", linewidth=0.5)
    ax_v.legend(title="command voltage", loc="upper left")
    if ax is None:
        set_title(fig, _cycles_title(cycles) if title is None else title)
    save_to(fig, path)
    return fig


def _damper_words(damper, ds) -> str:
    """ "railway damper (bouc-wen model)" for a preset, "bouc-wen damper" for another model."""
    model = getattr(damper, "model", None) or damper_model_name(ds)
    preset = damper.to_dict().get("preset") if hasattr(damper, "to_dict") else None
    if preset:
        return f"{preset} damper ({model} model)" if model else f"{preset} damper"
    return f"{model} damper" if model else "damper"


def _cycles_title(cycles) -> str:
    """The damper, the motion and the cycle shown: "railway damper (bouc-wen model), x = 10 mm
    sin(2 pi 1 Hz t), cycle 4 of 4"."""
    parts = [_damper_words(cycles.damper, cycles.dataset)]
    motion = cycles.motion
    if motion is not None:
        parts.append(f"x = {motion.amplitude * 1e3:g} mm sin(2 pi {motion.frequency:g} Hz t)")
    n = getattr(cycles, "n_cycles", None)
    parts.append(f"cycle {n} of {n}" if n else "steady-state cycle")
    return ", ".join(parts)


@styled
def plot_tracking(tracking, path=None, *, title: str | None = None, ax=None):
    """Force tracking of `railride.run.rig.track` (a `railride.run.rig.Tracking`): top, the desired and
    the actual damper force (kN, tension +) against time; bottom, the command voltage v and the
    coil voltage u (V). The first cycle, left out of the metrics (start-up), is shaded, and the
    force axis fits the forces after it.

    ``ax``: two Axes to draw in (no title then), or None for a new figure titled ``title``
    (default: the demand, the damper, the gains and the error, as `railride tracking --out` has
    it). Saved at ``path`` when given (format from its suffix, else PNG; atomically). Returns
    the `Figure`.
    """
    _expect(tracking, "tracking", "Tracking", "desired")
    ds = tracking.dataset
    missing = [c for c in ("F", "desired_force", "v", "u") if c not in ds.variables]
    if missing:
        raise InputError(f"expected the result of railride.run.rig.track; missing {', '.join(missing)}")
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 4.6))
        ax_f, ax_v = fig.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    else:
        ax_f, ax_v = given_axes(ax, 2, "forces, voltages")
        fig = ax_f.figure
    time = ds["time"].values
    desired, actual = ds["desired_force"].values / 1e3, ds["F"].values / 1e3
    ax_f.plot(time, desired, color="0.15", linestyle="--", label="desired")
    ax_f.plot(time, actual, color="tab:red", label="actual")
    ax_f.set_ylabel("damper force (kN, tension +)")
    ax_f.legend(loc="upper right", ncols=2)
    ax_v.plot(time, ds["v"].values, color="tab:blue", linewidth=0.8, label="command v")
    ax_v.plot(time, ds["u"].values, color="tab:orange", label="coil u")
    ax_v.set_ylabel("voltage (V)")
    ax_v.set_xlabel("time (s)")
    ax_v.legend(loc="upper right", ncols=2)
    window = tracking.window
    start_up = frame_window([ax_f], time, [desired, actual], window)
    frame_window([ax_v], time, [], window)  # shaded; the voltages keep the damper's range
    ax_v.set_xlim(time[0], time[-1])
    if ax is None:
        if title is None:
            title = _tracking_title(tracking)
        if start_up:
            title += "\n(shaded: start-up, left out of the metrics)"
        set_title(fig, title)
    save_to(fig, path)
    return fig


def _tracking_title(tracking) -> str:
    """The demand, the damper, the gains and the error: "sine demand 10 kN at 1 Hz, railway
    damper, B = 1, G = 0.00115 V/N: normalised RMS error 0.202"."""
    damper = _damper_words(tracking.damper, tracking.dataset).split(" (")[0]
    head = (
        f"{tracking.desired} demand {tracking.amplitude / 1e3:g} kN at {tracking.frequency:g} Hz, "
        f"{damper}, B = {tracking.B:g}, G = {tracking.G:.3g} V/N"
    )
    error = tracking.metrics().normalised_rms_error
    return head + (f": normalised RMS error {error:.3f}" if math.isfinite(error) else "")
