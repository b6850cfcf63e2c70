"""Result folders: every file railride writes, all or nothing.

* `write_folder` is the all-or-nothing folder writer behind the ``write_*`` functions;
  `check_out_dir` rejects an output location that cannot be a folder before any work is done.
* `write_netcdf` writes a Dataset as netCDF3 (`netcdf_ready`); `json_text` is the strict JSON
  of the documents.
* One ``write_*`` function per result: `write_outputs` (a ride), `write_damper_outputs` and
  `write_tracking_outputs` (the damper rig), `write_compare_outputs` (a controller
  comparison), `write_tune_outputs` (a tuning study), `write_sweep_outputs` (a sweep),
  `write_frf_outputs` (frequency responses) and `write_pareto_outputs` (the Pareto view), each
  writing the files of its ``*_FILES`` tuple: tables from `railride.output.tables`, analysis from
  `railride.analysis.spectra`, figures from `railride.plots`. A figure is written once per format of
  its ``figures`` (`railride.plots.FigureOptions`: PNG at 120 dpi unless asked otherwise), so
  ``pitch.png`` in a tuple stands for ``pitch.pdf`` and ``pitch.svg`` too (`figure_files`).
"""

from __future__ import annotations

import glob
import json
import os
import secrets
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from railride import validation
from railride.errors import InputError
from railride.analysis.spectra import PSD_SEGMENT_S, comparison_psd
from railride.analysis.labels import CARBODY_RESPONSES, psd_title
from railride.plots import FigureOptions, save_figure
from railride.plots.comparison import (
    plot_comparison_damper_forces,
    plot_comparison_hysteresis,
    plot_comparison_psd,
    plot_comparison_response,
    plot_comparison_voltages,
)
from railride.plots.frf import plot_frf
from railride.plots.pareto import pareto_caption, plot_pareto
from railride.plots.ride import plot_body_responses
from railride.plots.rig import plot_hysteresis, plot_tracking
from railride.plots.sweep import has_comfort, plot_sweep, plot_sweep_comfort, sweep_plot_axis
from railride.plots.tuning import plot_sensitivity, sensitivity_pages, sensitivity_stem
from railride.output.tables import comparison_frame, curves_frame, cycles_frame, modes_frame, to_frame

#: the files `write_outputs` produces, in the order they are written
OUTPUT_FILES = ("ride.nc", "ride.csv", "metrics.json", "body_responses.png")
#: the files `write_damper_outputs` produces, in the order they are written
DAMPER_FILES = ("loops.png", "cycles.csv", "damper.json")
#: the files `write_tracking_outputs` produces, in the order they are written
TRACKING_FILES = ("tracking.png", "tracking.csv", "tracking.json")
#: the files `write_compare_outputs` produces, in the order they are written
COMPARE_FILES = (
    "compare.json",
    "compare.nc",
    "compare.csv",
    "acceleration.png",
    "displacement.png",
    "pitch.png",
    "roll.png",
    "damper_forces.png",
    "damper_hysteresis.png",
    "voltages.png",
    "psd.png",
    "psd.csv",
)
#: the files `write_tune_outputs` produces, in the order they are written; sensitivity.png is
#: followed by sensitivity_2.png, ... where the figure has several pages (`sensitivity_pages`)
TUNE_FILES = ("gains.toml", "sensitivity.png", "curves.csv", "tune.json")
#: the files `write_sweep_outputs` always produces (the run table runs.csv is the library's);
#: ``sweep.png`` is added when one or two axes have several values (`sweep_plot_axis`), and with it
#: ``comfort.png`` when the rows hold the comfort indices (`railride sweep --comfort`)
SWEEP_FILES = ("sweep.json",)
#: the files `write_frf_outputs` produces, in the order they are written
FRF_FILES = ("frf.csv", "frf.json", "frf.png", "modes.csv")
#: the files `write_pareto_outputs` produces, in the order they are written
PARETO_FILES = ("pareto.png", "pareto_caption.txt", "pareto.csv", "pareto.json")


