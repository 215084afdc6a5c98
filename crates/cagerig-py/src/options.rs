//! Session options from Python keyword strings (the CLI's option values, same meaning).

use cagerig::cage_coords::CoordsPrecision;
use cagerig::coords::stretched_normals::FaceTermKind;
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

/// The option names of `Rig.load` / `Rig.builtin` / `Rig.from_arrays`, as given.
pub struct OptionNames<'a> {
    pub skinning: &'a str,
    pub fit_rows: &'a str,
    pub localisation: &'a str,
    pub fit_source: &'a str,
    pub coords_precision: &'a str,
    pub coords: &'a str,
    pub cage_fit: &'a str,
    pub green_face_term: &'a str,
}

/// The session options these names give (each read by its kind's `FromStr`).
pub fn session_options(names: &OptionNames<'_>) -> PyResult<SessionOptions> {
    Ok(SessionOptions {
        cage_fit: named::<CageFitKind>("cage_fit", names.cage_fit)?,
        coords: named::<CoordsKind>("coords", names.coords)?,
        skinning: skinning_method(names.skinning)?,
        fit_rows: named::<FitRowsKind>("fit_rows", names.fit_rows)?.into(),
        localisation: named::<LocalisationKind>("localisation", names.localisation)?.localisation(),
        fit_source: fit_source(names.fit_source)?,
        cage_coords_precision: named::<CoordsPrecision>(
            "coords_precision",
            names.coords_precision,
        )?,
        green_face_term: named::<FaceTermKind>("green_face_term", names.green_face_term)?,
        ..SessionOptions::default()
    })
}
