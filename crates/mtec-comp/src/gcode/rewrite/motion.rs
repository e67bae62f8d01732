//! The motion mode of a block (G0, G1, G2, G3, G80 or one the rewriter does not follow), shared
//! by the interpreter and the checks of what LinuxCNC refuses.

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
    /// G80: no motion mode; axis words alone are an error.
    Cancelled,
    /// After an unsupported motion code (canned cycle, probing, …) or poisoning.
    Unknown,
}

impl Motion {
    pub(super) fn code(self) -> &'static str {
        match self {
            Motion::Rapid => "G0",
            Motion::Linear => "G1",
            Motion::Cw => "G2",
            Motion::Ccw => "G3",
            _ => "",
        }
    }
}