# -- NetCDF and JSON ------------------------------------------------------------------------------
def netcdf_ready(ds: xr.Dataset) -> xr.Dataset:
    """A copy of ``ds`` that scipy's netCDF3 writer accepts without losing data.

    netCDF3 has no 64-bit integers: integer variables (the ``sample`` and ``wheelset``
    coordinates) are stored as int32, which holds them exactly. Text (the JSON records
    ``scenario`` and ``vehicle_params``) is stored as UTF-8 and reads back unchanged.
    """
    out = ds.copy()
    for name, var in ds.variables.items():
        if var.dtype.kind in "iu" and var.dtype != np.int32:
            if var.size and (var.values.min() < np.iinfo(np.int32).min or var.values.max() > np.iinfo(np.int32).max):
                raise InputError(f"{name}: integers beyond int32 cannot be stored in netCDF3")
            out[name] = var.astype(np.int32)
    return out


def write_netcdf(ds: xr.Dataset, path: Path) -> None:
    """Write ``ds`` to ``path`` as netCDF3 (scipy engine, no extra dependency)."""
    netcdf_ready(ds).to_netcdf(path, engine="scipy")


def json_text(doc: dict) -> str:
    """``doc`` as indented strict JSON (NaN or infinity raises ValueError)."""
    return json.dumps(doc, indent=2, allow_nan=False) + "\n"


# -- the output folder ----------------------------------------------------------------------------
def check_out_dir(out_dir, field: str | None = None) -> Path:
    """Reject an output location that cannot be a folder, or where no folder can be made, before
    any work is done. ``field`` (e.g. ``"--out"``) names it in the error: ``--out =
    '/proc/x': ...``; without it, ``output folder /proc/x: ...``."""
    if isinstance(out_dir, str) and not out_dir.strip():
        # Path("") is the current folder: an empty name is a mistake, not a choice of "."
        name = "output folder" if field is None else f"{field} ="
        raise InputError(f'{name} {out_dir!r}: an empty name; give a folder ("." for the current one)')
    out_dir = Path(out_dir)
    name = f"output folder {out_dir}" if field is None else f"{field} = {str(out_dir)!r}"
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{name}: exists and is not a folder; give a folder to write into")
    # write_folder stages beside the folder, then moves the files into it: both places must take
    # new entries
    validation.creatable(out_dir, name)
    if out_dir.is_dir():
        validation.takes_entries(out_dir, name)
    return out_dir


def _move_into(stage: Path, out_dir: Path, names) -> None:
    """Move the staged files ``names`` into an existing ``out_dir``; on failure put everything
    back."""
    backup = stage / ".previous"
    backup.mkdir()
    moved, saved = [], []
    try:
        for name in names:
            target = out_dir / name
            if target.exists() or target.is_symlink():
                os.replace(target, backup / name)
                saved.append(name)
            os.replace(stage / name, target)
            moved.append(name)
    except BaseException:
        for name in moved:
            try:
                os.replace(out_dir / name, stage / name)
            except OSError:
                pass
        for name in saved:
            try:
                os.replace(backup / name, out_dir / name)
            except OSError:
                pass
        raise


