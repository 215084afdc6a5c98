//! Session options from Python keyword strings (the CLI's option values, same meaning).

use cagerig::cage_coords::CoordsPrecision;
use cagerig::session::{CageFitSource, FitRows, SessionOptions};
use cagerig::skinning::SkinningMethod;
use cagerig::sync::skeleton_updater::JointLocalisation;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

fn unknown(what: &str, value: &str, allowed: &str) -> PyErr {
    PyValueError::new_err(format!("{what} must be {allowed}, got {value:?}"))
}

/// A method name (`"lbs" | "dqs" | "cor" | "blended"`, any case), read by `SkinningMethod: FromStr`.
pub fn skinning_method(value: &str) -> PyResult<SkinningMethod> {
    value.parse().map_err(|_| {
        let names: Vec<String> = SkinningMethod::ALL
            .iter()
            .map(|m| format!("'{}'", m.name()))
            .collect();
        let allowed = match names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => names.concat(),
        };
        unknown("skinning", value, &allowed)
    })
}

/// `"ghost" | "displayed"`.
pub fn fit_source(value: &str) -> PyResult<CageFitSource> {
    match value {
        "ghost" => Ok(CageFitSource::GhostLbs),
        "displayed" => Ok(CageFitSource::DisplayedMesh),
        _ => Err(unknown("fit_source", value, "'ghost' or 'displayed'")),
    }
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
        cage_fit: cage_fit
            .parse::<cagerig::CageFitKind>()
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("cage_fit: {e}")))?,
        coords: coords
            .parse::<cagerig::CoordsKind>()
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("coords: {e}")))?,
        skinning: skinning_method(skinning)?,
        fit_rows: match fit_rows {
            "maxvol" => FitRows::MaxVol,
            "all" => FitRows::AllRows,
            _ => return Err(unknown("fit_rows", fit_rows, "'maxvol' or 'all'")),
        },
        localisation: match localisation {
            "articulation" => JointLocalisation::default(),
            "reference_tool" | "reference-tool" => JointLocalisation::reference_tool(),
            _ => {
                return Err(unknown(
                    "localisation",
                    localisation,
                    "'articulation' or 'reference_tool'",
                ));
            }
        },
        fit_source: fit_source(fit_source_name)?,
        cage_coords_precision: match coords_precision {
            "f64" => CoordsPrecision::F64,
            "f32" => CoordsPrecision::F32,
            _ => {
                return Err(unknown(
                    "coords_precision",
                    coords_precision,
                    "'f64' or 'f32'",
                ));
            }
        },
        ..SessionOptions::default()
    })
}
