//! `cagerig` for Python: the coupled cage + skeleton rig and its kernels over numpy arrays.
//! The Python package (python/cagerig) re-exports this module (`cagerig._cagerig`).

use pyo3::prelude::*;

mod auto_weights;
mod convert;
mod errors;
mod functions;
mod green;
mod interchange;
mod options;
mod output_folder;
mod rig;
mod rig_output;
mod rig_sequences;
mod rig_structures;
mod rig_timing;
mod script;
mod tracks;

#[pymodule]
fn _cagerig(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("RigError", py.get_type::<errors::RigError>())?;
    m.add("RigFileError", py.get_type::<errors::RigFileError>())?;
    m.add("ScriptError", py.get_type::<errors::ScriptError>())?;
    m.add("RigWarning", py.get_type::<errors::RigWarning>())?;
    m.add_class::<rig::Rig>()?;
    m.add_class::<script::EditScriptPy>()?;
    m.add_class::<output_folder::OutputFolder>()?;
    m.add_function(wrap_pyfunction!(functions::mvc, m)?)?;
    m.add_function(wrap_pyfunction!(green::green_coordinates, m)?)?;
    m.add_function(wrap_pyfunction!(auto_weights::skin_weights, m)?)?;
    m.add_function(wrap_pyfunction!(functions::maxvol_rows, m)?)?;
    m.add_function(wrap_pyfunction!(functions::max_entropy_coordinates, m)?)?;
    m.add_function(wrap_pyfunction!(functions::lbs, m)?)?;
    m.add_function(wrap_pyfunction!(functions::dqs, m)?)?;
    m.add_function(wrap_pyfunction!(functions::cor, m)?)?;
    m.add_function(wrap_pyfunction!(functions::cor_centres, m)?)?;
    m.add_function(wrap_pyfunction!(functions::validate_cage, m)?)?;
    m.add_function(wrap_pyfunction!(functions::subdivide, m)?)?;
    m.add_function(wrap_pyfunction!(functions::read_obj, m)?)?;
    m.add_function(wrap_pyfunction!(functions::write_obj, m)?)?;
    m.add_function(wrap_pyfunction!(interchange::generate_cage, m)?)?;
    // The accepted names of each rig option, in the order front ends list them (the CLI's
    // values of the same options): front ends such as the Blender add-on build their choices
    // from these instead of repeating them, and the stubs' literals are checked against them.
    m.add(
        "SKINNING_METHODS",
        names::<cagerig::skinning::SkinningMethod>(),
    )?;
    m.add("COORDS_KINDS", names::<cagerig::CoordsKind>())?;
    m.add("CAGE_FITS", names::<cagerig::CageFitKind>())?;
    m.add("CAGE_LAYOUTS", names::<cagerig::cage_gen::CageLayout>())?;
    m.add(
        "UNFITTED_CAGE_POLICIES",
        names::<cagerig::session::UnfittedCagePolicy>(),
    )?;
    m.add("FIT_ROWS", names::<cagerig::session::FitRowsKind>())?;
    m.add(
        "LOCALISATIONS",
        names::<cagerig::sync::skeleton_updater::LocalisationKind>(),
    )?;
    m.add("FIT_SOURCES", names::<cagerig::session::CageFitSource>())?;
    m.add(
        "COORDS_PRECISIONS",
        names::<cagerig::cage_coords::CoordsPrecision>(),
    )?;
    m.add(
        "GREEN_FACE_TERMS",
        names::<cagerig::coords::stretched_normals::FaceTermKind>(),
    )?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

/// The names of the kind `K`, in `K::ALL`'s order.
fn names<K: cagerig::NamedKind>() -> Vec<&'static str> {
    K::ALL.iter().map(|k| k.name()).collect()
}