def write_folder(out_dir, files) -> list[Path]:
    """Write a set of files into ``out_dir``, all or nothing.

    ``files`` is a sequence of ``(name, write)`` pairs: ``write(path)`` must create the file
    ``path``. Everything is first written, in the given order, into a hidden staging folder
    beside ``out_dir`` (``.NAME.staging-XXXXXXXX``, same parent, so renames are atomic). Only
    when every file exists are they moved in: a missing ``out_dir`` is created by renaming the
    staging folder; in an existing one, files of the same names are replaced (other files stay)
    and restored if a move fails. On any error the staging folder is removed and ``out_dir`` is
    left as it was. Returns the written paths, in the given order.
    """
    files = list(files)
    names = [name for name, _ in files]
    if len(set(names)) != len(names) or any(Path(n).name != n or n.startswith(".") for n in names):
        raise InputError(f"write_folder: file names must be distinct plain names, got {names}")
    given = out_dir = check_out_dir(out_dir)
    if out_dir.is_symlink() and out_dir.is_dir():
        # a link to a folder elsewhere: stage beside the folder itself, on its file system,
        # where the renames work (beside the link they would cross file systems)
        out_dir = Path(os.path.realpath(out_dir))
    parent = out_dir.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    remove_leftovers(out_dir)
    stage = None
    for _ in range(100):
        candidate = parent / f".{out_dir.name}.staging-{secrets.token_hex(4)}"
        try:
            candidate.mkdir()
        except FileExistsError:
            continue
        stage = candidate
        break
    if stage is None:
        raise OSError(f"cannot create a staging folder in {parent}")
    held = _hold(stage)  # marks the staging folder as live for `remove_leftovers`
    try:
        for name, write in files:
            write(stage / name)
            if not (stage / name).is_file():
                raise OSError(f"the writer of {name} created no file")
        if not out_dir.exists():
            try:
                os.rename(stage, out_dir)  # a new folder appears complete, in one step
                stage = None
            except OSError:
                if not out_dir.is_dir():  # not a race with another writer: a real failure
                    raise
        if stage is not None:
            _move_into(stage, out_dir, names)
    finally:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
        os.close(held)
    return [given / name for name in names]


#: a staging folder younger than this is never taken for a leftover (it may be one just made,
#: whose writer is about to lock it)
LEFTOVER_AGE_S = 2.0


def _hold(stage: Path) -> int:
    """A shared lock on the staging folder, held by its writer until it is renamed or removed;
    the system drops it when the writer's process ends, however it ends."""
    import fcntl

    fd = os.open(stage, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_SH)
    return fd


def remove_leftovers(out_dir) -> list[Path]:
    """Remove the staging folders ``.NAME.staging-XXXXXXXX`` beside ``out_dir`` that a killed
    write left (`write_folder`): those no process holds (a live writer keeps a lock on its own)
    and older than `LEFTOVER_AGE_S`. Returns the removed paths."""
    import fcntl
    import time

    out_dir = Path(out_dir)
    parent = out_dir.absolute().parent
    removed = []
    for stage in parent.glob(f".{glob.escape(out_dir.name)}.staging-*"):
        try:
            if not stage.is_dir() or time.time() - stage.stat().st_mtime < LEFTOVER_AGE_S:
                continue
            fd = os.open(stage, os.O_RDONLY)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            continue  # a writer is at work in it
        else:
            shutil.rmtree(stage, ignore_errors=True)
            removed.append(stage)
        finally:
            os.close(fd)
    return removed


def _text(text: str):
    return lambda path: path.write_text(text, encoding="utf-8")


class _Figure:
    """A figure to write: ``draw()`` makes it; `_entries` turns it into one file per format.
    Called with a path, it writes the PNG file alone (at 120 dpi)."""

    def __init__(self, draw):
        self.draw = draw

    def __call__(self, path: Path) -> None:
        save_figure(self.draw(), path, "png")


def _png(draw) -> _Figure:
    """The figure ``draw()`` returns, in a writers' table under its ``.png`` name."""
    return _Figure(draw)


def figure_files(stem: str, draw, figures: FigureOptions | None = None) -> list:
    """The ``(name, write)`` pairs of `write_folder` for the figure ``draw()`` returns, one per
    format of ``figures`` (default PNG at 120 dpi): "pitch.png", "pitch.pdf". The figure is
    drawn once, when the first file is written, and let go after the last."""
    figures = FigureOptions() if figures is None else figures
    made: dict = {}
    last = figures.figure_formats[-1]

    def writer(fmt: str):
        def write(path: Path) -> None:
            if "figure" not in made:
                made["figure"] = draw()
            try:
                save_figure(made["figure"], path, fmt, figures.dpi)
            finally:
                if fmt == last:
                    made.clear()

        return write

    return [(f"{stem}.{fmt}", writer(fmt)) for fmt in figures.figure_formats]


