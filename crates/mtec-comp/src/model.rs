//! The one interface every compensable error model offers.

use crate::chain::{ChainKinematics, Pose, PoseError};
use crate::map::GridMap;

/// What an update of the machine state did to the model (see [`ErrorModel::update_state`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateStatus {
    /// Weight of the state-dependent (thermal) part now: 1 inside the training envelope, fading
    /// linearly to 0 outside it (`crate::machine`).
    pub thermal_weight: f64,
    /// Index (in [`ErrorModel::state_inputs`]) of the input furthest outside the training
    /// envelope, if any input is outside it.
    pub outside: Option<usize>,
}

impl Default for StateStatus {
    fn default() -> Self {
        StateStatus {
            thermal_weight: 1.0,
            outside: None,
        }
    }
}

/// Why a state update was refused (the state is then unchanged).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StateError {
    /// `given` readings for a model that takes `expected`.
    Count { given: usize, expected: usize },
    /// Reading `index` is NaN or infinite.
    NotFinite { index: usize },
    /// The time step is negative or not finite.
    TimeStep,
}

impl std::fmt::Display for StateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StateError::Count { given, expected } => {
                write!(f, "{given} readings given, the model takes {expected}")
            }
            StateError::NotFinite { index } => write!(f, "reading {index} is not finite"),
            StateError::TimeStep => write!(f, "the time step must be finite and ≥ 0"),
        }
    }
}

impl std::error::Error for StateError {}

/// A model of the volumetric error of the tool tip relative to the workpiece, as a function of
/// the commanded position of every axis and of the machine's state. Grids, identified kinematic
/// error models (with or without rotary axes), fitted models (BPNN) and the stateful machine
/// model implement it; compensation only ever sees this trait.
///
/// Two views of the same error: [`ErrorModel::pose_error`] takes every axis (a fixed-size
/// [`Pose`]: X, Y, Z in mm and A, B, C in degrees) and gives the tool-tip error, and the
/// orientation error where the model knows it, in the workpiece frame; [`ErrorModel::error_um`]
/// is its special case with the rotary axes at 0°, the whole story for a machine without
/// rotary axes (where the workpiece frame is the machine frame). A model whose
/// [`ErrorModel::kinematics`] has rotary axes must implement `pose_error`; the others get it
/// from `error_um`.
pub trait ErrorModel: Send + Sync {
    /// Volumetric error [Ex, Ey, Ez] in µm at the commanded position `p_mm` [x, y, z] in mm
    /// (any rotary axes at 0°).
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3];
    /// [`ErrorModel::error_um`] at many points in one call: `out[i]` is the error at
    /// `points[i]`, equal to `error_um(points[i])` (a model may reorder its arithmetic only
    /// within 1e-12 relative; the grid map's batch is bit-identical). The batch form is for
    /// callers with many points at hand (`mtec map eval`, the Python module): a model can read
    /// its constants once per call and keep its loop free of dispatch. The default is the loop.
    ///
    /// Panics when `out` and `points` differ in length. Must not allocate.
    fn eval_batch(&self, points: &[[f64; 3]], out: &mut [[f64; 3]]) {
        assert_eq!(
            points.len(),
            out.len(),
            "eval_batch: as many outputs as points"
        );
        for (o, p) in out.iter_mut().zip(points) {
            *o = self.error_um(*p);
        }
    }
    /// The error at a pose of every axis, in the workpiece frame (see [`crate::pose`]). Must
    /// not allocate.
    fn pose_error(&self, pose: &Pose) -> PoseError {
        PoseError {
            position_um: self.error_um(pose.linear_mm),
            orientation_urad: None,
        }
    }
    /// The ideal kinematic chain the model is defined on, when it is a chain with rotary axes
    /// (or any chain a kinematic model describes). `None`: a three-axis machine whose
    /// workpiece frame is its machine frame; rotary axis words are then refused.
    fn kinematics(&self) -> Option<&ChainKinematics> {
        None
    }
    /// One line saying what the model is and where it came from (written into outputs as provenance).
    fn describe(&self) -> String;
    /// The model as a trilinear grid map, when it is one: G-code rewriting then bounds the
    /// path error exactly from the grid's cells instead of sampling (see `gcode::bound`).
    fn as_grid(&self) -> Option<&GridMap> {
        None
    }
    /// The box of machine positions [[x_min, x_max], [y_min, y_max], [z_min, z_max]] (mm) the
    /// model describes: a grid map's grid box, a kinematic model's axis travels. Outside it a
    /// value is clamped, extrapolated or a fit beyond its data, so users are told when a
    /// program goes there. `None`: no such box is known.
    fn domain_mm(&self) -> Option<[[f64; 2]; 3]> {
        None
    }
    /// The machine-state inputs the model reads, in the order [`ErrorModel::update_state`] takes
    /// them (temperature columns such as `t3_c`, `spindle_rpm`, `ambient_c`); empty for a static
    /// model.
    fn state_inputs(&self) -> &[String] {
        &[]
    }
    /// Advances the model's state by `dt_s` seconds with new readings of
    /// [`ErrorModel::state_inputs`]; [`ErrorModel::error_um`] then gives the error in the new
    /// state. Must not allocate. A static model takes no readings.
    fn update_state(&mut self, readings: &[f64], dt_s: f64) -> Result<StateStatus, StateError> {
        if !readings.is_empty() {
            return Err(StateError::Count {
                given: readings.len(),
                expected: 0,
            });
        }
        if !(dt_s >= 0.0 && dt_s.is_finite()) {
            return Err(StateError::TimeStep);
        }
        Ok(StateStatus::default())
    }
}

