"""Type stubs of the mtec module (the functions are implemented in Rust, mtec._mtec)."""

import os
from typing import Any, Literal, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = npt.ArrayLike
#: A CSV file, or its columns: a mapping of column name to 1-D array (dict, pandas.DataFrame).
Columns = Union[PathLike, Mapping[str, ArrayLike]]
FloatArray = npt.NDArray[np.float64]

class InputError(ValueError):
    """An input is wrong; `str(e)` is `file:line:column: message`.

    For arrays passed instead of a CSV file, `file` is `<arrays>`, `line` the 1-based row
    (index + 1) and `column` the 1-based position of the column.
    """

    file: str
    line: Optional[int]
    column: Optional[int]
    message: str

def iso230_2(
    data: Columns,
    *,
    air_temp_c: Optional[float] = None,
    pressure_pa: Optional[float] = None,
    humidity_pct: Optional[float] = None,
    co2_ppm: float = 450.0,
    wavelength_nm: Optional[float] = None,
    air_formula: Literal["ciddor", "edlen", "bonsch-potulski"] = "ciddor",
    laser_n: Optional[float] = None,
    material_temp_c: Optional[float] = None,
    alpha_um_per_m_k: Optional[float] = None,
    standard: Literal["iso230-2:2014", "vdi-3441", "all"] = "iso230-2:2014",
    out: Optional[PathLike] = None,
) -> dict[str, Any]:
    """ISO 230-2:2014 positioning statistics and VDI/DGQ 3441 values of a linear axis."""

def circular(
    run: Columns,
    *,
    radius_mm: Optional[float] = None,
    plane: Optional[Literal["XY", "YZ", "ZX"]] = None,
    feed_mm_min: Optional[float] = None,
    arc_start_deg: Optional[float] = None,
    arc_end_deg: Optional[float] = None,
    threshold_um: float = 0.3,
    out: Optional[PathLike] = None,
) -> dict[str, Any]:
    """ISO 230-4 circular deviation and hysteresis and the ballbar diagnostics of a trace."""

def identify_lines(
    machine: PathLike,
    data: Columns,
    degree: Optional[int] = None,
    errors_out: Optional[PathLike] = None,
    kinematic_model_out: Optional[PathLike] = None,
) -> dict[str, Any]:
    """The error elements of a three-axis machine from laser line measurements (9-line method).

    degree None: chosen per kind of element by cross-validation (the CLI's --degree auto).
    """

def identify_ballbar(setup: PathLike, data: Columns) -> dict[str, Any]:
    """The error motions EXC, EYC, EZC, EAC, EBC of a rotary C axis from ballbar readings."""

@overload
def volumetric(
    machine: PathLike,
    errors: PathLike,
    points: Union[Columns, ArrayLike],
    form: Literal["htm-exact", "htm-first", "poe-exact", "poe-first"] = ...,
    orientation: Literal[False] = ...,
) -> FloatArray: ...
@overload
def volumetric(
    machine: PathLike,
    errors: PathLike,
    points: Union[Columns, ArrayLike],
    form: Literal["htm-exact", "htm-first", "poe-exact", "poe-first"] = ...,
    *,
    orientation: Literal[True],
) -> Tuple[FloatArray, FloatArray]: ...
def thermal_fit(
    data: Columns,
    target: str,
    model: Literal["auto", "mlr", "ridge", "heat-input", "exp-ambient"] = "auto",
    *,
    sensors: Sequence[str] = ...,
    k: Optional[float] = None,
    lag: bool = False,
    block_min: Optional[float] = None,
    max_sensors: Optional[int] = None,
    input: str = "spindle_rpm",
    train: Sequence[str] = ...,
    test: Sequence[str] = ...,
    train_until: Optional[float] = None,
    out: Optional[PathLike] = None,
) -> dict[str, Any]:
    """Fits a thermal error model (`mtec.thermal-model/1`) to a temperature log."""