def _entries(names, writers: dict, figures: FigureOptions | None) -> list:
    """The ``(name, write)`` pairs of the files ``names`` from ``writers``, each figure
    (`_png`, listed as ``stem.png``) once per format of ``figures``."""
    out: list = []
    for name in names:
        write = writers[name]
        if isinstance(write, _Figure):
            out += figure_files(name.rsplit(".", 1)[0], write.draw, figures)
        else:
            out.append((name, write))
    return out


def _csv(frame: pd.DataFrame, index: bool = False):
    return lambda path: frame.to_csv(path, index=index)


def _expect(value, name: str, kind: str, needs: tuple[str, ...]) -> None:
    """ValueError unless ``value`` has the attributes ``needs`` of a ``kind`` (a result class's
    path): the writers read what they are given and import no result module (those sit above)."""
    if not all(hasattr(value, a) for a in needs):
        raise InputError(f"{name}: expected a {kind}, got {type(value).__name__}")


# -- one writer per result ------------------------------------------------------------------------
#: the file formats of time histories: NetCDF (the Dataset), CSV (one table) and MATLAB (`write_mat`)
HISTORY_FORMATS = ("nc", "csv", "mat")


def history_formats(value=("nc", "csv")) -> tuple:
    """``value`` (a sequence, or one comma-separated text, of `HISTORY_FORMATS`) as a tuple in
    the given order without repeats; ValueError naming ``history_formats`` otherwise."""
    items = value.split(",") if isinstance(value, str) else list(value)
    names = [i.strip().lower() if isinstance(i, str) else i for i in items]
    bad = [n for n in names if n not in HISTORY_FORMATS]
    if bad or not names:
        what = f"{bad[0]!r} is not a format" if bad else "no format given"
        raise InputError(f"history_formats = {value!r}: {what}; allowed one or more of {', '.join(HISTORY_FORMATS)}")
    return tuple(dict.fromkeys(names))


def _history_names(names, stem: str, formats) -> list:
    """``names`` with the time-history files stem.nc and stem.csv replaced by one per format."""
    formats = history_formats(formats)
    out = []
    for name in names:
        if name == f"{stem}.nc":
            out += [f"{stem}.{fmt}" for fmt in formats]
        elif name != f"{stem}.csv":
            out.append(name)
    return out


def write_outputs(
    result, out_dir, metrics_doc: dict, *, figures: FigureOptions | None = None, histories=("nc", "csv")
) -> list[Path]:
    """Write the files of a run, a `railride.run.ride.RideResult`, into ``out_dir``, all or
    nothing (`write_folder`): ``ride.nc`` (its Dataset as NetCDF, see `netcdf_ready`),
    ``ride.csv`` (`railride.output.tables.to_frame`), ``metrics.json`` (``metrics_doc`` as indented
    JSON; NaN or infinity is refused) and ``body_responses.png``
    (`railride.plots.ride.plot_body_responses`, over the metric window of
    ``metrics_doc["settings"]["window_s"]``; in each format of ``figures``). ``histories``:
    the time-history formats (`HISTORY_FORMATS`; ``mat`` writes ride.mat, `write_mat`) in
    place of ride.nc and ride.csv. Returns the written paths."""
    _expect(result, "result", "railride.run.ride.RideResult", ("dataset", "metrics"))
    ds = result.dataset
    if "vehicle" in metrics_doc:  # the vehicle record (name, load, values) as an attribute of ride.nc
        ds = ds.assign_attrs(vehicle=json.dumps(metrics_doc["vehicle"]))
    text = json_text(metrics_doc)  # refuse NaN before any file is written
    window = _window(metrics_doc)
    writers = {
        "ride.nc": lambda path: write_netcdf(ds, path),
        "ride.csv": lambda path: to_frame(ds).to_csv(path),
        "ride.mat": lambda path: write_mat(ds, path),
        "metrics.json": _text(text),
        "body_responses.png": _png(lambda: plot_body_responses(ds, window=window)),
    }
    return write_folder(out_dir, _entries(_history_names(OUTPUT_FILES, "ride", histories), writers, figures))