/// [`ErrorModel::eval_batch`] on `threads` threads: the points are cut into `threads` equal
/// contiguous runs (whole blocks of 1024, so every run but the last is the same size) and each
/// run is one `eval_batch` call on its own scoped thread; the caller's thread takes the first.
/// `out[i]` is exactly what one `eval_batch` call gives (each point is evaluated on its own),
/// so the thread count never changes a result. `threads` ≤ 1, or fewer than 2 × 1024 points:
/// one call on the caller's thread. Unlike `eval_batch` this spawns threads (their stacks are
/// allocated), so it is for large batches (issue 22: 1 M points), not a real-time loop.
///
/// Panics when `out` and `points` differ in length.
pub fn eval_batch_threads(
    model: &dyn ErrorModel,
    points: &[[f64; 3]],
    out: &mut [[f64; 3]],
    threads: usize,
) {
    assert_eq!(
        points.len(),
        out.len(),
        "eval_batch: as many outputs as points"
    );
    const RUN_QUANTUM: usize = 1024;
    let threads = threads.min(points.len() / RUN_QUANTUM).max(1);
    if threads == 1 {
        model.eval_batch(points, out);
        return;
    }
    let run = points.len().div_ceil(threads).div_ceil(RUN_QUANTUM) * RUN_QUANTUM;
    std::thread::scope(|s| {
        let mut runs = points.chunks(run).zip(out.chunks_mut(run));
        let first = runs.next();
        for (p, o) in runs {
            s.spawn(move || model.eval_batch(p, o));
        }
        if let Some((p, o)) = first {
            model.eval_batch(p, o);
        }
    });
}

/// The grid map is the one model the trait has a concrete view of (`as_grid`, for the exact
/// path bounds of the G-code rewriter), so its implementation lives beside the trait and
/// `map` stays plain data and interpolation.
impl ErrorModel for GridMap {
    /// The interpolated error; NaN outside the grid when the policy is `refuse`.
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        self.try_error_um(p_mm).unwrap_or([f64::NAN; 3])
    }

    fn eval_batch(&self, points: &[[f64; 3]], out: &mut [[f64; 3]]) {
        GridMap::eval_batch(self, points, out)
    }

    fn as_grid(&self) -> Option<&GridMap> {
        Some(self)
    }

    fn domain_mm(&self) -> Option<[[f64; 2]; 3]> {
        let r = |a: usize| {
            [
                self.axes_mm()[a][0],
                self.axes_mm()[a][self.axes_mm()[a].len() - 1],
            ]
        };
        Some([r(0), r(1), r(2)])
    }

    fn describe(&self) -> String {
        let r = |a: usize| {
            let ax = &self.axes_mm()[a];
            format!("{}..{} mm ({})", ax[0], ax[ax.len() - 1], ax.len())
        };
        format!(
            "trilinear grid map (mtec.map/1): x {}, y {}, z {}, outside = {}, from {}",
            r(0),
            r(1),
            r(2),
            self.outside().name(),
            if self.source().is_empty() {
                "unknown source"
            } else {
                self.source()
            }
        )
    }
}