def thermal_predict(
    model: PathLike, data: Columns, history: Optional[Columns] = None
) -> dict[str, Any]:
    """Predicts the thermal drift (µm) of every row of a log with a model file."""

def thermal_select(
    data: Columns,
    target: str,
    *,
    sensors: Sequence[str] = ...,
    out: Optional[PathLike] = None,
) -> dict[str, Any]:
    """VIF table, ridge trace and the sensors kept (`mtec.thermal-selection/1`)."""

def thermal_cv(
    data: Columns,
    target: str,
    model: Literal["auto", "mlr", "ridge", "heat-input", "exp-ambient"] = "auto",
    *,
    sensors: Sequence[str] = ...,
    k: Optional[float] = None,
    lag: bool = False,
    block_min: Optional[float] = None,
    max_sensors: Optional[int] = None,
    input: str = "spindle_rpm",
    up_sensors: Sequence[str] = ...,
    nut_sensors: Sequence[str] = ...,
    loo: bool = False,
) -> dict[str, Any]:
    """Forward (or, with loo, leave-one-block-out) validation of a thermal model kind."""

def map_fit(
    grid: Columns,
    out: Optional[PathLike] = None,
    outside: Literal["clamp", "extrapolate", "refuse"] = "clamp",
    controller: Literal["none", "fanuc-3d", "linuxcnc"] = "none",
    max_points_per_axis: Optional[int] = None,
) -> dict[str, Any]:
    """A volumetric error map (`mtec.map/1`, trilinear) from a measured grid."""

def map_eval(model: PathLike, points: Union[Columns, ArrayLike]) -> FloatArray:
    """An error model's (N, 3) errors ex, ey, ez (µm) at (N, 3) points x, y, z (mm)."""

def compensate_gcode(
    program: str,
    model: PathLike,
    *,
    state: Optional[PathLike] = None,
    offsets: Optional[PathLike] = None,
    start_position_mm: Optional[Tuple[float, float, float]] = None,
    tolerance_um: float = 0.5,
    max_segment_mm: float = 10.0,
    chord_tolerance_um: float = 0.5,
    max_correction_um: float = 500.0,
    on_unsupported: Literal["refuse", "pass-through-with-warning"] = "refuse",
    default_units: Literal["mm", "inch"] = "mm",
    name: str = "<program>",
) -> Tuple[str, dict[str, Any]]:
    """An NC program rewritten so the machine with the model's errors cuts the programmed path."""

def compensate_gcode_file(
    input: PathLike,
    model: PathLike,
    output: PathLike,
    *,
    state: Optional[PathLike] = None,
    offsets: Optional[PathLike] = None,
    tool_table: Optional[PathLike] = None,
    machine_units: Literal["mm", "inch"] = "mm",
    block_delete: Optional[bool] = None,
    elements: str = "all",
    tolerance_um: float = 0.5,
    max_segment_mm: float = 10.0,
    chord_tolerance_um: float = 0.5,
    max_correction_um: float = 500.0,
    on_unsupported: Literal["refuse", "pass-through-with-warning"] = "refuse",
    default_units: Literal["mm", "inch"] = "mm",
    decimals_mm: Optional[int] = None,
    decimals_inch: Optional[int] = None,
    start_position_mm: Optional[Tuple[float, float, float]] = None,
    check_step_mm: float = 0.5,
    start_rotary_deg: Optional[Tuple[float, float, float]] = None,
    check_step_deg: float = 0.5,
    max_line_chars: int = 251,
    flatten_with: Optional[Literal["rs274"]] = None,
    rs274: Optional[PathLike] = None,
    var_file: Optional[PathLike] = None,
    rs274_timeout_s: Optional[float] = None,
) -> dict[str, Any]:
    """An NC program file compensated as `mtec compensate gcode` does it (every option)."""