def _window(doc) -> tuple | None:
    """The metric window ``doc["settings"]["window_s"]`` of a result document, if it holds
    one."""
    settings = doc.get("settings") if isinstance(doc, dict) else None
    window = settings.get("window_s") if isinstance(settings, dict) else None
    if isinstance(window, (list, tuple)) and len(window) == 2:
        return (float(window[0]), float(window[1]))
    return None


def write_damper_outputs(
    cycles, out_dir, doc: dict, *, title: str | None = None, figures: FigureOptions | None = None
) -> list[Path]:
    """Write the `railride.run.rig.Cycles` of `railride.run.rig.cycles` into ``out_dir``, all or
    nothing: ``loops.png`` (`plot_hysteresis`), ``cycles.csv`` (`cycles_frame`) and
    ``damper.json`` (``doc`` as indented strict JSON). Returns the written paths."""
    text = json_text(doc)
    writers = {
        "loops.png": _png(lambda: plot_hysteresis(cycles, title=title)),
        "cycles.csv": lambda path: cycles_frame(cycles.dataset).to_csv(path, index=False),
        "damper.json": _text(text),
    }
    return write_folder(out_dir, _entries(DAMPER_FILES, writers, figures))


def write_tracking_outputs(
    tracking, out_dir, doc: dict, *, title: str | None = None, figures: FigureOptions | None = None
) -> list[Path]:
    """Write a force-tracking run of `railride.run.rig.track` (a `railride.run.rig.Tracking`) into
    ``out_dir``, all or nothing: ``tracking.png`` (`plot_tracking`), ``tracking.csv``
    (`to_frame` of its Dataset: time, the rig channels and ``desired_force``) and
    ``tracking.json`` (``doc``). Returns the paths."""
    text = json_text(doc)
    writers = {
        "tracking.png": _png(lambda: plot_tracking(tracking, title=title)),
        "tracking.csv": lambda path: to_frame(tracking.dataset).to_csv(path),
        "tracking.json": _text(text),
    }
    return write_folder(out_dir, _entries(TRACKING_FILES, writers, figures))


def write_compare_outputs(
    comparison, out_dir, doc: dict, *, figures: FigureOptions | None = None, histories=("nc", "csv")
) -> list[Path]:
    """Write a `railride.studies.comparison.Comparison` into ``out_dir``, all or nothing
    (`write_folder`): ``compare.json`` (``doc``, the ``Comparison.to_dict()`` document, strict
    JSON), ``compare.nc`` (``combined()`` as NetCDF, see `netcdf_ready`), ``compare.csv``
    (`comparison_frame`), ``acceleration.png``, ``displacement.png``, ``pitch.png``,
    ``roll.png`` (`plot_comparison_response`), ``damper_forces.png``
    (`plot_comparison_damper_forces`), ``damper_hysteresis.png`` (`plot_comparison_hysteresis`),
    ``voltages.png`` (`plot_comparison_voltages`), and the
    acceleration spectra over the metric window ``doc["settings"]["window_s"]`` (None: the
    whole run): ``psd.png`` (`plot_comparison_psd`) and ``psd.csv``
    (`railride.analysis.spectra.comparison_psd`). ``histories``: the time-history formats
    (`HISTORY_FORMATS`; ``mat`` writes compare.mat, `write_mat`) in place of compare.nc and
    compare.csv. Returns the written paths."""
    _expect(comparison, "comparison", "railride.studies.comparison.Comparison", ("combined",))
    text = json_text(doc)
    ds = comparison.combined()
    given = (doc or {}).get("settings")
    settings = given if isinstance(given, dict) else {}
    window = settings.get("window_s")
    psd = comparison_psd(ds, window)
    title = psd_title(ds, window, PSD_SEGMENT_S)
    writers = {
        "psd.png": _png(lambda: plot_comparison_psd(psd, title=title)),
        "psd.csv": _csv(psd),
        "compare.json": _text(text),
        "compare.nc": lambda path: write_netcdf(ds, path),
        "compare.csv": lambda path: comparison_frame(ds).to_csv(path, index=False),
        "compare.mat": lambda path: write_mat(ds, path),
        "damper_forces.png": _png(lambda: plot_comparison_damper_forces(comparison)),
        "damper_hysteresis.png": _png(lambda: plot_comparison_hysteresis(comparison)),
        "voltages.png": _png(lambda: plot_comparison_voltages(comparison)),
    }
    for response in CARBODY_RESPONSES:
        writers[f"{response}.png"] = (lambda r: _png(lambda: plot_comparison_response(comparison, r)))(response)
    return write_folder(out_dir, _entries(_history_names(COMPARE_FILES, "compare", histories), writers, figures))


