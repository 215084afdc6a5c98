//! `cagerig.EditScript`: the `cagerig edit` JSON scripts (crates/cagerig/src/script.rs), parsed
//! once, checked against a rig, run step by step or whole.

use cagerig::skinning::SkinningMethod;
use std::path::PathBuf;

use cagerig::script::EditScript;
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::errors::{rig_error, script_error};
use crate::rig::Rig;

/// An edit script in the ``cagerig edit`` format::
///
///     {"skinning": "lbs", "steps": [
///       {"op": "rotate_joint", "joint": "lowerarm01.R", "axis": [1, 0, 0], "degrees": 60},
///       {"op": "move_rest_cage", "vertices": [0, 2, 4, 5, 6], "offset": [2, -1, 1.5]},
///       {"op": "move_posed_cage", "vertices": [20, 23, 25], "offset": [-1.5, 2, 0.5]},
///       {"op": "set_skinning", "method": "dqs"},
///       {"op": "reset_pose"}]}
///
/// Parameters
/// ----------
/// script : str, dict or os.PathLike
///     JSON text (a str starting with ``{``), the parsed JSON (dict), or a file to read.
///
/// Raises
/// ------
/// ScriptError
///     Naming the first bad step (1-based, like the CLI's output files).
#[pyclass(module = "cagerig", name = "EditScript", frozen)]
pub struct EditScriptPy {
    script: EditScript,
    text: String,
}

impl EditScriptPy {
    /// A script from an `EditScript` object or anything its constructor takes.
    pub fn from_any<'py>(obj: &Bound<'py, PyAny>) -> PyResult<PyRef<'py, Self>> {
        if let Ok(s) = obj.cast::<Self>() {
            return Ok(s.borrow());
        }
        let parsed = Bound::new(obj.py(), Self::new(obj)?)?;
        Ok(parsed.borrow())
    }

    /// Checks the script against the rig, sets its skinning (if any) and runs every step.
    pub fn run_all(&self, py: Python<'_>, rig: &mut Rig) -> PyResult<()> {
        self.script.validate(rig.session()).map_err(script_error)?;
        let script = &self.script;
        let session = rig.session_mut();
        py.detach(|| {
            if let Some(method) = script.skinning {
                session.set_skinning(method).map_err(Err)?;
            }
            for k in 0..script.steps.len() {
                script.run_step(k, session).map_err(Ok)?;
            }
            Ok(())
        })
        .map_err(
            |e: Result<cagerig::script::ScriptError, cagerig::RigError>| match e {
                Ok(e) => script_error(e),
                Err(e) => rig_error(e),
            },
        )
    }
}

#[pymethods]
impl EditScriptPy {
    #[new]
    fn new(script: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = script.py();
        let text = if script.is_instance_of::<PyString>() {
            let s: String = script.extract()?;
            if s.trim_start().starts_with('{') {
                s
            } else {
                read_script(PathBuf::from(s))?
            }
        } else if script.is_instance_of::<PyDict>() || script.is_instance_of::<PyList>() {
            py.import("json")?
                .call_method1("dumps", (script,))?
                .extract::<String>()?
        } else {
            let path: PathBuf = script.extract().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(
                    "script must be JSON text (str), a dict or a path",
                )
            })?;
            read_script(path)?
        };
        let parsed = EditScript::parse(&text).map_err(script_error)?;
        Ok(Self {
            script: parsed,
            text,
        })
    }

    /// Number of steps.
    fn __len__(&self) -> usize {
        self.script.steps.len()
    }

    /// The script's starting skinning method, or None.
    #[getter]
    fn skinning(&self) -> Option<&'static str> {
        self.script.skinning.map(SkinningMethod::name)
    }

    /// The steps as parsed JSON objects (a new list of dicts).
    #[getter]
    fn steps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?
            .call_method1("loads", (self.text.as_str(),))?
            .get_item("steps")
    }

    /// The script's JSON text.
    #[getter]
    fn text(&self) -> &str {
        &self.text
    }

    /// Checks every step against the rig (joint names and indices, cage vertex indices,
    /// finite numbers) without running anything.
    fn validate(&self, rig: PyRef<'_, Rig>) -> PyResult<()> {
        self.script.validate(rig.session()).map_err(script_error)
    }

    /// Runs step ``index`` (0-based) on the rig. Does not apply the script's ``skinning``.
    fn run_step(&self, py: Python<'_>, mut rig: PyRefMut<'_, Rig>, index: usize) -> PyResult<()> {
        let n = self.script.steps.len();
        if index >= n {
            return Err(PyIndexError::new_err(format!(
                "step index {index} is out of range (the script has {n} steps)"
            )));
        }
        let script = &self.script;
        let session = rig.session_mut();
        py.detach(|| script.run_step(index, session))
            .map_err(script_error)
    }

    /// Checks the script against the rig, sets its skinning (if any), then runs every step.
    fn run(&self, py: Python<'_>, mut rig: PyRefMut<'_, Rig>) -> PyResult<()> {
        self.run_all(py, &mut rig)
    }

    fn __repr__(&self) -> String {
        format!("EditScript({} steps)", self.script.steps.len())
    }
}

fn read_script(path: PathBuf) -> PyResult<String> {
    std::fs::read_to_string(&path).map_err(|e| {
        crate::errors::file_error(cagerig::io::ParseError::Io {
            path: path.clone(),
            kind: e.kind(),
            message: e.to_string(),
        })
    })
}
