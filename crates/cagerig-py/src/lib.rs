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
    // `--skinning`, `--coords`, `--cage-fit` and `--unfitted-cage` values): front ends such as
    // the Blender add-on build their choices from these instead of repeating them.
    m.add(
        "SKINNING_METHODS",
        cagerig::skinning::SkinningMethod::ALL
            .map(|k| k.name())
            .to_vec(),
    )?;
    m.add(
        "COORDS_KINDS",
        cagerig::CoordsKind::ALL.map(|k| k.name()).to_vec(),
    )?;
    m.add(
        "CAGE_FITS",
        cagerig::CageFitKind::ALL.map(|k| k.name()).to_vec(),
    )?;
    m.add(
        "UNFITTED_CAGE_POLICIES",
        cagerig::session::UnfittedCagePolicy::ALL
            .map(|k| k.name())
            .to_vec(),
    )?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
