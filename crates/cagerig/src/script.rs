//! Edit scripts: a JSON list of user events replayed on a [`RigSession`] (one step = one event).
//!
//! ```json
//! {"skinning":"lbs","steps":[
//!   {"op":"rotate_joint","joint":"lowerarm01.R","axis":[1,0,0],"degrees":60},
//!   {"op":"move_rest_cage","vertices":[0,2,4,5,6],"offset":[2,-1,1.5]},
//!   {"op":"move_posed_cage","vertices":[20,23,25],"offset":[-1.5,2,0.5]},
//!   {"op":"set_skinning","method":"dqs"}]}
//! ```
//! `joint` is a name or an index. The whole script is parsed and checked against the rig before
//! any step runs, so a bad step is reported (with its number) before anything happens.

use glam::DVec3;
use serde::Deserialize;
use thiserror::Error;

use crate::error::{RigError, first_bad_component, is_input_value};
use crate::session::RigSession;
use crate::skinning::SkinningMethod;

/// A joint given by name or by index.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(try_from = "serde_json::Value")]
pub enum JointRef {
    /// The joint index in S.
    Index(usize),
    /// The joint name.
    Name(String),
}

impl TryFrom<serde_json::Value> for JointRef {
    type Error = String;

    fn try_from(value: serde_json::Value) -> Result<Self, String> {
        match &value {
            serde_json::Value::String(name) => Ok(JointRef::Name(name.clone())),
            serde_json::Value::Number(n) => match n.as_u64() {
                Some(j) => Ok(JointRef::Index(j as usize)),
                None => Err(format!(
                    "\"joint\": expected a joint name or a non-negative integer index, found {n}"
                )),
            },
            other => Err(format!(
                "\"joint\": expected a joint name or a non-negative integer index, found {other}"
            )),
        }
    }
}

/// One user event.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum EditStep {
    /// Rotate a joint about a world axis through its current position (S' edit).
    RotateJoint {
        /// The joint to rotate.
        joint: JointRef,
        /// Rotation axis in world space (any non-zero length).
        axis: [f64; 3],
        /// Rotation angle in degrees, right-handed about `axis`.
        degrees: f64,
    },
    /// Translate rest-cage vertices (C edit).
    MoveRestCage {
        /// Rest-cage vertex indices (into `#C`), each listed once.
        vertices: Vec<usize>,
        /// Translation applied to every listed vertex (world space).
        offset: [f64; 3],
    },
    /// Translate current-cage vertices (C' edit).
    MovePosedCage {
        /// Current-cage vertex indices (into `#C`), each listed once.
        vertices: Vec<usize>,
        /// Translation applied to every listed vertex (world space).
        offset: [f64; 3],
    },
    /// Switch the skinning method.
    SetSkinning {
        /// The skinning method to switch to.
        method: SkinningMethod,
    },
    /// Back to the rest pose.
    ResetPose {},
}

impl std::fmt::Display for JointRef {
    /// As written in a script: an index, or a quoted name.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            JointRef::Index(j) => write!(f, "{j}"),
            JointRef::Name(name) => write!(f, "{}", serde_json::Value::String(name.clone())),
        }
    }
}

impl EditStep {
    /// A short description for captions and logs: `rotate joint 3 by 60° about [1, 0, 0]`,
    /// `move 5 rest-cage vertices by [0.2, -0.1, 0.15]`, `skinning DQS`.
    pub fn summary(&self) -> String {
        let vector = |v: &[f64; 3]| crate::error::vector_text(DVec3::from_array(*v));
        let count = |n: usize| {
            if n == 1 {
                "1 vertex".to_string()
            } else {
                format!("{n} vertices")
            }
        };
        match self {
            EditStep::RotateJoint {
                joint,
                axis,
                degrees,
            } => format!(
                "rotate joint {joint} by {}\u{b0} about {}",
                crate::error::number_text(*degrees),
                vector(axis)
            ),
            EditStep::MoveRestCage { vertices, offset } => format!(
                "move {} of the rest cage by {}",
                count(vertices.len()),
                vector(offset)
            ),
            EditStep::MovePosedCage { vertices, offset } => format!(
                "grab {} of the current cage by {}",
                count(vertices.len()),
                vector(offset)
            ),
            EditStep::SetSkinning { method } => format!("skinning {}", method.label()),
            EditStep::ResetPose {} => "reset the pose".into(),
        }
    }
}

