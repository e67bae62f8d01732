//! `mtec compensate thermal-offset`: the work-offset update (or Siemens temperature-compensation
//! setting data) for the thermal state now; the job is `ops::compensate_thermal_offset` of
//! mtec-workflow (the method `mtec_comp::thermal_offset`). This parses and prints.

use crate::{choice::choice, error::CliError, help::examples};
use mtec_comp::table::DEFAULT_MAX_CORRECTION_UM;
use mtec_comp::thermal_offset::OutsidePolicy;
use mtec_workflow::ops::compensate_table::parse_axis;
use mtec_workflow::ops::compensate_thermal_offset::{self as op, parse_travel, Options};
use std::path::PathBuf;

/// `mtec compensate thermal-offset`.
#[derive(clap::Args)]
#[command(after_long_help = examples!("compensate_thermal_offset.examples"))]
pub struct Args {
    /// A machine error model (mtec.machine-error/1: thermal parts with axis, sign, envelope) or
    /// a thermal model (mtec.thermal-model/1, with --training).
    #[arg(long)]
    model: PathBuf,
    /// The temperature log up to now (CSV: time_min and the model's inputs); the last row is now.
    #[arg(long)]
    temps: PathBuf,
    /// Output format.
    #[arg(long, value_parser = choice::<op::Format>(), default_value = "g10")]
    format: op::Format,
    /// The axis whose offset is updated: X, Y or Z.
    #[arg(long, default_value = "Z")]
    axis: String,
    /// Work offset: g10 P0-P9 (1 = G54), fanuc 1-6 (G54-G59), sinumerik frame 0-99 (1 = G54).
    #[arg(long, default_value_t = 1)]
    offset: u32,
    /// g10/fanuc: the offset's value (mm) with no drift, or when it was set (--zeroed-at-min).
    #[arg(long, allow_hyphen_values = true)]
    base_mm: Option<f64>,
    /// Machine position (mm) the offset is used at; needed when the drift depends on position.
    #[arg(long, allow_hyphen_values = true)]
    at_mm: Option<f64>,
    /// Machine position (mm) of the model's position_mm = 0 (sinumerik-sd: SD43920).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    position_origin_mm: f64,
    /// Log time (min) at which the offset was last set; the update is relative to that moment.
    #[arg(long, allow_hyphen_values = true)]
    zeroed_at_min: Option<f64>,
    /// The log's first row is the machine at rest, in equilibrium with the room.
    #[arg(long)]
    starts_at_rest: bool,
    /// Outside the training envelope: refuse, or fade the update to none (the safe fallback).
    #[arg(long, value_parser = choice::<OutsidePolicy>(), default_value = "refuse")]
    outside: OutsidePolicy,
    /// Refuse an update larger than this (um).
    #[arg(long, default_value_t = DEFAULT_MAX_CORRECTION_UM)]
    max_correction_um: f64,
    /// Bare thermal model: its training log (the envelope is the range of every input in it).
    #[arg(long)]
    training: Option<PathBuf>,
    /// Bare thermal model: 1 if its target is the tool's displacement along +axis, -1 if opposite.
    #[arg(long, allow_hyphen_values = true)]
    sign: Option<f64>,
    /// fanuc-macro: the control's axis number (default X1, Y2, Z3).
    #[arg(long)]
    axis_number: Option<u32>,
    /// sinumerik-sd: the machine axis name (default AX1, AX2, AX3 for X, Y, Z).
    #[arg(long)]
    machine_axis: Option<String>,
    /// sinumerik-sd: the axis travel FROM:TO (mm), over which the compensation is bounded.
    #[arg(long, allow_hyphen_values = true)]
    travel_mm: Option<String>,
    /// sinumerik-sd: MD32760 $MA_COMP_ADD_VELO_FACTOR, the largest |tan(beta)|.
    #[arg(long, default_value_t = 0.01)]
    comp_add_velo_factor: f64,
    /// Output file (default and `-`: stdout), replaced atomically.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<(), CliError> {
    // The job's options; a malformed axis or travel is a usage error.
    let opts = Options {
        axis: parse_axis("--axis", &a.axis)?,
        travel_mm: a.travel_mm.as_deref().map(parse_travel).transpose()?,
        model: a.model,
        temps: a.temps,
        format: a.format,
        offset: a.offset,
        base_mm: a.base_mm,
        at_mm: a.at_mm,
        position_origin_mm: a.position_origin_mm,
        zeroed_at_min: a.zeroed_at_min,
        starts_at_rest: a.starts_at_rest,
        outside: a.outside,
        max_correction_um: a.max_correction_um,
        training: a.training,
        sign: a.sign,
        axis_number: a.axis_number,
        machine_axis: a.machine_axis,
        comp_add_velo_factor: a.comp_add_velo_factor,
        out: a.out,
    };
    let done = op::run(&opts, &mut crate::observer::Stderr::default())?;
    eprint!("{done}");
    for n in &done.notes {
        eprintln!("note: {n}");
    }
    Ok(())
}
