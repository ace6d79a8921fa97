//! The scenario kinds `thm run` knows, dispatched on the file's `kind` key.

pub mod dem_uniaxial_tension_bar;
pub mod lumped_cooling;
pub mod mpm_dem_biaxial;
pub mod mpm_dem_column;
pub mod mpm_dem_rod;
pub mod mpm_dem_square;
pub mod mpm_semi_infinite_bar;
pub mod pore_scale_bar;

use std::path::Path;

use super::config::ScenarioDocument;
use super::error::{ConfigError, RunError};
use super::scenario::{self, DriveOptions, Outcome, Scenario, drive};

/// The `kind` tags.
const KINDS: [&str; 8] = [
    lumped_cooling::LumpedCooling::KIND,
    mpm_dem_rod::MpmDemRod::KIND,
    mpm_dem_square::MpmDemSquare::KIND,
    mpm_semi_infinite_bar::SemiInfiniteBar::KIND,
    dem_uniaxial_tension_bar::DemTensionBar::KIND,
    pore_scale_bar::PoreScaleBar::KIND,
    mpm_dem_biaxial::MpmDemBiaxial::KIND,
    mpm_dem_column::MpmDemColumn::KIND,
];

/// The `kind` tags, for error messages.
pub fn names() -> String {
    KINDS
        .iter()
        .map(|k| format!("`{k}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether `kind` names a scenario kind.
pub fn is_known(kind: &str) -> bool {
    KINDS.contains(&kind)
}

/// Checks the document as its kind's run does before writing anything: parameters, time and
/// output sections, and building the initial state. Every document gives `Ok` or an error
/// naming the key path, never a panic.
pub fn validate(doc: &ScenarioDocument) -> Result<(), ConfigError> {
    match doc.common.kind.as_str() {
        lumped_cooling::LumpedCooling::KIND => {
            scenario::validate::<lumped_cooling::LumpedCooling>(doc)
        }
        mpm_semi_infinite_bar::SemiInfiniteBar::KIND => {
            scenario::validate::<mpm_semi_infinite_bar::SemiInfiniteBar>(doc)
        }
        mpm_dem_rod::MpmDemRod::KIND => scenario::validate::<mpm_dem_rod::MpmDemRod>(doc),
        mpm_dem_square::MpmDemSquare::KIND => {
            scenario::validate::<mpm_dem_square::MpmDemSquare>(doc)
        }
        mpm_dem_biaxial::MpmDemBiaxial::KIND => {
            scenario::validate::<mpm_dem_biaxial::MpmDemBiaxial>(doc)
        }
        mpm_dem_column::MpmDemColumn::KIND => {
            scenario::validate::<mpm_dem_column::MpmDemColumn>(doc)
        }
        dem_uniaxial_tension_bar::DemTensionBar::KIND => {
            scenario::validate::<dem_uniaxial_tension_bar::DemTensionBar>(doc)
        }
        pore_scale_bar::PoreScaleBar::KIND => {
            scenario::validate::<pore_scale_bar::PoreScaleBar>(doc)
        }
        other => Err(ConfigError::new(
            "kind",
            format!("unknown scenario kind `{other}`; one of {}", names()),
        )),
    }
}

/// Runs the document with the driver of its kind.
pub fn dispatch(
    doc: ScenarioDocument,
    file: &Path,
    opts: &DriveOptions<'_>,
) -> Result<Outcome, RunError> {
    match doc.common.kind.as_str() {
        lumped_cooling::LumpedCooling::KIND => {
            drive::<lumped_cooling::LumpedCooling>(doc, file, opts)
        }
        mpm_semi_infinite_bar::SemiInfiniteBar::KIND => {
            drive::<mpm_semi_infinite_bar::SemiInfiniteBar>(doc, file, opts)
        }
        mpm_dem_rod::MpmDemRod::KIND => drive::<mpm_dem_rod::MpmDemRod>(doc, file, opts),
        mpm_dem_square::MpmDemSquare::KIND => {
            drive::<mpm_dem_square::MpmDemSquare>(doc, file, opts)
        }
        mpm_dem_biaxial::MpmDemBiaxial::KIND => {
            drive::<mpm_dem_biaxial::MpmDemBiaxial>(doc, file, opts)
        }
        mpm_dem_column::MpmDemColumn::KIND => {
            drive::<mpm_dem_column::MpmDemColumn>(doc, file, opts)
        }
        dem_uniaxial_tension_bar::DemTensionBar::KIND => {
            drive::<dem_uniaxial_tension_bar::DemTensionBar>(doc, file, opts)
        }
        pore_scale_bar::PoreScaleBar::KIND => {
            drive::<pore_scale_bar::PoreScaleBar>(doc, file, opts)
        }
        other => Err(RunError::Config {
            path: file.to_path_buf(),
            error: ConfigError::new(
                "kind",
                format!("unknown scenario kind `{other}`; one of {}", names()),
            ),
        }),
    }
}
