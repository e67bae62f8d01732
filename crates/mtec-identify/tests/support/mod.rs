//! Shared by the line-identification tests: the `vmc-9line` scenario as the tests read it.

use mtec_identify::lines::LineData;
use mtec_io::Table;
use mtec_model::{ErrorSet, Machine};
use std::path::Path;

/// The scenario's machine, its line measurements (all runs) and its truth.
#[allow(dead_code)]
pub fn vmc_9line(seed: u64) -> (Machine, LineData, ErrorSet) {
    let out = mtec_sim::run_scenario("vmc-9line", seed).unwrap();
    let csv = &out
        .files
        .iter()
        .find(|f| f.name == "lines.csv")
        .unwrap()
        .contents;
    let data = LineData::from_table(&Table::parse(Path::new("lines.csv"), csv).unwrap()).unwrap();
    let truth: ErrorSet = serde_json::from_value(out.truth["errors"].clone()).unwrap();
    let machine = Machine::vmc_xyfz(mtec_sim::vmc_9line::TOOL_LENGTH_MM);
    (machine, data, truth)
}

/// Any line scenario (e.g. `vmc-9line-realistic`): its machine (from its `machine.toml`), its
/// line measurements and its truth.
#[allow(dead_code)]
pub fn line_scenario(name: &str, seed: u64) -> (Machine, LineData, ErrorSet) {
    let out = mtec_sim::run_scenario(name, seed).unwrap();
    let file = |n: &str| &out.files.iter().find(|f| f.name == n).unwrap().contents;
    let data =
        LineData::from_table(&Table::parse(Path::new("lines.csv"), file("lines.csv")).unwrap())
            .unwrap();
    let spec: mtec_model::MachineSpec = toml::from_str(file("machine.toml")).unwrap();
    let truth: ErrorSet = serde_json::from_value(out.truth["errors"].clone()).unwrap();
    (Machine::from_spec(spec).unwrap(), data, truth)
}
