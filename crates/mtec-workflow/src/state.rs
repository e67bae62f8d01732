//! `--state LOG.csv` of the offline compensation outputs (`compensate gcode`, `compensate
//! table`): a model with a state is brought to the state of the log before it is used, and a
//! stateful model without a log is refused (its thermal part would silently be left out).

use crate::{Error as CliError, Observer};
use mtec_comp::{advance_through_log, ErrorModel, WithState};
use mtec_io::Table;
use std::path::Path;

/// The model to compensate with: a static model as it is (refusing a `--state` it cannot use),
/// a stateful one advanced through `state` (refused without one). The returned model's
/// provenance names the log and the state.
pub fn model_in_state(
    mut model: Box<dyn ErrorModel>,
    model_path: &Path,
    state: Option<&Path>,
    obs: &mut dyn Observer,
) -> Result<Box<dyn ErrorModel>, CliError> {
    let inputs = model.state_inputs().to_vec();
    match (inputs.is_empty(), state) {
        (true, None) => Ok(model),
        (true, Some(_)) => Err(CliError::usage(format!(
            "--state: {} is a static model (no temperatures or other state inputs); leave --state out",
            model_path.display()
        ))),
        (false, None) => Err(CliError::usage(format!(
            "{} has a state (inputs: {}): its thermal part depends on the machine's readings now, \
             and without them it would be left out silently. Give --state LOG.csv with time_min \
             and these columns, one row per reading in time order: every row advances the state, \
             the state after the last row is compensated for",
            model_path.display(),
            inputs.join(", ")
        ))),
        (false, Some(log)) => {
            let table = Table::read(log)?;
            let status = advance_through_log(model.as_mut(), &table)?;
            let line = status.describe(&log.display().to_string());
            if status.last.thermal_weight < 1.0 {
                obs.warning(&format!(
                    "at the last reading of {} the thermal part is faded to {:.3} (`{}` outside the training envelope)",
                    log.display(),
                    status.last.thermal_weight,
                    status.outside.as_deref().unwrap_or("?")
                ));
            }
            obs.progress(&line);
            Ok(Box::new(WithState::new(model, &line)))
        }
    }
}