def write_tune_outputs(
    curves, out_dir, doc: dict, gains_text: str, *, title: str | None = None, figures: FigureOptions | None = None
) -> list[Path]:
    """Write the results of a tuning study into ``out_dir``, all or nothing (`write_folder`;
    other files there, such as the run table ``runs.csv``, stay): ``gains.toml``
    (``gains_text``, a gains file), ``sensitivity.png`` (`plot_sensitivity` of ``curves``,
    ``TuneResult.curves``; sensitivity_2.png, ... for its further pages), ``curves.csv``
    (`curves_frame`) and ``tune.json`` (``doc`` as indented strict JSON). Returns the written paths."""
    text = json_text(doc)  # refuse NaN before any file is written
    curves = list(curves)
    frame = curves_frame(curves)
    pages = [f"{sensitivity_stem(k + 1)}.png" for k in range(max(1, len(sensitivity_pages(curves))))]
    writers = {"gains.toml": _text(gains_text), "curves.csv": _csv(frame), "tune.json": _text(text)}
    for k, name in enumerate(pages, 1):
        writers[name] = _png(lambda k=k: plot_sensitivity(curves, title=title, page=k))
    names = [n for name in TUNE_FILES for n in (pages if name == "sensitivity.png" else [name])]
    return write_folder(out_dir, _entries(names, writers, figures))


def write_sweep_outputs(
    result, out_dir, doc: dict | None = None, *, figures: FigureOptions | None = None
) -> list[Path]:
    """Write a `railride.studies.sweep.SweepResult` into ``out_dir`` beside the run table ``runs.csv``
    that `railride.studies.sweep.run_cases` keeps there, all or nothing: ``sweep.json`` (``doc``,
    default ``result.to_dict()``) and, when one or two axes have several values
    (`sweep_plot_axis`), ``sweep.png`` (`plot_sweep`) and, if the rows hold the comfort indices,
    ``comfort.png`` (`plot_sweep_comfort`). Returns the written paths."""
    _expect(result, "result", "railride.studies.sweep.SweepResult", ("grid", "frame"))
    text = json_text(result.to_dict() if doc is None else doc)  # refuse NaN before any file is written
    files = [("sweep.json", _text(text))]
    axis = sweep_plot_axis(result)
    if axis is not None:
        files += figure_files("sweep", lambda: plot_sweep(result, axis=axis), figures)
        if has_comfort(result):
            files += figure_files("comfort", lambda: plot_sweep_comfort(result, axis=axis), figures)
    return write_folder(out_dir, files)


def write_frf_outputs(
    frame: pd.DataFrame, modes, out_dir, doc: dict, *, title: str | None = None, figures: FigureOptions | None = None
) -> list[Path]:
    """Write the frequency responses of `railride frf` into ``out_dir``, all or nothing:
    ``frf.csv`` (``frame``, `railride.analysis.spectra.frf_frame`), ``frf.json`` (``doc``, strict
    JSON), ``frf.png`` (`plot_frf`) and ``modes.csv`` (`modes_frame` of ``modes``, the records
    ``Mode.to_dict()`` of `Vehicle.modes()`). Returns the written paths."""
    text = json_text(doc)
    table = modes_frame(modes)
    writers = {
        "frf.csv": _csv(frame),
        "frf.json": _text(text),
        "frf.png": _png(lambda: plot_frf(frame, table, title=title)),
        "modes.csv": _csv(table),
    }
    return write_folder(out_dir, _entries(FRF_FILES, writers, figures))


