# TEMPORARY re-exports: removed once every caller imports the new modules
"""The old home of the report layer; its parts now live in `railride.tables`,
`railride.analysis`, `railride.labels`, `railride.plots` and `railride.files`."""

from .analysis import FRF_MAGNITUDES, FRF_PATTERNS, frf_frame, frf_peaks  # noqa: F401
from .files import (  # noqa: F401
    check_out_dir,
    write_compare_outputs,
    write_damper_outputs,
    write_frf_outputs,
    write_outputs,
    write_sweep_outputs,
    write_tracking_outputs,
    write_tune_outputs,
)
from .labels import describe_dampers, describe_scenario  # noqa: F401
from .labels import gain_unit as _gain_unit  # noqa: F401
from .plots.comparison import plot_comparison_response  # noqa: F401
from .plots.ride import plot_body_responses  # noqa: F401
from .plots.rig import plot_hysteresis, plot_tracking  # noqa: F401
from .plots.tuning import plot_sensitivity  # noqa: F401
from .tables import curves_frame, to_frame  # noqa: F401
