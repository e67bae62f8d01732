"""mtec: machine-tool error measurement, identification, modelling and compensation.

The Python face of the mtec Rust workspace: each function runs the library code the `mtec`
command runs (in-process, no subprocess), with numpy arrays in and out. See docs/python.md.

Tabular inputs are a CSV path or a mapping of column name to 1-D array (a dict of numpy
arrays, a pandas DataFrame), validated as the CLI validates files. Errors in the inputs raise
`mtec.InputError` (a ValueError) with `.file`, `.line` and `.column`.
"""

from ._mtec import (
    InputError,
    __version__,
    circular,
    compensate_gcode,
    compensate_gcode_file,
    compensate_table,
    compensate_thermal_offset,
    identify_ballbar,
    identify_lines,
    iso230_2,
    machine_build,
    machine_replay,
    map_eval,
    map_fit,
    run_project,
    sensitivity,
    simulate,
    thermal_cv,
    thermal_fit,
    thermal_predict,
    thermal_select,
    volumetric,
)

__all__ = [
    "InputError",
    "__version__",
    "circular",
    "compensate_gcode",
    "compensate_gcode_file",
    "compensate_table",
    "compensate_thermal_offset",
    "identify_ballbar",
    "identify_lines",
    "iso230_2",
    "machine_build",
    "machine_replay",
    "map_eval",
    "map_fit",
    "run_project",
    "sensitivity",
    "simulate",
    "thermal_cv",
    "thermal_fit",
    "thermal_predict",
    "thermal_select",
    "volumetric",
]