def write_pareto_outputs(result, out_dir, *, figures: FigureOptions | None = None) -> list[Path]:
    """Write a `railride.studies.pareto.ParetoResult` into ``out_dir``, all or nothing (other files,
    such as a run table, stay): ``pareto.png`` (`plot_pareto`), ``pareto_caption.txt`` (its
    caption, `pareto_caption`, with the in-sample note), ``pareto.csv``
    (``to_pandas()``) and ``pareto.json`` (``to_dict()``). Returns the paths."""
    text = json_text(result.to_dict())  # refuse NaN before any file is written
    frame = result.to_pandas()
    writers = {
        "pareto.png": _png(lambda: plot_pareto(result)),
        "pareto_caption.txt": _text(pareto_caption(result) + "\n"),
        "pareto.csv": _csv(frame),
        "pareto.json": _text(text),
    }
    return write_folder(out_dir, _entries(PARETO_FILES, writers, figures))


#: the files `LeagueTable.save` writes
LEAGUE_FILES = ("league.json", "league.csv", "league.png", "league_comfort.png")


def write_league_outputs(table, out_dir, *, figures: FigureOptions | None = None) -> list[Path]:
    """Write a `railride.studies.league.LeagueTable` into ``out_dir``, all or nothing: ``league.json``
    (``to_dict()``), ``league.csv`` (one row per case and controller), ``league.png``
    (`plot_league`) and ``league_comfort.png`` (`plot_league_comfort`, N_MV against speed)."""
    from railride.plots.league import plot_league, plot_league_comfort

    text = json_text(table.to_dict())
    writers = {
        "league.json": _text(text),
        "league.csv": _csv(table.to_pandas()),
        "league.png": _png(lambda: plot_league(table)),
        "league_comfort.png": _png(lambda: plot_league_comfort(table)),
    }
    return write_folder(out_dir, _entries(LEAGUE_FILES, writers, figures))


#: the files `StudyResult.save` writes, in this order
STUDY_FILES = ("study.json", "study_summary.csv", "study_runs.csv", "study.png")


def write_study_outputs(
    result, out_dir, *, figures: FigureOptions | None = None, extra: dict | None = None
) -> list[Path]:
    """Write a `railride.studies.study.StudyResult` into ``out_dir``, all or nothing: ``study.json``
    (``to_dict()``, then the entries of ``extra``), ``study_summary.csv`` (``to_pandas()``),
    ``study_runs.csv`` (one row per run, ``cases``) and ``study.png`` (``plot()``); other files
    (the run table) stay."""
    from railride.plots.study import plot_study

    text = json_text({**result.to_dict(), **(extra or {})})
    writers = {
        "study.json": _text(text),
        "study_summary.csv": _csv(result.to_pandas()),
        "study_runs.csv": _csv(result.cases),
        "study.png": _png(lambda: plot_study(result)),
    }
    return write_folder(out_dir, _entries(STUDY_FILES, writers, figures))


#: the files `write_design_outputs` produces, in the order they are written
DESIGN_FILES = ("design.json", "design.csv", "design_runs.csv", "gains.toml", "design.png", "design_costs.png")


def write_design_outputs(result, out_dir, doc: dict, gains_text: str, *, figures: FigureOptions | None = None):
    """Write a `railride.studies.design_result.DesignResult` into ``out_dir``, all or nothing:
    ``design.json`` (``doc``), ``design.csv`` (``to_pandas()``), ``design_runs.csv`` (the
    held-out runs), ``gains.toml`` (``gains_text``), ``design.png`` (`plot_design`) and
    ``design_costs.png`` (`plot_design_costs`); other files (the run table) stay. Returns the
    written paths."""
    from railride.plots.design import plot_design, plot_design_costs

    _expect(result, "result", "railride.studies.design_result.DesignResult", ("summary", "runs", "ranking"))
    text = json_text(doc)  # refuse NaN before any file is written
    writers = {
        "design.json": _text(text),
        "design.csv": _csv(result.to_pandas()),
        "design_runs.csv": _csv(result.runs),
        "gains.toml": _text(gains_text),
        "design.png": _png(lambda: plot_design(result)),
        "design_costs.png": _png(lambda: plot_design_costs(result)),
    }
    return write_folder(out_dir, _entries(DESIGN_FILES, writers, figures))