def compensate_table(
    format: Literal["linuxcnc", "sinumerik-cec", "sinumerik-lec", "fanuc", "heidenhain", "beckhoff"],
    out: PathLike,
    *,
    model: Optional[PathLike] = None,
    from_iso230_2: Optional[PathLike] = None,
    state: Optional[PathLike] = None,
    axis: Literal["X", "Y", "Z"] = "X",
    output_axis: Optional[Literal["X", "Y", "Z"]] = None,
    range: Optional[Tuple[float, float, float]] = None,
    at: Optional[Tuple[float, float, float]] = None,
    elements: str = "all",
    max_correction_um: float = 500.0,
    comp_type: int = 1,
    table_index: int = 0,
    direction: int = 0,
    max_points: Optional[int] = None,
    reference_mm: float = 0.0,
    reference_number: int = 0,
    magnification: int = 1,
    detection_unit_um: float = 1.0,
    max_increment: int = 127,
    axis_number: Optional[int] = None,
    cma_name: str = "config.cma",
    x_range: Optional[Tuple[float, float, float]] = None,
    y_range: Optional[Tuple[float, float, float]] = None,
    z_range: Optional[Tuple[float, float, float]] = None,
) -> dict[str, Any]:
    """Writes a controller's compensation table from a model or an ISO 230-2 run."""

def compensate_thermal_offset(
    model: PathLike,
    temps: Columns,
    format: Literal["g10", "fanuc", "fanuc-macro", "sinumerik", "sinumerik-sd"] = "g10",
    *,
    axis: Literal["X", "Y", "Z"] = "Z",
    offset: int = 1,
    base_mm: Optional[float] = None,
    at_mm: Optional[float] = None,
    position_origin_mm: float = 0.0,
    zeroed_at_min: Optional[float] = None,
    starts_at_rest: bool = False,
    outside: Literal["refuse", "fade"] = "refuse",
    max_correction_um: float = 500.0,
    training: Optional[PathLike] = None,
    sign: Optional[float] = None,
    axis_number: Optional[int] = None,
    machine_axis: Optional[str] = None,
    travel_mm: Optional[Tuple[float, float]] = None,
    comp_add_velo_factor: Optional[float] = None,
    out: Optional[PathLike] = None,
) -> dict[str, Any]:
    """The work-offset update (or Siemens SD43900 data) for the thermal drift now."""

def machine_build(
    output: PathLike,
    *,
    geometric: Optional[PathLike] = None,
    thermal: Sequence[str] = ...,
    data: Optional[PathLike] = None,
    guard: Sequence[str] = ...,
    fade_c: Optional[float] = None,
    fade_other: Optional[float] = None,
) -> dict[str, Any]:
    """A machine error model file (`mtec.machine-error/1`) of geometric and thermal models."""

def machine_replay(
    model: PathLike, state: PathLike, probes: PathLike, *, output: Optional[PathLike] = None
) -> dict[str, Any]:
    """A recorded day compensated through the real-time code path, before and after."""

def sensitivity(
    *,
    function: Optional[Literal["ishigami", "sobol-g", "linear"]] = None,
    machine: Optional[PathLike] = None,
    stats: Optional[PathLike] = None,
    method: Literal["efast", "sobol", "morris"] = "efast",
    samples: Optional[int] = None,
    at: Optional[Sequence[float]] = None,
    points: Optional[PathLike] = None,
    interference: int = 4,
    resamples: int = 10,
    levels: int = 4,
    num_resamples: int = 100,
    conf_level: float = 0.95,
    seed: int = 1,
    target_um: float = 25.0,
    coverage: float = 2.0,
    lhs_poses: Optional[int] = None,
) -> dict[str, Any]:
    """Sensitivity indices with their confidence intervals (`mtec sensitivity --json`)."""

def simulate(scenario: str, out: PathLike, seed: int = 1) -> dict[str, str]:
    """Writes a scenario's simulated measurement files and truth.json into `out`."""

def run_project(project: PathLike, out: Optional[PathLike] = None) -> dict[str, Any]:
    """Runs a project file's whole pipeline in-process and writes report.html (`mtec run`)."""