impl std::fmt::Display for EditStep {
    /// The step in the script's own terms (its JSON object), for logs:
    /// `{"op":"rotate_joint","joint":3,"axis":[0,0,1],"degrees":-10}`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let vector = |v: &[f64; 3]| format!("[{},{},{}]", v[0], v[1], v[2]);
        let list = |v: &[usize]| {
            let items: Vec<String> = v.iter().map(usize::to_string).collect();
            format!("[{}]", items.join(","))
        };
        match self {
            EditStep::RotateJoint {
                joint,
                axis,
                degrees,
            } => write!(
                f,
                r#"{{"op":"rotate_joint","joint":{joint},"axis":{},"degrees":{degrees}}}"#,
                vector(axis)
            ),
            EditStep::MoveRestCage { vertices, offset } => write!(
                f,
                r#"{{"op":"move_rest_cage","vertices":{},"offset":{}}}"#,
                list(vertices),
                vector(offset)
            ),
            EditStep::MovePosedCage { vertices, offset } => write!(
                f,
                r#"{{"op":"move_posed_cage","vertices":{},"offset":{}}}"#,
                list(vertices),
                vector(offset)
            ),
            EditStep::SetSkinning { method } => {
                write!(f, r#"{{"op":"set_skinning","method":"{method}"}}"#)
            }
            EditStep::ResetPose {} => write!(f, r#"{{"op":"reset_pose"}}"#),
        }
    }
}

/// A parsed script.
#[derive(Debug, Clone, PartialEq)]
pub struct EditScript {
    /// Skinning method to start with (the rig's default when absent).
    pub skinning: Option<SkinningMethod>,
    /// The steps, in the order they run.
    pub steps: Vec<EditStep>,
}

/// Problems with a script; step numbers are 1-based like the output files.
#[derive(Debug, Error)]
pub enum ScriptError {
    /// The text is not valid JSON (the parser's message).
    #[error("the script is not valid JSON: {0}")]
    Json(String),
    /// The JSON is not an object with a "steps" array (the detail in parentheses, or empty).
    #[error("the script must be an object with a \"steps\" array{0}")]
    Shape(String),
    /// A step is malformed or does not fit the rig.
    #[error("step {step}: {message}")]
    Step {
        /// The 1-based step number.
        step: usize,
        /// What is wrong with the step.
        message: String,
    },
    /// The session refused a step.
    #[error("step {step}: {source}")]
    Rig {
        /// The 1-based step number.
        step: usize,
        /// The session's error.
        #[source]
        source: RigError,
    },
}

impl EditScript {
    /// Parses a script, naming the first bad step.
    pub fn parse(text: &str) -> Result<Self, ScriptError> {
        // A UTF-8 byte-order mark (some Windows editors write one) is not part of the JSON.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| ScriptError::Json(e.to_string()))?;
        let obj = value
            .as_object()
            .ok_or_else(|| ScriptError::Shape(String::new()))?;
        if let Some(key) = obj.keys().find(|k| *k != "skinning" && *k != "steps") {
            return Err(ScriptError::Shape(format!(" (unknown key {key:?})")));
        }
        let skinning = match obj.get("skinning") {
            None => None,
            Some(v) => Some(
                SkinningMethod::deserialize(v)
                    .map_err(|e| ScriptError::Shape(format!(" (\"skinning\": {e})")))?,
            ),
        };
        let steps = obj
            .get("steps")
            .and_then(|s| s.as_array())
            .ok_or_else(|| ScriptError::Shape(String::new()))?
            .iter()
            .enumerate()
            .map(|(i, v)| {
                EditStep::deserialize(v).map_err(|e| ScriptError::Step {
                    step: i + 1,
                    message: crate::error::plain_serde_message(&e.to_string()),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { skinning, steps })
    }

    /// Checks every step against the rig (joint names/indices, cage indices, finite numbers).
    pub fn validate(&self, session: &RigSession) -> Result<(), ScriptError> {
        for (i, step) in self.steps.iter().enumerate() {
            let step_no = i + 1;
            let fail = |message: String| ScriptError::Step {
                step: step_no,
                message,
            };
            match step {
                EditStep::RotateJoint {
                    joint,
                    axis,
                    degrees,
                } => {
                    resolve_joint(session, joint).map_err(fail)?;
                    let axis = DVec3::from_array(*axis);
                    if first_bad_component(axis).is_some() || axis.length_squared() == 0.0 {
                        return Err(fail(format!(
                            "\"axis\": expected a non-zero direction of finite numbers of \
                             magnitude at most 1e12, found {}",
                            crate::error::vector_text(axis)
                        )));
                    }
                    if !is_input_value(*degrees) {
                        return Err(fail(format!(
                            "\"degrees\": expected a finite angle of magnitude at most 1e12, \
                             found {}",
                            crate::error::number_text(*degrees)
                        )));
                    }
                }
                EditStep::MoveRestCage { vertices, offset }
                | EditStep::MovePosedCage { vertices, offset } => {
                    let n = session.rest_cage().len();
                    if vertices.is_empty() {
                        return Err(fail("no cage vertices given".into()));
                    }
                    if let Some(v) = vertices.iter().find(|&&v| v >= n) {
                        return Err(fail(format!(
                            "\"vertices\": cage vertex {v} is out of range (the cage has {n} \
                             vertices, 0 to {})",
                            n - 1
                        )));
                    }
                    let mut sorted = vertices.clone();
                    sorted.sort_unstable();
                    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
                        let times = vertices.iter().filter(|&&v| v == w[0]).count();
                        return Err(fail(format!(
                            "\"vertices\": cage vertex {} is listed {times} times; list each \
                             vertex once (the offset moves every listed vertex once)",
                            w[0]
                        )));
                    }
                    let offset = DVec3::from_array(*offset);
                    if first_bad_component(offset).is_some() {
                        return Err(fail(format!(
                            "\"offset\": expected finite numbers of magnitude at most 1e12, \
                             found {}",
                            crate::error::vector_text(offset)
                        )));
                    }
                }
                EditStep::SetSkinning { .. } | EditStep::ResetPose {} => {}
            }
        }
        Ok(())
    }

    /// Runs step `index` (0-based) on the session.
    pub fn run_step(&self, index: usize, session: &mut RigSession) -> Result<(), ScriptError> {
        let step_no = index + 1;
        let rig = |source| ScriptError::Rig {
            step: step_no,
            source,
        };
        match &self.steps[index] {
            EditStep::RotateJoint {
                joint,
                axis,
                degrees,
            } => {
                let j = resolve_joint(session, joint).map_err(|message| ScriptError::Step {
                    step: step_no,
                    message,
                })?;
                session
                    .rotate_joint(j, DVec3::from_array(*axis), degrees.to_radians())
                    .map_err(rig)
            }
            EditStep::MoveRestCage { vertices, offset } => session
                .move_rest_cage(vertices, &[DVec3::from_array(*offset)])
                .map_err(rig),
            EditStep::MovePosedCage { vertices, offset } => session
                .move_posed_cage(vertices, &[DVec3::from_array(*offset)])
                .map_err(rig),
            EditStep::SetSkinning { method } => session.set_skinning(*method).map_err(rig),
            EditStep::ResetPose {} => {
                session.reset_pose();
                Ok(())
            }
        }
    }
}

/// Index of a joint given by name or index.
pub fn resolve_joint(session: &RigSession, joint: &JointRef) -> Result<usize, String> {
    let n = session.skeleton().len();
    match joint {
        JointRef::Index(j) if *j < n => Ok(*j),
        JointRef::Index(j) => Err(format!(
            "joint {j} is out of range (the rig has {n} joints)"
        )),
        JointRef::Name(name) => session.skeleton().find(name).ok_or_else(|| {
            let names: Vec<&str> = session
                .skeleton()
                .joints()
                .iter()
                .take(12)
                .map(|j| j.name.as_str())
                .collect();
            format!(
                "unknown joint {name:?}: expected one of the rig's {n} joint names ({}{}) or an \
                 index 0 to {}",
                names.join(", "),
                if n > names.len() { ", …" } else { "" },
                n.saturating_sub(1)
            )
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_example_and_names_bad_steps() {
        let s = EditScript::parse(
            r#"{"skinning":"lbs","steps":[
            {"op":"rotate_joint","joint":"lowerarm01.R","axis":[1,0,0],"degrees":60},
            {"op":"move_rest_cage","vertices":[0,2,4,5,6],"offset":[2,-1,1.5]},
            {"op":"move_posed_cage","vertices":[20,23,25],"offset":[-1.5,2,0.5]},
            {"op":"set_skinning","method":"dqs"},
            {"op":"rotate_joint","joint":3,"axis":[0,0,1],"degrees":-10}]}"#,
        )
        .unwrap();
        assert_eq!(s.steps.len(), 5);
        assert_eq!(s.skinning, Some(SkinningMethod::Lbs));
        assert_eq!(
            s.steps[4],
            EditStep::RotateJoint {
                joint: JointRef::Index(3),
                axis: [0.0, 0.0, 1.0],
                degrees: -10.0
            }
        );
        // A byte-order mark is accepted; Rust type names never reach the user.
        let with_bom = format!("\u{feff}{}", r#"{"steps":[{"op":"reset_pose"}]}"#);
        assert_eq!(EditScript::parse(&with_bom).unwrap().steps.len(), 1);
        let err = EditScript::parse(
            r#"{"steps":[{"op":"move_rest_cage","vertices":[1.5],"offset":[0,0,0]}]}"#,
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("an index (a whole number ≥ 0)") && !err.contains("usize"),
            "{err}"
        );
        // Steps print in the script's own terms, and parse back to themselves.
        for step in &s.steps {
            let text = format!(r#"{{"steps":[{step}]}}"#);
            assert_eq!(&EditScript::parse(&text).unwrap().steps[0], step, "{text}");
        }
        assert_eq!(
            s.steps[4].summary(),
            "rotate joint 3 by -10\u{b0} about [0, 0, 1]"
        );
        assert_eq!(
            s.steps[4].to_string(),
            r#"{"op":"rotate_joint","joint":3,"axis":[0,0,1],"degrees":-10}"#
        );
        let err =
            EditScript::parse(r#"{"steps":[{"op":"reset_pose"},{"op":"explode","vertices":[1]}]}"#)
                .unwrap_err();
        assert!(matches!(err, ScriptError::Step { step: 2, .. }), "{err}");
        assert!(err.to_string().contains("explode"));
        assert!(matches!(
            EditScript::parse("[1,2]"),
            Err(ScriptError::Shape(_))
        ));
        assert!(matches!(
            EditScript::parse(r#"{"steps":[{"op":"move_rest_cage","vertices":[1]}]}"#),
            Err(ScriptError::Step { step: 1, .. })
        ));
        // No serde internals in the message.
        let err = EditScript::parse(
            r#"{"steps":[{"op":"rotate_joint","joint":[1],"axis":[1,0,0],"degrees":1}]}"#,
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("joint name or a non-negative integer") && !err.contains("untagged"),
            "{err}"
        );
    }
}