#: the files `RideSpectrum.save` writes, in this order
RIDE_SPECTRUM_FILES = ("ride_spectrum.json", "ride_spectrum.csv", "ride_spectrum_psd.csv", "ride_spectrum.png")


def write_ride_spectrum_outputs(result, out_dir, *, figures: FigureOptions | None = None) -> list[Path]:
    """Write a `railride.frequency.ride_spectrum.RideSpectrum` into ``out_dir``, all or nothing:
    ``ride_spectrum.json`` (``to_dict()``), ``ride_spectrum.csv`` (``to_pandas()``: RMS and
    weighted RMS), ``ride_spectrum_psd.csv`` (the PSDs, one row per suspension and frequency)
    and ``ride_spectrum.png`` (``plot()``)."""
    from railride.plots.ride_spectrum import plot_ride_spectrum

    text = json_text(result.to_dict())
    psd = result.psd.to_dataframe().reset_index()
    writers = {
        "ride_spectrum.json": _text(text),
        "ride_spectrum.csv": _csv(result.to_pandas()),
        "ride_spectrum_psd.csv": _csv(psd),
        "ride_spectrum.png": _png(lambda: plot_ride_spectrum(result)),
    }
    return write_folder(out_dir, _entries(RIDE_SPECTRUM_FILES, writers, figures))


#: the suffixes of `write_model`'s files
MODEL_SUFFIXES = (".mat", ".json")


def check_model_path(path, field: str = "path") -> Path:
    """``path`` as a Path if `write_model` can write there: a file name ending in .mat or
    .json, not a folder, at a place where a file can be made. InputError naming ``field``
    otherwise."""
    path = Path(path)
    name = f"{field} = {str(path)!r}"
    if path.suffix.lower() not in MODEL_SUFFIXES:
        raise InputError(f"{name}: the file name must end in .mat or .json")
    if path.is_dir():
        raise InputError(f"{name}: a folder; give the name of the file to write, e.g. model.mat")
    validation.creatable(path, name)
    return path


def write_model(model, path) -> Path:
    """Write a `railride.frequency.linear.LinearModel` to ``path``, atomically: a MATLAB file for a
    ``.mat`` suffix (`LinearModel.to_mat`), else its JSON document (``to_dict()``)."""
    from railride._io import atomic_write

    path = check_model_path(path)
    if path.suffix.lower() == ".mat":
        model.to_mat(path)
    else:
        text = json_text(model.to_dict())
        atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return path


def write_mat(ds: xr.Dataset, path) -> Path:
    """Write the time histories ``ds`` (a run's or a comparison's Dataset) to ``path`` as a
    MATLAB file (scipy.io, format 5, compressed), atomically. Each variable keeps its name, with
    time as the first dimension (a column per corner, wheelset or rail); the coordinates are
    variables too (text ones as cell arrays), ``units`` is a struct of every variable's unit,
    ``dims`` a struct of its dimension names, and ``attributes`` holds the Dataset's attributes
    (versions, step, suspension, sign convention), text records (scenario, parameters) as
    their JSON text."""
    from scipy.io import savemat

    from railride._io import atomic_write

    content: dict = {}
    units: dict = {}
    dims: dict = {}
    for name in [*ds.coords, *ds.data_vars]:
        var = ds[name]
        order = [d for d in ("time", *var.dims) if d in var.dims]
        order = list(dict.fromkeys(order))
        values = var.transpose(*order).values
        if values.dtype.kind in "UO":
            values = np.array(values.tolist(), dtype=object) if values.ndim else str(values)
        content[str(name)] = values
        units[str(name)] = str(var.attrs.get("units", ""))
        dims[str(name)] = np.array(order, dtype=object)
    content["units"] = units
    content["dims"] = dims
    content["attributes"] = {str(k): str(v) for k, v in ds.attrs.items()}
    atomic_write(Path(path), lambda tmp: savemat(tmp, content, do_compression=True, long_field_names=True))
    return Path(path)
