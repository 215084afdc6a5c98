//! Session options from Python keyword strings (the CLI's option values, same meaning).

use cagerig::cage_coords::CoordsPrecision;
use cagerig::session::{CageFitSource, FitRowsKind, SessionOptions};
use cagerig::skinning::SkinningMethod;
use cagerig::sync::skeleton_updater::LocalisationKind;
use cagerig::{CageFitKind, CoordsKind, NamedKind};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The kind named `value` for the keyword `what`, read by the kind's `FromStr` (the one parser of
/// its names, shared with the CLI); the error names the keyword, the value and the names.
pub fn named<K: NamedKind>(what: &str, value: &str) -> PyResult<K>
where
    K::Err: std::fmt::Display,
{
    value
        .parse::<K>()
        .map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}

/// A method name (`"lbs" | "dqs" | "cor" | "blended"`, any case), read by `SkinningMethod: FromStr`.
pub fn skinning_method(value: &str) -> PyResult<SkinningMethod> {
    named("skinning", value)
}

/// `"ghost" | "displayed"`.
pub fn fit_source(value: &str) -> PyResult<CageFitSource> {
    named("fit_source", value)
}

/// Options of `Rig.load` / `Rig.builtin` / `Rig.from_arrays`.
pub fn session_options(
    skinning: &str,
    fit_rows: &str,
    localisation: &str,
    fit_source_name: &str,
    coords_precision: &str,
    coords: &str,
    cage_fit: &str,
) -> PyResult<SessionOptions> {
    Ok(SessionOptions {
        cage_fit: named::<CageFitKind>("cage_fit", cage_fit)?,
        coords: named::<CoordsKind>("coords", coords)?,
        skinning: skinning_method(skinning)?,
        fit_rows: named::<FitRowsKind>("fit_rows", fit_rows)?.into(),
        localisation: named::<LocalisationKind>("localisation", localisation)?.localisation(),
        fit_source: fit_source(fit_source_name)?,
        cage_coords_precision: named::<CoordsPrecision>("coords_precision", coords_precision)?,
        ..SessionOptions::default()
    })
}
